"""The adaptive plan over DDS (`tyrerig run --plan adaptive`, not headless): the sequencer node
decides each sweep with the fit node's `model/covariance`, once that model has seen the last
sweep, and logs every decision on `/diagnostics`. The log is read back with the independent
Python readers (`mcap`, `mcap-ros2-support`) and the decisions are compared with a headless run
of the same procedure and seed, whose planner has the live fit in-process.

A short free-rolling procedure (two step steers, four candidate sweeps at two pressures: ~90 s
of rig time) keeps it to seconds; `docs/adaptive-plan.md` has the full-procedure figures.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.reader import read_ros2_messages

REPO = Path(__file__).resolve().parents[2]

SHORT_PROCEDURE = """
[procedure]
name = "dds_adaptive_short"
title = "Short free-rolling run for the DDS adaptive-plan test"
config_tag = "FreeRoll"
mode = "free_rolling"
specimen = "A"
tyre_change_s = 900.0

[[section]]
name = "step_steer"
pressure = "mid"
[[section.step]]
kind = "step_steer"
loads = [0.75, 1.0]
slip_angles_deg = [1.5, -1.5]
roll_speed_mps = 1.0
distance_m = 1.5
pre_roll_s = 2.0
steer_rate_dps = 10.0

[[section]]
name = "force_moment"
pressures = ["mid", "high"]
[[section.step]]
kind = "sweep"
peak_deg = 12.0
low_rate_dps = 2.0
high_rate_dps = 30.0
threshold_deg = 4.0
asym = "medium"
[[section.step]]
kind = "sweep"
peak_deg = 12.0
low_rate_dps = 2.0
high_rate_dps = 30.0
threshold_deg = 4.0
asym = "medium"
camber_coupling_deg = 1.8
saturation_deg = 5.0
"""


def decisions(log: Path) -> list[tuple[float, dict[str, str], str]]:
    """The adaptive plan's records on /diagnostics: (rig time, values, message)."""
    out = []
    for m in read_ros2_messages(str(log), topics=["/diagnostics"]):
        for st in m.ros_msg.status:
            if st.name == "sequencer: adaptive":
                values = {kv.key: kv.value for kv in st.values}
                out.append((float(values["rig_time_s"]), values, st.message))
    return out


def test_the_sequencer_node_plans_with_the_fit_nodes_model(tyrerig, domain_id, tmp_path):
    procedure = tmp_path / "short.toml"
    procedure.write_text(SHORT_PROCEDURE)
    common = ["run", "--procedure", str(procedure), "--plan", "adaptive", "--seed", "1", "--quiet"]
    headless_log, dds_log = tmp_path / "headless.mcap", tmp_path / "dds.mcap"
    done = subprocess.run([str(tyrerig), *common, "--headless", "--out", str(headless_log)],
                          cwd=REPO, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    done = subprocess.run([str(tyrerig), *common, "--out", str(dds_log)],
                          cwd=REPO, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]

    # The model travels as its own ROS 2 type, readable by any consumer.
    with open(dds_log, "rb") as f:
        summary = make_reader(f).get_summary()
    channel = next(c for c in summary.channels.values() if c.topic == "/rig/model/covariance")
    schema = summary.schemas[channel.schema_id]
    assert (schema.name, schema.encoding, channel.message_encoding) == \
        ("tyre_msgs/msg/ModelCovariance", "ros2msg", "cdr")
    models = [m.ros_msg for m in read_ros2_messages(str(dds_log), topics=["/rig/model/covariance"])]
    assert [m.update_index for m in models] == list(range(1, len(models) + 1))
    with_model = [m for m in models if m.has_model]
    assert with_model, "no model/covariance carried a model"
    for m in with_model:
        assert "FITTYP" in m.tir and "PDY1" in m.tir, m.tir[:300]
        assert m.r0_m > 0.2 and m.fz0_n > 1000.0, (m.r0_m, m.fz0_n)
        for s in m.stages:
            assert len(s.covariance) == len(s.keys) ** 2, (s.stage, len(s.keys), len(s.covariance))
    fy = next(s for s in with_model[-1].stages if s.stage == "fy_pure")
    assert "PDY1" in fy.keys and all(v == v for v in fy.covariance[:: len(fy.keys) + 1]), fy.keys
    reach = [m.last_sweep_index for m in models]
    assert reach == sorted(reach), reach
    # The reach is the sweep the model's newest segment came from, as procedure/state named it.
    running = [m.ros_msg for m in read_ros2_messages(str(dds_log), topics=["/rig/procedure/state"])
               if m.ros_msg.phase == 1]
    names = {st.sweep_index: f"{st.section}/{st.sweep_name}" for st in running}
    for m in models:
        assert names[m.last_sweep_index] == m.last_sweep, (m.update_index, m.last_sweep_index, m.last_sweep)

    # Every decision was made with a model that had seen every data sweep before it.
    sweeps = [(st.header.stamp.sec + st.header.stamp.nanosec * 1e-9, st.sweep_index) for st in running
              if st.section != "warmup"]
    dds = decisions(dds_log)
    assert dds, "no adaptive decision on /diagnostics"
    with_a_model = 0
    for t, values, message in dds:
        before = [i for (ts, i) in sweeps if ts < t]
        if "model_last_sweep_index" in values:
            with_a_model += 1
            assert int(values["model_last_sweep_index"]) >= max(before), (t, values, max(before))
        else:
            # Only before the first force & moment sweep is there no model to decide with.
            assert message.startswith("chose") and "no model of" in message, message
    assert with_a_model >= len(dds) - 1, dds

    # The same decisions as the headless run, whose planner has the live fit in-process.
    headless = decisions(headless_log)
    chosen = lambda ds: [v.get("sweep", "closed") for _, v, _ in ds]  # noqa: E731
    assert chosen(dds) == chosen(headless), (chosen(dds), chosen(headless))
    assert dds[-1][2].startswith("slot 0 closed"), dds[-1][2]

    # The procedure states say why each chosen sweep ran, and the model was written.
    reasons = {m.ros_msg.plan_reason for m in read_ros2_messages(str(dds_log), topics=["/rig/procedure/state"])
               if m.ros_msg.phase == 1 and m.ros_msg.section.startswith("force_moment")}
    assert reasons and all(r and r != "fixed" for r in reasons), reasons
    assert "FITTYP" in dds_log.with_suffix(".tir").read_text()
    json.dumps(chosen(dds))  # the names are plain strings

    # Each choice made with a model counts the tread it wears, on /diagnostics for any consumer.
    worn = [float(v["wear_mm"]) for _, v, m in dds if m.startswith("chose") and "model_last_sweep_index" in v]
    assert worn and all(0.0 < w < 0.2 for w in worn), worn
    # … at the wear rate it was priced at: the configured 0.208 mm/MJ until the monitor has
    # measured the tyre's (two holds of one load case, more than this short run has), the same
    # over DDS as headless.
    rates = lambda ds: [float(v["wear_rate_mm_per_mj"]) for _, v, m in ds if m.startswith("chose")]  # noqa: E731
    assert rates(dds) == rates(headless) and all(r == 0.208 for r in rates(dds)), (rates(dds), rates(headless))

    # The cool-down analysis script reads a real log and scores its three predictors.
    done = subprocess.run([sys.executable, str(REPO / "scripts/cooldown-predictors.py"), str(headless_log)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    rows = [line for line in done.stdout.splitlines() if "MAE" in line]
    assert len(rows) == 3 and all("nan" not in r for r in rows), done.stdout
