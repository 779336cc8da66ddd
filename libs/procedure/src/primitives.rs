//! Builders of the GS2MF primitives: each returns one or more [`Segment`]s (a named trajectory
//! with its kind and whether a thermal pause follows). Loads here are in newtons; the expansion
//! turns a file's Fz0 factors into them.

use crate::plan::StepKind;
use crate::setpoint::{RigLimits, RigMode, Setpoint};
use crate::sweep::{CamberCoupling, Keyframes, LoadCoupling, RateLaw, SlipAxis, SlipPath, SlipSweep, Trajectory};
use serde::{Deserialize, Serialize};

/// A named piece of trajectory, before the plan numbers it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// What kind of step this is.
    pub kind: StepKind,
    /// The type part of the thesis-style name, e.g. `VariableRate_LR2_HR30_TH4`.
    pub type_name: String,
    /// The setpoints.
    pub trajectory: Trajectory,
    /// Whether the sequencer waits on the thermal gate after it.
    pub thermal_pause_after: bool,
}

impl Segment {
    /// Duration \[s\].
    pub fn duration_s(&self) -> f64 {
        self.trajectory.duration_s()
    }
}

/// Format a number for a sweep name: integers without decimals, others with up to two
/// (`4` → "4", `1.8` → "1.8", `0.333` → "0.33").
pub fn fmt_num(x: f64) -> String {
    let r = (x * 100.0).round() / 100.0;
    if (r - r.round()).abs() < 1e-9 {
        format!("{}", r.round() as i64)
    } else {
        let s = format!("{r:.2}");
        s.trim_end_matches('0').to_owned()
    }
}

/// The type part of a sweep name for a rate law: rates and thresholds in °/s and ° for slip
/// angle, %/s and % for slip ratio (the thesis's convention: `LR10_HR60_TH2` for BrkDrv).
pub fn rate_type_name(axis: SlipAxis, law: &RateLaw) -> String {
    let k = match axis {
        SlipAxis::SlipAngle => 1.0,
        SlipAxis::SlipRatio => 100.0,
    };
    match *law {
        RateLaw::Constant { rate } => format!("ConstantRate_{}", fmt_num(rate * k)),
        RateLaw::Variable { low_rate, high_rate, threshold } => format!(
            "VariableRate_LR{}_HR{}_TH{}",
            fmt_num(low_rate * k),
            fmt_num(high_rate * k),
            fmt_num(threshold * k)
        ),
        RateLaw::Continuous { rate_at_zero, max_rate, knee } => format!(
            "ContinuousRate_LR{}_HR{}_KN{}",
            fmt_num(rate_at_zero * k),
            fmt_num(max_rate * k),
            fmt_num(knee * k)
        ),
    }
}

/// A slip sweep (constant, variable or continually variable rate, by `path.law`), with load and
/// camber fixed or coupled to slip angle. A thermal pause follows.
pub fn slip_sweep(
    axis: SlipAxis,
    path: SlipPath,
    base: Setpoint,
    load: LoadCoupling,
    camber: CamberCoupling,
) -> Segment {
    let type_name = rate_type_name(axis, &path.law);
    Segment {
        kind: StepKind::Sweep,
        type_name,
        trajectory: Trajectory::Sweep(SlipSweep { axis, path, base, load, camber }),
        thermal_pause_after: true,
    }
}

/// Vertical-load sweep (§3.8): steer to `slip_angle_deg` at low load, ramp the load up to
/// `high_fz_n` and back as fast as the rig allows, steer back. A thermal pause follows.
pub fn vertical_load_sweep(
    slip_angle_deg: f64,
    low_fz_n: f64,
    high_fz_n: f64,
    slip_rate_dps: f64,
    base: Setpoint,
    limits: &RigLimits,
) -> Segment {
    let mut start = base.zero_slip();
    start.fz_n = low_fz_n;
    let steer_s = slip_angle_deg.abs() / slip_rate_dps.max(1e-9);
    let load_s = (high_fz_n - low_fz_n).abs() / limits.load_rate_nps;
    let k = Keyframes::start(start)
        .then(steer_s, |s| s.slip_angle_deg = slip_angle_deg)
        .then(load_s, |s| s.fz_n = high_fz_n)
        .then(load_s, |s| s.fz_n = low_fz_n)
        .then(steer_s, |s| s.slip_angle_deg = 0.0);
    Segment {
        kind: StepKind::Sweep,
        type_name: format!("VerticalLoad_SA{}_FZ{}kN", fmt_num(slip_angle_deg), fmt_num(high_fz_n / 1000.0)),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: true,
    }
}

