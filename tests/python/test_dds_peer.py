"""A real third-party DDS peer (Eclipse Cyclone DDS, C library via its Python binding) and the
Rust suite, in separate processes on loopback:

- cyclonedds subscribes to ``rt/rig/sample`` published by the Rust test_pattern node and decodes
  every field of every RigSample;
- cyclonedds publishes ``ProcedureCommand``s on ``rt/rig/procedure/command`` that the Rust
  recorder node receives (and records: we read them back from its MCAP).
"""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from conftest import stop, taken, wait_for
from pattern import expected, plain, stamp_sec
from tyre_msgs_idl import types

COUNT = 60
RELIABLE = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll,
               Policy.Durability.Volatile)


def pattern_launch(domain_id: int, rate_hz: float, count: int) -> str:
    """A launch file's runtime and a test_pattern node publishing RigSamples. It publishes only
    once a subscriber is discovered: the topic is volatile, so a sample sent before the match is
    gone (a fixed 2 s wait lost them once on a loaded CI machine)."""
    return f"""
[runtime]
namespace = "/rig"
domain_id = {domain_id}

[[node]]
name = "pattern"
kind = "test_pattern"
[node.config]
rate_hz = {rate_hz}
count = {count}
wait_for_subscribers = 1
discovery_wait_s = 1.0
topics = ["sample"]
"""


def test_cyclonedds_reads_rig_samples_and_sends_commands(tyrerig, domain_id, tmp_path: Path):
    RigSample = types["RigSample"]
    ProcedureCommand = types["ProcedureCommand"]
    Header = types["std_msgs/msg/Header"]
    Time = types["builtin_interfaces/msg/Time"]

    dp = DomainParticipant(domain_id)
    reader = DataReader(dp, Topic(dp, "rt/rig/sample", RigSample), qos=RELIABLE)
    writer = DataWriter(dp, Topic(dp, "rt/rig/procedure/command", ProcedureCommand), qos=RELIABLE)

    launch = tmp_path / "peer.toml"
    launch.write_text(pattern_launch(domain_id, 30.0, COUNT) + """
[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "peer.mcap"
topics = ["procedure/command"]
""")
    proc = subprocess.Popen([str(tyrerig), "launch", str(launch), "--processes"], cwd=tmp_path)
    try:
        # Rust → cyclonedds: every sample, every field.
        got = {}

        def collect():
            for s in taken(reader, 100):
                got[stamp_sec(s)] = s
            return len(got) >= COUNT

        try:
            wait_for(collect, 30.0, f"{COUNT} RigSamples from the Rust test_pattern node")
        except AssertionError as e:
            raise AssertionError(f"{e}; got {len(got)}: {sorted(got)[:5]}…") from None
        for n in range(COUNT):
            assert got[n] == expected("tyre_msgs/msg/RigSample", n), f"RigSample {n}"
        assert got[7].fx_n == 7 + 5 / 8 and got[7].header.frame_id == "7:2:ü"

        # cyclonedds → Rust: commands once the recorder's reader has matched our writer.
        wait_for(lambda: writer.get_matched_subscriptions(), 20.0, "the Rust recorder to match our writer")
        sent = []
        for i, cmd in enumerate([ProcedureCommand.START, ProcedureCommand.PAUSE, ProcedureCommand.RESUME,
                                 ProcedureCommand.ABORT, ProcedureCommand.ESTOP]):
            msg = ProcedureCommand(header=Header(stamp=Time(sec=100 + i, nanosec=5), frame_id="control_room"),
                                   command=cmd, procedure="gs2mf", operator_name=f"cyclonedds peer {i} ✓")
            writer.write(msg)
            sent.append(msg)
        time.sleep(1.5)
    finally:
        assert stop(proc) == 0

    with open(tmp_path / "peer.mcap", "rb") as f:
        log = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        received = [m for _, _, _, m in log.iter_decoded_messages(topics=["/rig/procedure/command"])]
    assert [plain(m) for m in received] == [plain(m) for m in sent]


def test_the_test_pattern_waits_for_a_late_subscriber(tyrerig, domain_id, tmp_path: Path):
    """With `wait_for_subscribers`, a pattern started before its only subscriber holds its first
    sample until the subscriber is there: on a volatile topic, nothing sent earlier would arrive."""
    RigSample = types["RigSample"]
    launch = tmp_path / "late.toml"
    launch.write_text(pattern_launch(domain_id, 20.0, 10))
    proc = subprocess.Popen([str(tyrerig), "node", "pattern", "--config", str(launch)], cwd=tmp_path)
    try:
        # Longer than the pattern would take to send everything if it did not wait.
        time.sleep(3.0)
        assert proc.poll() is None, "the pattern ended before anybody subscribed"
        dp = DomainParticipant(domain_id)
        reader = DataReader(dp, Topic(dp, "rt/rig/sample", RigSample), qos=RELIABLE)
        got = set()

        def collect():
            got.update(stamp_sec(s) for s in taken(reader, 100))
            return len(got) >= 10

        wait_for(collect, 30.0, "10 RigSamples sent after our reader joined")
        assert sorted(got) == list(range(10)), "the first sample waited for the subscriber"
        assert proc.wait(timeout=30) == 0
    finally:
        stop(proc)
