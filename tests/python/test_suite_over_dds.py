"""The main job over DDS, watched by a third-party control room.

`tyrerig run --procedure staticlong` runs the whole suite over DDS (virtual rig in lockstep,
thermal gate, sequencer, quality node = live channels + monitor, recorder). While it runs, a
Cyclone DDS participant (another vendor's DDS, as a control room's tools would be) follows
``procedure/state`` and ``quality/report``. Afterwards the MCAP log is read with the independent
Python readers and compared with a headless run of the same procedure and seed: the quality
node must have turned every rig sample into live channels and produced the same sweep summaries
as the in-process pipeline.
"""

from __future__ import annotations

import json
import subprocess
from collections import Counter
from pathlib import Path

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from conftest import REPO, taken, wait_for
from tyre_msgs_idl import types

PHASE_COMPLETE = 8


def topic_counts(path: Path) -> Counter:
    """Messages per topic, every one decoded (CRCs checked)."""
    counts: Counter = Counter()
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        for _, channel, _, _ in reader.iter_decoded_messages():
            counts[channel.topic] += 1
    return counts


def test_staticlong_over_dds_with_a_cyclonedds_control_room(tyrerig, domain_id, tmp_path: Path):
    launch_config = str(REPO / "launch-config")
    common = ["--procedure", "staticlong", "--seed", "3", "--quiet", "--launch-config", launch_config]

    headless = subprocess.run(
        [str(tyrerig), "run", "--headless", *common, "--out", "headless.mcap", "--summary-json", "headless.json"],
        cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert headless.returncode == 0, headless.stderr

    ProcedureState = types["ProcedureState"]
    QualityReport = types["QualityReport"]
    dp = DomainParticipant(domain_id)
    qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll,
              Policy.Durability.Volatile)
    states_reader = DataReader(dp, Topic(dp, "rt/rig/procedure/state", ProcedureState), qos=qos)
    reports_reader = DataReader(dp, Topic(dp, "rt/rig/quality/report", QualityReport), qos=qos)

    proc = subprocess.Popen(
        [str(tyrerig), "run", *common, "--out", "dds.mcap", "--summary-json", "dds.json"],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    states, reports = [], []

    def watch():
        states.extend(taken(states_reader, 1000))
        reports.extend(taken(reports_reader, 100))
        return any(s.phase == PHASE_COMPLETE for s in states)

    try:
        wait_for(watch, 280.0, "procedure/state to say the procedure completed", interval=0.2)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err

    # The control room saw the procedure run from start to end, every sweep of it.
    n_sweeps = json.loads((tmp_path / "headless.json").read_text())["sweeps"]
    assert min(s.progress for s in states) < 0.05 and states[-1].progress > 0.99
    assert {s.sweep_index for s in states if s.phase == 1} == set(range(n_sweeps))
    assert all(s.sweep_count == n_sweeps for s in states if s.phase == 1)
    assert reports, "no quality/report reached the control room"

    dds = json.loads((tmp_path / "dds.json").read_text())
    live = json.loads((tmp_path / "headless.json").read_text())
    assert dds["completed"] and live["completed"]
    assert dds["sweeps"] == live["sweeps"]
    assert abs(dds["total_rig_time_s"] - live["total_rig_time_s"]) < 5.0

    got = topic_counts(tmp_path / "dds.mcap")
    want = topic_counts(tmp_path / "headless.mcap")
    print("DDS log:", dict(got), "\nheadless log:", dict(want))
    assert got["/rig/channels/live"] == got["/rig/sample"] > 0
    assert got["/rig/channels/sweep_summary"] == want["/rig/channels/sweep_summary"] > 0
    assert got["/rig/channels/derived"] == want["/rig/channels/derived"] > 0
    assert got["/rig/quality/report"] >= 1
    assert got["/rig/procedure/state"] > 0 and got["/rig/thermal/state"] > 0
