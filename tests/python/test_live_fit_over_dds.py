"""The live fit over DDS (`tyrerig run --fit`): the fit node, as its own participant, reads the
rig's samples and the procedure state, publishes `model/state` after every completed segment and
at the end, and writes the `.tir` and the fit report; the recorder logs every model state. The
log is read back with the independent Python readers (`mcap`, `mcap-ros2-support`).

A short free-rolling procedure (four step steers, one force & moment sweep: ~35 s of rig time)
keeps it to seconds; the headless test `nodes/livefit/tests/virtual_rig.rs` checks the fit's
accuracy and calibration on a full FreeRolling run.
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.reader import read_ros2_messages

SHORT_PROCEDURE = """
[procedure]
name = "dds_fit_short"
title = "Short free-rolling run for the DDS live-fit test"
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
pressure = "mid"
[[section.step]]
kind = "sweep"
peak_deg = 16.0
low_rate_dps = 2.0
high_rate_dps = 30.0
threshold_deg = 4.0
asym = "medium"
"""

WAITING, FITTING, IDENTIFIED = 0, 1, 2


def test_the_fit_node_publishes_a_model_after_every_segment_and_writes_it_at_the_end(tyrerig, domain_id, tmp_path):
    procedure = tmp_path / "short.toml"
    procedure.write_text(SHORT_PROCEDURE)
    log, report = tmp_path / "run.mcap", tmp_path / "fit_report"
    done = subprocess.run(
        [str(tyrerig), "run", "--procedure", str(procedure), "--fit", "--quiet", "--out", str(log),
         "--fit-report", str(report)],
        cwd=Path(__file__).resolve().parents[2], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]

    with open(log, "rb") as f:
        summary = make_reader(f).get_summary()
    channel = next(c for c in summary.channels.values() if c.topic == "/rig/model/state")
    schema = summary.schemas[channel.schema_id]
    assert (schema.name, schema.encoding, channel.message_encoding) == ("tyre_msgs/msg/ModelState", "ros2msg", "cdr")

    states = [m.ros_msg for m in read_ros2_messages(str(log), topics=["/rig/model/state"])]
    # With every model state, the same update's whole model and covariance (docs/live-fit.md).
    covariances = [m.ros_msg for m in read_ros2_messages(str(log), topics=["/rig/model/covariance"])]
    assert [c.update_index for c in covariances] == [s.update_index for s in states]
    assert [c.has_model for c in covariances] == [s.error == "" for s in states], \
        [(c.has_model, s.error) for c, s in zip(covariances, states)]
    # One update per completed segment (4 step steers, 1 sweep), then the final one.
    assert [s.update_index for s in states] == list(range(1, len(states) + 1)), [s.update_index for s in states]
    assert len(states) >= 6, len(states)
    assert [s.final_update for s in states] == [False] * (len(states) - 1) + [True]
    names = {s.stage for s in states[-1].stages}
    assert {"fy_pure", "mz_pure", "fx_pure", "mx", "radius_stiffness", "relaxation"} <= names, names

    # Step steers alone: no force & moment data yet, every point stage waits and says why.
    first = states[0]
    assert "force & moment" in first.error, first.error
    assert all(s.status == WAITING for s in first.stages if s.stage != "relaxation"), \
        [(s.stage, s.status) for s in first.stages]

    # After the sweep: the lateral stages are fitted, with coefficients, σ and maps.
    after = next(s for s in states if s.last_sweep.startswith("force_moment/"))
    assert after.error == "", after.error
    fy = next(s for s in after.stages if s.stage == "fy_pure")
    assert fy.status in (FITTING, IDENTIFIED), (fy.status, fy.status_reason)
    assert 0.0 < fy.nrmse_pct < 5.0, fy.nrmse_pct
    assert fy.coefficients and any(math.isfinite(c.std) and c.std > 0 for c in fy.coefficients)
    grid = (len(after.grid_fz_n) * len(after.grid_slip_angle_deg) * len(after.grid_camber_deg)
            * len(after.grid_pressure_pa))
    maps = {m.channel: m for m in after.maps}
    assert set(maps) == {"FYW", "FX", "MZW"}, set(maps)
    assert all(len(m.value) == grid and len(m.std) == grid for m in maps.values()), grid
    # Each map's grid points outside the tested envelope are flagged (read by the schema, not by us).
    assert len(after.maps_extrapolated) == grid * len(after.maps), (len(after.maps_extrapolated), grid)
    # And the band for a repeat measurement, one per map: finite for the fitted FYW.
    assert len(after.maps_repeat_band) == len(after.maps), after.maps_repeat_band
    fyw_band = after.maps_repeat_band[[m.channel for m in after.maps].index("FYW")]
    assert math.isfinite(fyw_band) and fyw_band > 0, after.maps_repeat_band
    assert any(math.isfinite(x) and x > 0 for x in maps["FYW"].std), "FYW has no finite uncertainty"

    # The model the node wrote at the end: an MF 6.1 property file and its fit report.
    tir = log.with_suffix(".tir").read_text()
    assert "FITTYP" in tir and "PDY1" in tir, tir[:500]
    assert (report / "fit.json").exists(), sorted(p.name for p in report.iterdir())

    # The monitor follows the model: the quality node puts its view of every update on
    # /diagnostics, and the run report gets a live-model section and plot.
    watched = [st for m in read_ros2_messages(str(log), topics=["/diagnostics"])
               for st in m.ros_msg.status if st.name == "tyrerig monitor: live_model"]
    assert len(watched) >= len(states) - 1, (len(watched), len(states))
    last = {kv.key: kv.value for kv in watched[-1].values}
    # As above: the final update may land after the monitor's last report at shutdown.
    assert last["updates"] in (str(len(states)), str(len(states) - 1)), (last, len(states))
    assert last["identified"].endswith(f"/{len(states[-1].stages)}"), last
    assert "fy_pure" in last and watched[-1].message.startswith("live model:"), watched[-1].message
    out = tmp_path / "run_report"
    done = subprocess.run([str(tyrerig), "report", str(log), "--out", str(out)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    md = (out / "report.md").read_text()
    # The first updates wait for force & moment data: that is no failure.
    failed = sum(1 for s in states if s.error and not s.error.startswith("no usable data"))
    assert failed == 0, [s.error for s in states]
    assert "## Live model" in md and f"{len(states)} updates (0 failed;" in md, md[:2000]
    assert "| fy_pure | FY |" in md, md
    assert (out / "live_model.png").exists(), sorted(p.name for p in out.iterdir())