/// On-centre holds (§3.11): hold `slip_angle_deg` and step through `loads_n`, `hold_s` at each.
/// The settle before it brings the rig to the first load; no thermal pause (little heat).
pub fn on_centre_holds(
    slip_angle_deg: f64,
    loads_n: &[f64],
    hold_s: f64,
    base: Setpoint,
    limits: &RigLimits,
) -> Segment {
    let mut start = base.zero_slip();
    start.slip_angle_deg = slip_angle_deg;
    start.fz_n = loads_n.first().copied().unwrap_or(base.fz_n);
    let mut k = Keyframes::start(start);
    for &fz in loads_n {
        let dt = (fz - k.last().fz_n).abs() / limits.load_rate_nps;
        k = k.then(dt, |s| s.fz_n = fz).hold(hold_s);
    }
    Segment {
        kind: StepKind::Hold,
        type_name: format!("OnCentre_SA{}", fmt_num(slip_angle_deg)),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: false,
    }
}

/// Rolling-radius steps (§3.10): zero slip at `speed_mps`, step through `loads_n`, `hold_s` each.
pub fn rolling_radius_steps(
    loads_n: &[f64],
    speed_mps: f64,
    hold_s: f64,
    base: Setpoint,
    limits: &RigLimits,
) -> Segment {
    let mut start = base.zero_slip();
    start.speed_mps = speed_mps;
    start.mode = RigMode::FreeRolling;
    start.fz_n = loads_n.first().copied().unwrap_or(base.fz_n);
    let mut k = Keyframes::start(start);
    for &fz in loads_n {
        let dt = (fz - k.last().fz_n).abs() / limits.load_rate_nps;
        k = k.then(dt, |s| s.fz_n = fz).hold(hold_s);
    }
    Segment {
        kind: StepKind::Hold,
        type_name: format!("RollingRadius_V{}", fmt_num(speed_mps)),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: false,
    }
}

/// Parameters of a step-steer test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepSteerParams {
    /// Rolling speed before the stop and during the measurement \[m/s\] (thesis: 1 m/s).
    pub roll_speed_mps: f64,
    /// Rolling at zero slip before the stop \[s\].
    pub pre_roll_s: f64,
    /// Distance rolled with the slip angle held \[m\].
    pub distance_m: f64,
    /// Steering rate at standstill \[deg/s\].
    pub steer_rate_dps: f64,
}

/// Step-steer (§3.12.1): roll at zero slip, stop, steer at standstill, roll again at
/// `roll_speed_mps` holding the slip angle for `distance_m`, steer back while rolling.
pub fn step_steer(slip_angle_deg: f64, fz_n: f64, p: &StepSteerParams, base: Setpoint, limits: &RigLimits) -> Segment {
    let mut start = base.zero_slip();
    start.fz_n = fz_n;
    start.speed_mps = p.roll_speed_mps;
    start.mode = RigMode::FreeRolling;
    let v_s = p.roll_speed_mps / limits.speed_accel_mps2;
    let steer_s = slip_angle_deg.abs() / p.steer_rate_dps.max(1e-9);
    // Distance covered while accelerating counts towards the measured distance.
    let accel_dist_m = 0.5 * p.roll_speed_mps * v_s;
    let roll_s = ((p.distance_m - accel_dist_m).max(0.0)) / p.roll_speed_mps.max(1e-9);
    let k = Keyframes::start(start)
        .hold(p.pre_roll_s)
        .then(v_s, |s| s.speed_mps = 0.0)
        .mode(RigMode::Static)
        .then(steer_s, |s| s.slip_angle_deg = slip_angle_deg)
        .mode(RigMode::FreeRolling)
        .then(v_s, |s| s.speed_mps = p.roll_speed_mps)
        .hold(roll_s)
        .then(steer_s, |s| s.slip_angle_deg = 0.0);
    Segment {
        kind: StepKind::Hold,
        type_name: format!("StepSteer_SA{}", fmt_num(slip_angle_deg)),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: false,
    }
}

