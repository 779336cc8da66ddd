"""A hostile peer on the network: Cyclone DDS publishes malformed CDR on the suite's own topic
names and type names while the whole suite runs (one OS process per node).

The peer uses the suite's DDS type names (``tyre_msgs::msg::dds_::RigSample_`` …) with a layout
of its own choosing (one ``sequence<octet>``), so it controls every byte after the first four:
payloads cut short, string lengths of 2 GB, sequence counts of 4 billion, random bytes, an empty
body; and, with the real types, RigSamples and setpoints that are NaN in every field. Every node
must count what it refused, say so on ``/diagnostics`` and in its log, and keep running; the
recorder's ``tyrerig.loss`` record must hold the counts.
"""

from __future__ import annotations

import math
import random
import re
import signal
import struct
import subprocess
import time
import types as pytypes
from dataclasses import dataclass
from pathlib import Path

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as idl
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from conftest import REPO, stop, wait_for
from tyre_msgs_idl import types

# Topic → (DDS type name, the suite's nodes that read it).
TARGETS = {
    "rt/rig/sample": ("tyre_msgs::msg::dds_::RigSample_", ["thermal", "sequencer", "quality", "recorder"]),
    "rt/rig/setpoint": ("tyre_msgs::msg::dds_::RigSetpoint_", ["virtual_rig", "recorder"]),
    "rt/rig/thermal/state": ("tyre_msgs::msg::dds_::ThermalState_", ["sequencer", "recorder"]),
    "rt/rig/procedure/command": ("tyre_msgs::msg::dds_::ProcedureCommand_", ["sequencer", "recorder"]),
    "rt/rig/procedure/state": ("tyre_msgs::msg::dds_::ProcedureState_", ["thermal", "quality", "recorder"]),
    "rt/diagnostics": ("diagnostic_msgs::msg::dds_::DiagnosticArray_", ["recorder"]),
}
TRANSIENT_LOCAL = {"rt/rig/procedure/state"}


def blob_type(dds_name: str) -> type:
    """A type named like the suite's whose wire layout is a length-prefixed byte string."""

    def body(ns):
        ns["__annotations__"].update({"data": idl.sequence[idl.uint8]})
        ns["__module__"] = __name__

    return dataclass(pytypes.new_class("Blob", (IdlStruct,), {"typename": dds_name}, body))


def valid_body(msg) -> bytes:
    """The CDR body of a real message without its encapsulation header."""
    return bytes(msg.serialize()[4:])


