"""How well can a sweep's cool-down be predicted before it runs? Reads a run's MCAP log.

For every sweep followed by a thermal pause it takes, from the log: the sweep's slip exposure
(the sequencer's pause-model measure, from the commanded setpoints: the time integral of
(|slip angle| + 10·|slip ratio|) · Fz / 6 kN, in deg·s), the gate's filtered tread temperature at
the sweep's start and end, the pause that followed, and the gate's fitted cooling time constant.
It then scores predictors of the pause that use only what was known before the sweep:

- `pause model × observed ratio`: the sequencer's cost today, 8 s + 0.6 s per deg·s (capped at
  the 120 s time-out), times the ratio of the pauses so far to the model's estimates of them;
- `gate model, T end known`: the thermal gate's single-exponential cooling model,
  τ·ln((T_end − T_amb)/(T_base − T_amb)), with τ of the previous pause and, in its favour, the
  sweep's *measured* end temperature (a planner would have to predict it) and the best of three
  effective ambients;
- `same sweep type`: the mean pause after the sweeps of the same type so far (the name without
  its sweep number and repeat), else the first predictor.

    .venv/bin/python scripts/cooldown-predictors.py out/run.mcap

Needs the `mcap` and `mcap-ros2-support` packages (the test venv has them).
"""

import math
import re
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

PHASE_SWEEP, PHASE_PAUSE = 1, 2


def pauses(path):
    """One row per sweep that a thermal pause followed."""
    rows, phase, cur, pending = [], None, None, None
    temp_c, tau_s, base_c = math.nan, math.nan, 45.0
    last_sp, last_t = None, None
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        topics = ["/rig/procedure/state", "/rig/thermal/state", "/rig/setpoint"]
        for _, ch, _, m in reader.iter_decoded_messages(topics=topics):
            t = m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
            if ch.topic.endswith("thermal/state"):
                temp_c, tau_s, base_c = m.filtered_temp_c, m.cooling_time_constant_s, m.baseline_c
            elif ch.topic.endswith("setpoint"):
                if cur is not None and cur["phase"] == PHASE_SWEEP and last_sp is not None:
                    slip = abs(last_sp.slip_angle_deg) + 10.0 * abs(last_sp.slip_ratio)
                    cur["exposure"] += slip * last_sp.fz_n / 6000.0 * (t - last_t)
                last_sp, last_t = m, t
            elif m.phase != phase:
                if cur is not None and cur["phase"] == PHASE_SWEEP and m.phase == PHASE_PAUSE:
                    cur["end_c"] = temp_c
                    pending = cur
                if cur is not None and cur["phase"] == PHASE_PAUSE and m.phase != PHASE_PAUSE and pending:
                    pending.update(pause_s=t - cur["t0"], tau_s=tau_s, base_c=base_c)
                    rows.append(pending)
                    pending = None
                cur = {"phase": m.phase, "t0": t, "start_c": temp_c, "exposure": 0.0, "name": m.sweep_name}
                phase = m.phase
    return rows


def sweep_type(name):
    return re.sub(r"_\d+$", "", re.sub(r"_sw\d+", "", name))


def score(rows):
    model = lambda r: min(120.0, 8.0 + 0.6 * r["exposure"])  # noqa: E731 (PauseModel::default)
    errors = {"pause model × observed ratio": [], "same sweep type": []}
    gate = {amb: [] for amb in (20.0, 30.0, 40.0)}
    seen_s = model_s = 0.0
    by_type, prev_tau = {}, 40.0
    for r in rows:
        ratio = seen_s / model_s if model_s > 0 else 1.0
        scaled = model(r) * ratio
        errors["pause model × observed ratio"].append(scaled - r["pause_s"])
        past = by_type.get(sweep_type(r["name"]))
        errors["same sweep type"].append((sum(past) / len(past) if past else scaled) - r["pause_s"])
        for amb, e in gate.items():
            hot = r["end_c"] > r["base_c"] and r["base_c"] > amb
            pred = prev_tau * math.log((r["end_c"] - amb) / (r["base_c"] - amb)) if hot else 0.0
            e.append(min(pred, 120.0) - r["pause_s"])
        seen_s += r["pause_s"]
        model_s += model(r)
        by_type.setdefault(sweep_type(r["name"]), []).append(r["pause_s"])
        prev_tau = r["tau_s"] if math.isfinite(r["tau_s"]) else prev_tau
    best_amb = min(gate, key=lambda a: sum(map(abs, gate[a])))
    errors[f"gate model, T end known (ambient {best_amb:.0f} °C)"] = gate[best_amb]
    return errors


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    rows = pauses(sys.argv[1])
    if not rows:
        sys.exit(f"{sys.argv[1]}: no sweep followed by a thermal pause")
    mean = sum(r["pause_s"] for r in rows) / len(rows)
    print(f"{sys.argv[1]}: {len(rows)} pauses, mean {mean:.1f} s")
    for name, e in score(rows).items():
        mae = sum(map(abs, e)) / len(e)
        rms = math.sqrt(sum(x * x for x in e) / len(e))
        print(f"  {name:<42} MAE {mae:5.1f} s  RMS {rms:5.1f} s  bias {sum(e) / len(e):+5.1f} s")


if __name__ == "__main__":
    main()