/// Parameters of a static longitudinal drag.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StaticDragParams {
    /// Belt displacement with the wheel locked \[m\] (thesis: ~0.1 m).
    pub displacement_m: f64,
    /// Belt speed during the drag \[m/s\].
    pub belt_speed_mps: f64,
    /// Rolling speed for the relaxing roll before the lock \[m/s\].
    pub roll_speed_mps: f64,
    /// Relaxing roll before the lock \[s\].
    pub roll_s: f64,
}

/// Static longitudinal drag (§3.12.2): roll forward (the sidewall relaxes), stop, lock the
/// wheel, move the belt `displacement_m`, release. No thermal pause: a static tyre barely heats.
pub fn static_drag(fz_n: f64, p: &StaticDragParams, base: Setpoint, limits: &RigLimits) -> Segment {
    let mut start = base.zero_slip();
    start.fz_n = fz_n;
    start.speed_mps = p.roll_speed_mps;
    start.camber_deg = 0.0;
    start.mode = RigMode::FreeRolling;
    let v_s = p.roll_speed_mps / limits.speed_accel_mps2;
    let drag_s = p.displacement_m.abs() / p.belt_speed_mps.max(1e-9);
    let k = Keyframes::start(start)
        .hold(p.roll_s)
        .then(v_s, |s| s.speed_mps = 0.0)
        .mode(RigMode::Static)
        .then(drag_s, |s| s.belt_displacement_m = p.displacement_m)
        .hold(0.5)
        .then(0.0, |s| {
            s.mode = RigMode::FreeRolling;
            s.belt_displacement_m = 0.0;
        });
    Segment {
        kind: StepKind::Hold,
        type_name: format!("StaticDrag_D{}", fmt_num(p.displacement_m)),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: false,
    }
}

/// Pressure change: zero slip, rolling, pressure ramps to `to_bar` over `duration_s`
/// (the thesis: "around 20 s").
pub fn pressure_change(from: Setpoint, to_bar: f64, duration_s: f64) -> Segment {
    let k = Keyframes::start(from.zero_slip()).then(duration_s, |s| s.pressure_bar = to_bar);
    Segment {
        kind: StepKind::PressureChange,
        type_name: format!("PressureChange_{}bar", fmt_num(to_bar)),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: false,
    }
}

/// Settle from `from` to `to`: back to zero slip at the present load case, move load, camber,
/// speed and pressure together (the slowest axis sets the time), then out to `to`'s slip, and
/// dwell. Slews at half the rig's fastest slip rates: no data are taken here.
pub fn settle(from: Setpoint, to: Setpoint, limits: &RigLimits) -> Segment {
    let sa_rate = 0.5 * limits.max_slip_angle_rate_dps;
    let sr_rate = 0.5 * limits.max_slip_ratio_rate_ps;
    let slip_time = |sp: &Setpoint| {
        (sp.slip_angle_deg.abs() / sa_rate).max(sp.slip_ratio.abs() / sr_rate)
            + 0.0_f64.max(sp.belt_displacement_m.abs() / 0.05)
    };
    let mid_from = from.zero_slip();
    let mut mid_to = to.zero_slip();
    mid_to.mode = from.mode;
    let pressure_s = if (to.pressure_bar - from.pressure_bar).abs() > 1e-6 { limits.pressure_change_s } else { 0.0 };
    let move_s = [
        (to.fz_n - from.fz_n).abs() / limits.load_rate_nps,
        (to.camber_deg - from.camber_deg).abs() / limits.camber_rate_dps,
        (to.speed_mps - from.speed_mps).abs() / limits.speed_accel_mps2,
        pressure_s,
    ]
    .into_iter()
    .fold(0.0_f64, f64::max);
    let mut k = Keyframes::start(from).to(slip_time(&from), mid_from).to(move_s, mid_to);
    let mut at_to = mid_to;
    at_to.mode = to.mode;
    k = k.to(0.0, at_to).to(slip_time(&to), to).hold(limits.settle_dwell_s);
    Segment {
        kind: StepKind::Settle,
        type_name: "Settle".into(),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: false,
    }
}