def hostile_payloads(real: bytes, rng: random.Random) -> list[tuple[str, bytes]]:
    """Blob contents. The blob's own 4-byte length prefix takes the place of header.stamp.sec,
    so each payload starts at stamp.nanosec."""
    rest = real[4:]
    wrong_len = bytearray(rest)
    wrong_len[4:8] = struct.pack("<I", 0x7FFF_FFF0)  # header.frame_id length: 2 GB
    huge_seq = struct.pack("<II", 0, 1) + b"\0\0\0\0" + struct.pack("<I", 0xFFFF_FFFF)
    return [
        ("truncated", rest[: len(rest) // 3]),
        ("wrong string length", bytes(wrong_len)),
        ("huge sequence count", huge_seq + b"\1\2\3"),
        ("random bytes", bytes(rng.randrange(256) for _ in range(rng.randrange(1, 200)))),
        ("empty", b""),
    ]


def test_every_node_survives_and_counts_malformed_input(tyrerig, domain_id, tmp_path: Path):
    launch = tmp_path / "hostile.toml"
    config = REPO / "launch-config"
    launch.write_text(f"""
[runtime]
domain_id = {domain_id}

[[node]]
name = "recorder"
kind = "recorder"
[node.config]
output = "hostile.mcap"

[[node]]
name = "virtual_rig"
kind = "virtual_rig"
[node.config]
rig_config = "{config / 'virtual_rig.toml'}"
clock = "realtime"
time_scale = 5.0
start_delay_s = 2.0

[[node]]
name = "thermal"
kind = "thermal"

[[node]]
name = "sequencer"
kind = "sequencer"
[node.config]
procedure = "{config / 'procedures' / 'gs2mf_freerolling.toml'}"
autostart = true

[[node]]
name = "quality"
kind = "quality"
""")
    dp = DomainParticipant(domain_id)
    rng = random.Random(13)
    writers, blobs = {}, {}
    for topic, (dds_name, _) in TARGETS.items():
        durability = Policy.Durability.TransientLocal if topic in TRANSIENT_LOCAL else Policy.Durability.Volatile
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(100), durability)
        blobs[topic] = blob_type(dds_name)
        writers[topic] = DataWriter(dp, Topic(dp, topic, blobs[topic]), qos=qos)
    # NaN in every field, with the real types (well-formed CDR, absurd content).
    RigSample, RigSetpoint = types["RigSample"], types["RigSetpoint"]
    nan_fields = lambda cls: {f: math.nan for f, t in cls.__annotations__.items() if t is float or t == idl.float64}
    reliable = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(100),
                   Policy.Durability.Volatile)
    nan_sample_writer = DataWriter(dp, Topic(dp, "rt/rig/sample", RigSample), qos=reliable)
    nan_setpoint_writer = DataWriter(dp, Topic(dp, "rt/rig/setpoint", RigSetpoint), qos=reliable)

    real_types = {
        "rt/rig/sample": RigSample,
        "rt/rig/setpoint": RigSetpoint,
        "rt/rig/thermal/state": types["ThermalState"],
        "rt/rig/procedure/command": types["ProcedureCommand"],
        "rt/rig/procedure/state": types["ProcedureState"],
        "rt/diagnostics": types["diagnostic_msgs/msg/DiagnosticArray"],
    }
    real = {topic: valid_body(cls(header=types["std_msgs/msg/Header"](frame_id="iso_w")))
            for topic, cls in real_types.items()}

    def malformed(topic: str, payload: bytes) -> bool:
        """Whether the real type refuses the bytes the suite will see (an independent decoder)."""
        wire = b"\x00\x01\x00\x00" + struct.pack("<I", len(payload)) + payload
        try:
            real_types[topic].deserialize(wire)
            return False
        except Exception:
            return True

    log_path = tmp_path / "suite.log"
    with open(log_path, "w") as log_file:
        proc = subprocess.Popen([str(tyrerig), "launch", str(launch), "--processes"], cwd=tmp_path,
                                stdout=log_file, stderr=subprocess.STDOUT)
        expected = {topic: 0 for topic in TARGETS}
        try:
            # Every reader of every target topic must have matched our writers.
            for topic, (_, readers) in TARGETS.items():
                wait_for(lambda w=writers[topic], n=len(readers): len(w.get_matched_subscriptions()) >= n,
                         30.0, f"{len(readers)} suite readers on {topic}")
            wait_for(lambda: len(nan_setpoint_writer.get_matched_subscriptions()) >= 2, 30.0, "setpoint readers")
            time.sleep(2.0)  # the rig runs
            for round_ in range(10):
                for topic, writer in writers.items():
                    for _, payload in hostile_payloads(real[topic], rng):
                        writer.write(blobs[topic](data=list(payload)))
                        expected[topic] += malformed(topic, payload)
                nan_sample_writer.write(RigSample(seq=10**9 + round_, **nan_fields(RigSample)))
                nan_setpoint_writer.write(RigSetpoint(seq=10**9 + round_, **nan_fields(RigSetpoint)))
                time.sleep(0.1)
            time.sleep(3.0)
            assert proc.poll() is None, f"the suite stopped under hostile input:\n{log_path.read_text()[-3000:]}"
        finally:
            code = stop(proc, signal.SIGINT, timeout=60)
    output = log_path.read_text()
    assert code == 0, f"a node failed:\n{output[-4000:]}"

    # Nodes log what they refuse (the first few per topic; the shared log of five processes is
    # only sampled here, the counts below are the check).
    assert "malformed message on /rig/sample refused" in output, output[-3000:]

    # The recorder's log: the loss record counts the malformed messages per topic, and the
    # nodes' /diagnostics announcements are in it.
    info = subprocess.run([str(tyrerig), "mcap", "info", str(tmp_path / "hostile.mcap")],
                          capture_output=True, text=True, check=True).stdout
    print(info)
    for topic in TARGETS:
        ros_topic = "/" + topic.removeprefix("rt/")
        m = re.search(rf"{re.escape(ros_topic)}: lost \d+ of \d+ in \d+ gap\(s\).*?(\d+) malformed", info)
        assert m and int(m.group(1)) == expected[topic] > 0, \
            f"{ros_topic}: expected {expected[topic]} malformed in:\n{info}"
    announcers = set()
    with open(tmp_path / "hostile.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, _, _, msg in reader.iter_decoded_messages(topics=["/diagnostics"]):
            for st in msg.status:
                if st.name.endswith(": data loss") and "malformed" in st.message:
                    announcers.add(st.name.split(":")[0])
    assert {"thermal", "sequencer", "quality", "virtual_rig", "recorder"} <= announcers, announcers