/// Free-rolling reference hold before a longitudinal sweep: the sweep's load case (slip angle
/// included) at zero slip ratio, drive torque off, so VX1 and W1 can be captured (§3.6.2).
pub fn free_rolling_ref(sweep_start: Setpoint, hold_s: f64) -> Segment {
    let mut sp = sweep_start;
    sp.slip_ratio = 0.0;
    sp.mode = RigMode::FreeRolling;
    let k = Keyframes::start(sp).hold(hold_s).mode(sweep_start.mode);
    Segment {
        kind: StepKind::FreeRollingRef,
        type_name: "FreeRollingRef".into(),
        trajectory: Trajectory::Keyframes(k),
        thermal_pause_after: false,
    }
}

/// Tyre change: the rig in its safe state for `duration_s` (the thesis: 900 s on Calspan).
pub fn tyre_change(duration_s: f64, specimen: &str) -> Segment {
    let sp = Setpoint { mode: RigMode::Safe, ..Setpoint::default() };
    Segment {
        kind: StepKind::TyreChange,
        type_name: format!("TyreChange_{specimen}"),
        trajectory: Trajectory::Keyframes(Keyframes::start(sp).hold(duration_s)),
        thermal_pause_after: false,
    }
}

/// The setpoint streamed during a thermal pause after a step ending at `end`: zero slip (no
/// friction heat), everything else as it was.
pub fn thermal_pause_setpoint(end: &Setpoint) -> Setpoint {
    let mut sp = end.zero_slip();
    if sp.mode == RigMode::Static {
        sp.mode = RigMode::FreeRolling;
    }
    sp
}

/// Parameters of the warm-up (§3.4): `blocks` blocks of `sweeps_per_block` constant-rate sweeps
/// to ±`peak_deg` at the graph-sweep load cases, `roll_s` of free rolling after each sweep, no
/// thermal pauses (the point is to heat the tyre to the 45 °C baseline).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WarmUpParams {
    /// Number of blocks (thesis: two; one reaches only 31 °C).
    pub blocks: u32,
    /// Peak slip angle \[deg\].
    pub peak_deg: f64,
    /// Slip-angle rate \[deg/s\].
    pub rate_dps: f64,
    /// Rolling at zero slip after each sweep \[s\].
    pub roll_s: f64,
}

/// Warm-up blocks: for every block, one sweep per load in `loads_n` (each followed by `roll_s`).
pub fn warm_up(p: &WarmUpParams, loads_n: &[f64], base: Setpoint) -> Vec<Segment> {
    let mut out = Vec::new();
    for _ in 0..p.blocks {
        for &fz in loads_n {
            let path = SlipPath::full_cycle(p.peak_deg, RateLaw::Constant { rate: p.rate_dps });
            let mut sweep_base = base.zero_slip();
            sweep_base.fz_n = fz;
            let sweep = SlipSweep {
                axis: SlipAxis::SlipAngle,
                path,
                base: sweep_base,
                load: LoadCoupling::Constant { fz_n: fz },
                camber: CamberCoupling::Constant { camber_deg: base.camber_deg },
            };
            // Append the roll as part of the same trajectory by sampling the sweep into frames:
            // a warm-up sweep's shape does not need the rate-law precision of a data sweep.
            let d = sweep.path.duration_s();
            let n = (d / 0.1).ceil().max(1.0) as usize;
            let mut k = Keyframes::start(sweep.at(0.0));
            for i in 1..=n {
                let t = d * i as f64 / n as f64;
                k = k.to(d / n as f64, sweep.at(t));
            }
            k = k.hold(p.roll_s);
            out.push(Segment {
                kind: StepKind::WarmUp,
                type_name: format!("WarmUp_ConstantRate_{}_SA{}", fmt_num(p.rate_dps), fmt_num(p.peak_deg)),
                trajectory: Trajectory::Keyframes(k),
                thermal_pause_after: false,
            });
        }
    }
    out
}

/// Which graph-sweep block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GraphBlock {
    /// FreeRolling: 6,000 N at 0° camber; 9,000 N; 3,000 N; 6,000 N at −3°; 6,000 N at +3°.
    FreeRolling,
    /// BrkDrv: the same loads, sweeps 4 and 5 at the low and high pressure instead of camber.
    BrkDrv,
}

/// FreeRolling graph sweep law: the thesis's optimum variable rate, 2/30 °/s, threshold 4°.
pub const GRAPH_FREE_ROLLING_LAW: RateLaw = RateLaw::Variable { low_rate: 2.0, high_rate: 30.0, threshold: 4.0 };
/// FreeRolling graph sweep peak \[deg\] (chosen: the F&M sweeps' 16°, the tyre's usual range).
pub const GRAPH_FREE_ROLLING_PEAK_DEG: f64 = 16.0;
/// BrkDrv graph sweep law: 10/60 %/s, threshold 2 %.
pub const GRAPH_BRKDRV_LAW: RateLaw = RateLaw::Variable { low_rate: 0.10, high_rate: 0.60, threshold: 0.02 };
/// BrkDrv graph sweep peak slip ratio (chosen: the Pure Long sweeps' ±25 %).
pub const GRAPH_BRKDRV_PEAK: f64 = 0.25;

/// The graph-sweep block: five sweeps, identical for every tyre ever tested (absolute loads in
/// N, fixed laws: never replaced by continually variable sweeps, so blocks stay comparable
/// across tyres and procedures). `pressures_bar` = (low, mid, high).
pub fn graph_sweep_block(block: GraphBlock, pressures_bar: [f64; 3], base: Setpoint) -> Vec<Segment> {
    graph_sweep_block_scaled(block, pressures_bar, base, 1.0)
}

/// [`graph_sweep_block`] with every load multiplied by `load_scale`: for tyres of another class
/// (a race tyre's Fz0 of ~1 kN), the same load factors of its own Fz0.
pub fn graph_sweep_block_scaled(
    block: GraphBlock,
    pressures_bar: [f64; 3],
    base: Setpoint,
    load_scale: f64,
) -> Vec<Segment> {
    let mid = pressures_bar[1];
    // (load N, camber deg, pressure bar)
    let cases: [(f64, f64, f64); 5] = match block {
        GraphBlock::FreeRolling => {
            [(6000.0, 0.0, mid), (9000.0, 0.0, mid), (3000.0, 0.0, mid), (6000.0, -3.0, mid), (6000.0, 3.0, mid)]
        }
        GraphBlock::BrkDrv => [
            (6000.0, 0.0, mid),
            (9000.0, 0.0, mid),
            (3000.0, 0.0, mid),
            (6000.0, 0.0, pressures_bar[0]),
            (6000.0, 0.0, pressures_bar[2]),
        ],
    };
    cases
        .iter()
        .map(|&(fz, camber, p)| {
            let mut b = base.zero_slip();
            b.pressure_bar = p;
            b.fz_n = fz * load_scale;
            b.camber_deg = camber;
            let (axis, path) = match block {
                GraphBlock::FreeRolling => {
                    b.mode = RigMode::FreeRolling;
                    (SlipAxis::SlipAngle, SlipPath::full_cycle(GRAPH_FREE_ROLLING_PEAK_DEG, GRAPH_FREE_ROLLING_LAW))
                }
                GraphBlock::BrkDrv => {
                    b.mode = RigMode::Coupled;
                    (SlipAxis::SlipRatio, SlipPath::full_cycle(GRAPH_BRKDRV_PEAK, GRAPH_BRKDRV_LAW))
                }
            };
            let mut s = slip_sweep(
                axis,
                path,
                b,
                LoadCoupling::Constant { fz_n: fz * load_scale },
                CamberCoupling::Constant { camber_deg: camber },
            );
            s.type_name = format!("GraphSweep_{}", s.type_name);
            s
        })
        .collect()
}
