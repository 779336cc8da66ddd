//! Calibration of the virtual rig against the thesis: the comparison sweeps of Tables 3.6.2-H
//! (FreeRolling) and 3.6.2-I (BrkDrv), the warm-up check (§3.4) and the wear check (§3.9).
//!
//! # The comparison sweeps
//! Each sweep runs on a fresh rig (same seed) with a broken-in, new-tread tyre brought to the
//! 45 °C baseline as the thesis's procedures bring it ([`preconditioned_rig`]: the two warm-up blocks
//! from 20 °C, a heating sweep, a thermal pause at the sweep's conditions until TRDTEMPC is back
//! at 45 °C); the sweep runs 0 → −max → +max → 0, and a zero-slip thermal pause follows until
//! TRDTEMPC (0.1 s mean) is back at 45 °C. The thesis gives rates and thresholds, not loads and ranges; chosen here:
//! - **Range**: ±28° and ±30 %. The thesis's 30 °/s sweep went to ±28° (Fig. 3.6.1-B); with
//!   that range its sweep times (112°/4 °/s = 28 s, 122.27 − 94.3 s cool-down = 27.97 s) and the
//!   BrkDrv ones (10 %/s: 28.6 − 16.2 = 12.4 s; 40 %/s: 12.23 − 8.8 = 3.43 s) fit ±30 % plus
//!   0.4 s of free-rolling reference before the sweep ([`BRKDRV_REFERENCE_HOLD_S`]).
//! - **BrkDrv variable**: 10/60 %/s with a **10 %** threshold, the sweep the thesis measured for
//!   Table 3.6.2-I (`BrkDrv_sw14`, see [`BRKDRV_VARIABLE_THRESHOLD`]), not the 2 % optimum of
//!   Table 3.6.2-E: the 2 % sweep is ~2.7 s shorter and carries a third less energy, so its
//!   sweep + cool-down cannot match the 12.72 s the thesis timed on sw14. The 2 % optimum is run
//!   and printed beside the table, ungraded.
//! - **Load**: 6,000 N for FreeRolling (the graph-sweep nominal load; peak FYW "just over
//!   6,000 N" in Fig. 3.6.2-J) and 5,000 N for BrkDrv (peak FX ≈ 6,000–6,450 N, Fig. 3.6.2-W).
//! - **Speed** 16.6 m/s (LONGVL, the procedure's nominal), camber 0°, 2.6 bar.
//!
//! Mechanical hysteresis = largest − smallest force at the zero crossings of the measured slip
//! during the sweep (reference §3); peak temperature = largest TRDTEMPC sample; sweep + cool =
//! path duration + thermal pause.
//!
//! # Pass criteria (the issue's)
//! Peak temperatures within ±10 %, sweep + cool-down within ±20 %, hysteresis within ±30 % (or
//! ±300 N where the thesis's value is below 1,000 N), and in every column the three sweeps
//! rank as in the thesis. Two sweeps the thesis gives the same value (BrkDrv hysteresis, 1,050 N
//! both) impose no order on each other.

use serde::Serialize;

use crate::config::RigConfig;
use crate::rig::{RigError, VirtualRig};
use mftyre::TyreParams;
use tyre_msgs::msg::{RigSample, RigSetpoint};

/// The thermal baseline every sweep starts from and cools back to [°C] (thesis §3.4).
pub const BASELINE_C: f64 = 45.0;
/// Setpoint stream rate of the harness (a sequencer's control rate) [Hz].
pub const SETPOINT_RATE_HZ: f64 = 100.0;
/// Longest thermal pause before giving up [s] (the thesis's rig used 120 s; the calibration
/// waits longer so a slow cool-down is measured rather than cut off).
pub const COOL_TIMEOUT_S: f64 = 300.0;

/// Which slip a sweep moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepAxis {
    /// Slip angle, drive un-coupled (FreeRolling).
    Lateral,
    /// Slip ratio, drive coupled (BrkDrv).
    Longitudinal,
}

/// A piecewise-linear slip path 0 → −max → +max → 0 at a 'low rate' inside ±threshold and a
/// 'high rate' beyond (a constant-rate sweep has both rates equal).
#[derive(Debug, Clone, PartialEq)]
pub struct SlipPath {
    /// (t0, t1, s0, s1) segments.
    segments: Vec<(f64, f64, f64, f64)>,
}

impl SlipPath {
    /// A variable-rate ("shark tooth") sweep to ±`max` with `low` rate inside ±`threshold`.
    pub fn variable(max: f64, low_rate: f64, high_rate: f64, threshold: f64) -> SlipPath {
        let th = threshold.abs().min(max.abs());
        let max = max.abs();
        // Way points with the rate that applies between them.
        let legs: [(f64, f64); 7] = [(0.0, -th), (-th, -max), (-max, -th), (-th, th), (th, max), (max, th), (th, 0.0)];
        let mut segments = Vec::new();
        let mut t = 0.0;
        for (s0, s1) in legs {
            let len = (s1 - s0).abs();
            if len <= 0.0 {
                continue;
            }
            let inside = s0.abs().max(s1.abs()) <= th + 1e-12;
            let rate = if inside { low_rate } else { high_rate };
            let dt = len / rate;
            segments.push((t, t + dt, s0, s1));
            t += dt;
        }
        SlipPath { segments }
    }

    /// A constant-rate sweep to ±`max`.
    pub fn constant(max: f64, rate: f64) -> SlipPath {
        SlipPath::variable(max, rate, rate, 0.0)
    }

    /// The same path after `hold_s` at zero slip: BrkDrv sweeps start with the free-rolling
    /// reference (VX1, W1 of the Calspan slip-ratio form, reference §3) recorded at the sweep's
    /// load case just before the sweep.
    pub fn with_reference_hold(self, hold_s: f64) -> SlipPath {
        let h = hold_s.max(0.0);
        let mut segments = vec![(0.0, h, 0.0, 0.0)];
        segments.extend(self.segments.into_iter().map(|(t0, t1, s0, s1)| (t0 + h, t1 + h, s0, s1)));
        SlipPath { segments }
    }

    /// Duration [s].
    pub fn duration_s(&self) -> f64 {
        self.segments.last().map_or(0.0, |s| s.1)
    }

    /// Slip at `t_s` after the start (0 before, 0 after).
    pub fn at(&self, t_s: f64) -> f64 {
        for &(t0, t1, s0, s1) in &self.segments {
            if t_s <= t1 {
                let f = ((t_s - t0) / (t1 - t0)).clamp(0.0, 1.0);
                return s0 + (s1 - s0) * f;
            }
        }
        0.0
    }
}

/// One sweep's operating conditions and path.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSetup {
    /// Name (becomes the setpoints' `sweep_name`).
    pub name: String,
    /// Slip angle or slip ratio.
    pub axis: SweepAxis,
    /// The path of the swept slip (deg or –).
    pub path: SlipPath,
    /// Vertical load [N].
    pub fz_n: f64,
    /// Belt speed [m/s].
    pub speed_mps: f64,
    /// Camber [deg].
    pub camber_deg: f64,
    /// Inflation pressure [Pa].
    pub pressure_pa: f64,
    /// Slip angle held during a longitudinal sweep [deg].
    pub slip_angle_deg: f64,
    /// Asymmetric loading (reference §7): load factors of `fz_n` at slip angles ≤ −5° and ≥ +5°,
    /// linear in between (weight transfer onto a right-side tyre when steering left).
    pub load_coupling: Option<(f64, f64)>,
}

/// What a sweep and its thermal pause produced.
#[derive(Debug, Clone)]
pub struct SweepOutcome {
    /// Mechanical hysteresis at zero slip [N].
    pub hysteresis_n: f64,
    /// Largest TRDTEMPC sample in sweep + pause [°C].
    pub peak_temp_c: f64,
    /// TRDTEMPC when the sweep started [°C].
    pub start_temp_c: f64,
    /// Path duration [s].
    pub sweep_s: f64,
    /// Thermal pause until TRDTEMPC ≤ baseline [s] (the timeout if it never got there).
    pub cool_s: f64,
    /// Whether the pause ended by reaching the baseline (false: timed out).
    pub cooled: bool,
    /// Sliding energy of the sweep (truth) [J].
    pub sliding_energy_j: f64,
    /// Every sample from sweep start to pause end.
    pub samples: Vec<RigSample>,
    /// Rig time at which the sweep started [s].
    pub start_time_s: f64,
}

impl SweepOutcome {
    /// Sweep + cool-down [s].
    pub fn sweep_plus_cool_s(&self) -> f64 {
        self.sweep_s + self.cool_s
    }
}

fn setpoint(setup: &SweepSetup, slip: f64) -> RigSetpoint {
    let (mode, sa, sr) = match setup.axis {
        SweepAxis::Lateral => (RigSetpoint::MODE_FREE_ROLLING, slip, 0.0),
        SweepAxis::Longitudinal => (RigSetpoint::MODE_COUPLED, setup.slip_angle_deg, slip),
    };
    let fz_n = match setup.load_coupling {
        Some((neg, pos)) => {
            let f = ((sa + 5.0) / 10.0).clamp(0.0, 1.0);
            setup.fz_n * (neg + (pos - neg) * f)
        }
        None => setup.fz_n,
    };
    RigSetpoint {
        mode,
        slip_angle_deg: sa,
        slip_ratio: sr,
        fz_n,
        camber_deg: setup.camber_deg,
        pressure_pa: setup.pressure_pa,
        speed_mps: setup.speed_mps,
        sweep_name: setup.name.clone(),
        ..RigSetpoint::default()
    }
}

/// Brings belt, load, camber and pressure to the sweep's conditions at zero slip (`settle_s`).
pub fn settle(rig: &mut VirtualRig, setup: &SweepSetup, settle_s: f64) -> Result<(), crate::SetpointRefusal> {
    rig.apply_setpoint(&setpoint(setup, 0.0))?;
    let t = rig.time_s() + settle_s;
    rig.run_until(t, &mut |_| {});
    Ok(())
}

/// Streams `setup`'s slip path to the rig at [`SETPOINT_RATE_HZ`], collecting samples.
pub fn run_path(
    rig: &mut VirtualRig,
    setup: &SweepSetup,
    samples: &mut Vec<RigSample>,
) -> Result<(), crate::SetpointRefusal> {
    let t0 = rig.time_s();
    let duration = setup.path.duration_s();
    let dt_sp = 1.0 / SETPOINT_RATE_HZ;
    let n = (duration / dt_sp).ceil() as usize;
    for k in 0..=n {
        let t = (k as f64 * dt_sp).min(duration);
        rig.apply_setpoint(&setpoint(setup, setup.path.at(t)))?;
        rig.run_until(t0 + ((k + 1) as f64 * dt_sp).min(duration + dt_sp), &mut |s| samples.push(s.clone()));
    }
    Ok(())
}

/// The thermal pause: zero slip at `setup`'s load and speed until TRDTEMPC (0.1 s mean) is at
/// `baseline_c`; returns its duration, or `None` when `timeout_s` passed first.
pub fn thermal_pause(
    rig: &mut VirtualRig,
    setup: &SweepSetup,
    baseline_c: f64,
    timeout_s: f64,
    samples: &mut Vec<RigSample>,
) -> Result<Option<f64>, crate::SetpointRefusal> {
    rig.apply_setpoint(&setpoint(setup, 0.0))?;
    let t_start = rig.time_s();
    let dt = 1.0 / SETPOINT_RATE_HZ;
    let window = 10;
    let mut recent: Vec<f64> = Vec::with_capacity(window);
    let mut t = t_start;
    while t < t_start + timeout_s {
        t += dt;
        rig.run_until(t, &mut |s| {
            samples.push(s.clone());
            if recent.len() == window {
                recent.remove(0);
            }
            recent.push(s.trdtempc_c);
        });
        if recent.len() == window && recent.iter().sum::<f64>() / window as f64 <= baseline_c {
            return Ok(Some(rig.time_s() - t_start));
        }
    }
    Ok(None)
}

/// Runs one sweep from the rig's present state, then the zero-slip pause until TRDTEMPC
/// (0.1 s mean) is at `baseline_c` or `cool_timeout_s` has passed.
pub fn run_sweep(
    rig: &mut VirtualRig,
    setup: &SweepSetup,
    baseline_c: f64,
    cool_timeout_s: f64,
) -> Result<SweepOutcome, crate::SetpointRefusal> {
    let t0 = rig.time_s();
    let e0 = rig.truth().sliding_energy_j;
    let duration = setup.path.duration_s();
    let mut samples = Vec::new();
    run_path(rig, setup, &mut samples)?;
    let t_end = t0 + duration;
    let energy = rig.truth().sliding_energy_j - e0;
    // The pause is timed from the end of the path (the servo may still be arriving).
    let extra = rig.time_s() - t_end;
    let pause = thermal_pause(rig, setup, baseline_c, cool_timeout_s, &mut samples)?;
    let (cooled, cool_s) = match pause {
        Some(p) => (true, p + extra),
        None => (false, cool_timeout_s + extra),
    };
    let start_temp_c = samples.first().map_or(f64::NAN, |s| s.trdtempc_c);
    let peak_temp_c = samples.iter().map(|s| s.trdtempc_c).fold(f64::NEG_INFINITY, f64::max);
    // Zero crossings while the slip is being swept (plus 0.3 s for the servo to arrive).
    let sweep_samples: Vec<&RigSample> = samples.iter().filter(|s| s.runtime_s <= t_end + 0.3).collect();
    let hysteresis_n = hysteresis(&sweep_samples, setup.axis);
    Ok(SweepOutcome {
        hysteresis_n,
        peak_temp_c,
        start_temp_c,
        sweep_s: duration,
        cool_s,
        cooled,
        sliding_energy_j: energy,
        samples,
        start_time_s: t0,
    })
}

/// Largest − smallest force at the zero crossings of the measured slip (linear interpolation
/// between the samples either side); 0 with fewer than two crossings.
pub fn hysteresis(samples: &[&RigSample], axis: SweepAxis) -> f64 {
    let get = |s: &RigSample| match axis {
        SweepAxis::Lateral => (s.slipangl_deg, s.fyw_n),
        SweepAxis::Longitudinal => (s.longslip, s.fx_n),
    };
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut count = 0;
    for w in samples.windows(2) {
        let (s0, f0) = get(w[0]);
        let (s1, f1) = get(w[1]);
        if (s0 < 0.0 && s1 >= 0.0) || (s0 > 0.0 && s1 <= 0.0) {
            let f = if s1 == s0 { f1 } else { f0 + (f1 - f0) * (-s0) / (s1 - s0) };
            lo = lo.min(f);
            hi = hi.max(f);
            count += 1;
        }
    }
    if count >= 2 { hi - lo } else { 0.0 }
}

/// Which of the three comparison sweeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepKind {
    /// The slow constant-rate sweep.
    ConstantLow,
    /// The fast constant-rate sweep.
    ConstantHigh,
    /// The optimal variable-rate sweep.
    Variable,
}

impl SweepKind {
    /// All three, in table order.
    pub const ALL: [SweepKind; 3] = [SweepKind::ConstantLow, SweepKind::ConstantHigh, SweepKind::Variable];

    /// The JSON/table name.
    pub fn name(self) -> &'static str {
        match self {
            SweepKind::ConstantLow => "constant_low",
            SweepKind::ConstantHigh => "constant_high",
            SweepKind::Variable => "variable",
        }
    }
}

/// The three figures of one sweep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Figures {
    /// Mechanical hysteresis [N].
    pub hysteresis_n: f64,
    /// Peak TRDTEMPC [°C].
    pub peak_temp_c: f64,
    /// Sweep + cool-down [s].
    pub sweep_plus_cool_s: f64,
}

/// One table row: the virtual rig's figures beside the thesis's.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Which sweep.
    pub sweep: SweepKind,
    /// Virtual rig: hysteresis [N].
    pub hysteresis_n: f64,
    /// Virtual rig: peak TRDTEMPC [°C].
    pub peak_temp_c: f64,
    /// Virtual rig: sweep + cool-down [s].
    pub sweep_plus_cool_s: f64,
    /// The thesis's figures.
    pub thesis: Figures,
    /// Sweep duration alone [s] (not in the thesis's table).
    #[serde(skip)]
    pub sweep_s: f64,
    /// Sliding energy [kJ] (truth).
    #[serde(skip)]
    pub sliding_energy_kj: f64,
    /// Whether the thermal pause reached the baseline.
    #[serde(skip)]
    pub cooled: bool,
}

impl Row {
    fn figures(&self) -> Figures {
        Figures {
            hysteresis_n: self.hysteresis_n,
            peak_temp_c: self.peak_temp_c,
            sweep_plus_cool_s: self.sweep_plus_cool_s,
        }
    }
}

/// Table 3.6.2-H (FreeRolling: 4 °/s, 30 °/s, 2/30 °/s at 4°).
pub const THESIS_FREEROLLING: [Figures; 3] = [
    Figures { hysteresis_n: 700.0, peak_temp_c: 106.5, sweep_plus_cool_s: 122.27 },
    Figures { hysteresis_n: 4100.0, peak_temp_c: 82.5, sweep_plus_cool_s: 41.94 },
    Figures { hysteresis_n: 300.0, peak_temp_c: 77.8, sweep_plus_cool_s: 42.55 },
];

/// Table 3.6.2-I (BrkDrv: 10 %/s, 40 %/s, 10/60 %/s at 2 %).
pub const THESIS_BRKDRV: [Figures; 3] = [
    Figures { hysteresis_n: 1050.0, peak_temp_c: 92.0, sweep_plus_cool_s: 28.6 },
    Figures { hysteresis_n: 2700.0, peak_temp_c: 74.4, sweep_plus_cool_s: 12.23 },
    Figures { hysteresis_n: 1050.0, peak_temp_c: 73.1, sweep_plus_cool_s: 12.72 },
];

/// FreeRolling comparison load [N] (see the module doc).
pub const FREEROLLING_LOAD_N: f64 = 6000.0;
/// BrkDrv comparison load [N] (see the module doc).
pub const BRKDRV_LOAD_N: f64 = 5000.0;
/// Threshold of the graded BrkDrv variable-rate sweep [-]: 10 %, because Table 3.6.2-I's
/// "optimal variable rate" figures are those of `BrkDrv_sw14` (LR10/HR60/TH10): "BrkDrv_sw14 has
/// a slightly different threshold to the optimal setup" (§3.6.2), and its 73.1 °C peak is the
/// one quoted for sw14 ("60 %/s (BrkDrv_sw14) peaked at 73.1 °C"). The 2 % optimum of Table
/// 3.6.2-E ([`BRKDRV_OPTIMUM_THRESHOLD`]) is run and printed beside it, ungraded: it is a
/// shorter sweep the thesis never timed.
pub const BRKDRV_VARIABLE_THRESHOLD: f64 = 0.10;
/// The GS2MF BrkDrv optimum threshold (Table 3.6.2-E) [-].
pub const BRKDRV_OPTIMUM_THRESHOLD: f64 = 0.02;

/// The GS2MF BrkDrv optimum variable-rate sweep (10/60 %/s, 2 %), printed but not graded.
pub fn brkdrv_optimum_setup() -> SweepSetup {
    let mut s = brkdrv_setup(SweepKind::Variable);
    s.name = "BrkDrv_variable_optimum_th2".into();
    s.path =
        SlipPath::variable(0.30, 0.10, 0.60, BRKDRV_OPTIMUM_THRESHOLD).with_reference_hold(BRKDRV_REFERENCE_HOLD_S);
    s
}

/// Free-rolling reference before each BrkDrv sweep [s]: the thesis's constant-rate BrkDrv
/// sweeps last 0.4 s longer than their ±30 % paths (10 %/s: 28.6 − 16.2 = 12.4 s for 12 s;
/// 40 %/s: 12.23 − 8.8 = 3.43 s for 3 s).
pub const BRKDRV_REFERENCE_HOLD_S: f64 = 0.4;
/// Comparison belt speed [m/s].
pub const SPEED_MPS: f64 = 16.6;
/// Comparison pressure [Pa].
pub const PRESSURE_PA: f64 = 260_000.0;

/// The FreeRolling comparison sweep of `kind`.
pub fn freerolling_setup(kind: SweepKind) -> SweepSetup {
    let path = match kind {
        SweepKind::ConstantLow => SlipPath::constant(28.0, 4.0),
        SweepKind::ConstantHigh => SlipPath::constant(28.0, 30.0),
        SweepKind::Variable => SlipPath::variable(28.0, 2.0, 30.0, 4.0),
    };
    SweepSetup {
        name: format!("FreeRoll_{}", kind.name()),
        axis: SweepAxis::Lateral,
        path,
        fz_n: FREEROLLING_LOAD_N,
        speed_mps: SPEED_MPS,
        camber_deg: 0.0,
        pressure_pa: PRESSURE_PA,
        slip_angle_deg: 0.0,
        load_coupling: None,
    }
}

/// The BrkDrv comparison sweep of `kind`.
pub fn brkdrv_setup(kind: SweepKind) -> SweepSetup {
    let path = match kind {
        SweepKind::ConstantLow => SlipPath::constant(0.30, 0.10),
        SweepKind::ConstantHigh => SlipPath::constant(0.30, 0.40),
        SweepKind::Variable => SlipPath::variable(0.30, 0.10, 0.60, BRKDRV_VARIABLE_THRESHOLD),
    }
    .with_reference_hold(BRKDRV_REFERENCE_HOLD_S);
    SweepSetup {
        name: format!("BrkDrv_{}", kind.name()),
        axis: SweepAxis::Longitudinal,
        path,
        fz_n: BRKDRV_LOAD_N,
        speed_mps: SPEED_MPS,
        camber_deg: 0.0,
        pressure_pa: PRESSURE_PA,
        slip_angle_deg: 0.0,
        load_coupling: None,
    }
}

/// The heating sweep that follows the warm-up in the thesis's procedures (§4.1: "one sweep
/// brings it to ~65 °C, then thermal pause"): the graph-sweep nominal load, GS2MF variable rate.
pub fn heating_sweep() -> SweepSetup {
    SweepSetup {
        name: "Heating".into(),
        axis: SweepAxis::Lateral,
        path: SlipPath::variable(15.0, 2.0, 30.0, 4.0),
        fz_n: 6000.0,
        speed_mps: SPEED_MPS,
        camber_deg: 0.0,
        pressure_pa: PRESSURE_PA,
        slip_angle_deg: 0.0,
        load_coupling: None,
    }
}

/// A new, broken-in tyre brought up the way the thesis's procedures do before their sweeps:
/// the two warm-up blocks from 20 °C, then the heating sweep. Every comparison sweep starts
/// from a clone of this rig, after a thermal pause at its own conditions
/// ([`comparison_sweep`]); the bulk keeps the heat this history leaves in it, which is what
/// makes cool-down times depend on the sweep.
pub fn preconditioned_rig(cfg: &RigConfig, params: &TyreParams) -> Result<VirtualRig, CalibrationError> {
    let mut cfg = cfg.clone();
    cfg.environment.initial_tyre_temp_c = 20.0;
    let mut rig = VirtualRig::new(cfg.clone(), params.clone(), cfg.seed)?;
    rig.complete_break_in();
    run_warmup(&mut rig, 2)?;
    let heat = heating_sweep();
    settle(&mut rig, &heat, 3.0).map_err(|r| CalibrationError::Refused(heat.name.clone(), r))?;
    let mut sink = Vec::new();
    // The sweep must end above the baseline so the thermal pause meets 45 °C on the way down;
    // a tyre the warm-up left cool gets another heating sweep (at most a few).
    for _ in 0..4 {
        sink.clear();
        run_path(&mut rig, &heat, &mut sink).map_err(|r| CalibrationError::Refused(heat.name.clone(), r))?;
        let tail = &sink[sink.len().saturating_sub(10)..];
        if tail.iter().map(|s| s.trdtempc_c).sum::<f64>() / tail.len().max(1) as f64 > BASELINE_C + 5.0 {
            break;
        }
    }
    Ok(rig)
}

/// A comparison sweep on a clone of `preconditioned`: the thermal pause at the sweep's load,
/// speed and drive mode until TRDTEMPC is at the 45 °C baseline, the sweep, the thermal pause.
pub fn comparison_sweep(preconditioned: &VirtualRig, setup: &SweepSetup) -> Result<SweepOutcome, CalibrationError> {
    let mut rig = preconditioned.clone();
    let refused = |r| CalibrationError::Refused(setup.name.clone(), r);
    let mut sink = Vec::new();
    thermal_pause(&mut rig, setup, BASELINE_C, COOL_TIMEOUT_S, &mut sink).map_err(refused)?;
    run_sweep(&mut rig, setup, BASELINE_C, COOL_TIMEOUT_S).map_err(refused)
}

/// Errors of the calibration harness.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// The rig could not be built.
    #[error(transparent)]
    Rig(#[from] RigError),
    /// The rig refused one of the harness's setpoints.
    #[error("sweep {0}: setpoint refused: {1}")]
    Refused(String, crate::SetpointRefusal),
}

/// The warm-up check (thesis §3.4): two blocks of five sweeps from 20 °C.
#[derive(Debug, Clone, Serialize)]
pub struct WarmupCheck {
    /// TRDTEMPC (1 s mean) at the end of block 1 [°C] (thesis: 31 °C at 235 s).
    pub after_block1_c: f64,
    /// TRDTEMPC (1 s mean) at the end of block 2 [°C] (thesis: 42 °C at 430 s).
    pub after_block2_c: f64,
    /// Duration of one block [s].
    pub block_s: f64,
    /// Whether block 2 ends within 40–45 °C.
    pub pass: bool,
}

/// The wear check: a representative GS2MF FreeRolling procedure's sweeps.
#[derive(Debug, Clone, Serialize)]
pub struct WearCheck {
    /// Number of sweeps run.
    pub sweeps: usize,
    /// Total sliding energy [MJ].
    pub sliding_energy_mj: f64,
    /// True tread loss [mm].
    pub tread_loss_mm: f64,
    /// DSTWOWHC at 6,000 N free rolling before minus after [mm] (0.1 mm resolution).
    pub measured_radius_loss_mm: f64,
    /// Simulated procedure time [s].
    pub procedure_s: f64,
    /// Whether the tread loss is within 1–3 mm.
    pub pass: bool,
}

/// Everything `tyrerig rig calibrate` prints.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationReport {
    /// FreeRolling rows (constant_low, constant_high, variable).
    pub freerolling: Vec<Row>,
    /// BrkDrv rows.
    pub brkdrv: Vec<Row>,
    /// The BrkDrv 2 % optimum variable-rate sweep (Table 3.6.2-E), beside the thesis's variable
    /// figures but not graded (see [`BRKDRV_VARIABLE_THRESHOLD`]).
    pub brkdrv_optimum: Row,
    /// Warm-up check.
    pub warmup: WarmupCheck,
    /// Wear check.
    pub wear: WearCheck,
    /// Wear over the thesis's 32-sweep investigation (Table 3.6.2-B; thesis: 1.4 mm).
    pub investigation_wear: WearCheck,
    /// Every failed criterion, in words; empty when all pass.
    pub failures: Vec<String>,
    /// The sweeps' samples, for plots (not serialised).
    #[serde(skip)]
    pub outcomes: Vec<(String, SweepAxis, SweepOutcome)>,
}

impl CalibrationReport {
    /// Whether every criterion passed.
    pub fn pass(&self) -> bool {
        self.failures.is_empty()
    }
}

fn row(kind: SweepKind, o: &SweepOutcome, thesis: Figures) -> Row {
    Row {
        sweep: kind,
        hysteresis_n: o.hysteresis_n,
        peak_temp_c: o.peak_temp_c,
        sweep_plus_cool_s: o.sweep_plus_cool_s(),
        thesis,
        sweep_s: o.sweep_s,
        sliding_energy_kj: o.sliding_energy_j * 1e-3,
        cooled: o.cooled,
    }
}

/// Checks one table against the pass criteria; pushes failures in words.
pub fn check_table(name: &str, rows: &[Row], failures: &mut Vec<String>) {
    for r in rows {
        let t = r.thesis;
        let h_tol = if t.hysteresis_n < 1000.0 { 300.0 } else { 0.3 * t.hysteresis_n };
        if (r.hysteresis_n - t.hysteresis_n).abs() > h_tol {
            failures.push(format!(
                "{name} {}: hysteresis {:.0} N vs thesis {:.0} N (±{h_tol:.0} N)",
                r.sweep.name(),
                r.hysteresis_n,
                t.hysteresis_n
            ));
        }
        if (r.peak_temp_c - t.peak_temp_c).abs() > 0.1 * t.peak_temp_c {
            failures.push(format!(
                "{name} {}: peak temperature {:.1} °C vs thesis {:.1} °C (±10 %)",
                r.sweep.name(),
                r.peak_temp_c,
                t.peak_temp_c
            ));
        }
        if (r.sweep_plus_cool_s - t.sweep_plus_cool_s).abs() > 0.2 * t.sweep_plus_cool_s {
            failures.push(format!(
                "{name} {}: sweep + cool {:.2} s vs thesis {:.2} s (±20 %)",
                r.sweep.name(),
                r.sweep_plus_cool_s,
                t.sweep_plus_cool_s
            ));
        }
        if !r.cooled {
            failures.push(format!("{name} {}: thermal pause timed out", r.sweep.name()));
        }
    }
    type Column = (&'static str, fn(&Figures) -> f64);
    let columns: [Column; 3] = [
        ("hysteresis", |f| f.hysteresis_n),
        ("peak temperature", |f| f.peak_temp_c),
        ("sweep + cool", |f| f.sweep_plus_cool_s),
    ];
    for (col, get) in columns {
        for i in 0..rows.len() {
            for j in 0..rows.len() {
                let (ti, tj) = (get(&rows[i].thesis), get(&rows[j].thesis));
                let (si, sj) = (get(&rows[i].figures()), get(&rows[j].figures()));
                if ti < tj && si >= sj {
                    failures.push(format!(
                        "{name} {col}: thesis ranks {} below {}, virtual rig does not ({si:.2} vs {sj:.2})",
                        rows[i].sweep.name(),
                        rows[j].sweep.name()
                    ));
                }
            }
        }
    }
}

/// The thesis's graph-sweep load cases (§3.9): (load N, camber deg).
pub const GRAPH_SWEEP_CASES: [(f64, f64); 5] =
    [(6000.0, 0.0), (9000.0, 0.0), (3000.0, 0.0), (6000.0, -3.0), (6000.0, 3.0)];

/// One warm-up sweep: the thesis does not give MICH2MF's warm-up block, so each of its five
/// sweeps (the graph-sweep load cases) is a gentle constant 4 °/s sweep to ±10° followed by
/// zero-slip rolling that fills the block to 215 s (the thesis's two blocks end at 430 s).
pub const WARMUP_SWEEP_MAX_DEG: f64 = 10.0;
/// Warm-up sweep rate [deg/s].
pub const WARMUP_SWEEP_RATE_DEG_PER_S: f64 = 4.0;
/// Duration of one warm-up sweep slot (sweep + rolling) [s].
pub const WARMUP_SLOT_S: f64 = 43.0;

fn warmup_setup(i: usize) -> SweepSetup {
    let (fz, camber) = GRAPH_SWEEP_CASES[i % GRAPH_SWEEP_CASES.len()];
    SweepSetup {
        name: format!("Warmup_{}", i + 1),
        axis: SweepAxis::Lateral,
        path: SlipPath::constant(WARMUP_SWEEP_MAX_DEG, WARMUP_SWEEP_RATE_DEG_PER_S),
        fz_n: fz,
        speed_mps: SPEED_MPS,
        camber_deg: camber,
        pressure_pa: PRESSURE_PA,
        slip_angle_deg: 0.0,
        load_coupling: None,
    }
}

/// Runs `blocks` warm-up blocks on `rig`; returns the TRDTEMPC (1 s mean) after each block.
pub fn run_warmup(rig: &mut VirtualRig, blocks: usize) -> Result<Vec<f64>, CalibrationError> {
    let mut temps = Vec::new();
    for b in 0..blocks {
        for i in 0..GRAPH_SWEEP_CASES.len() {
            let setup = warmup_setup(b * GRAPH_SWEEP_CASES.len() + i);
            let slot_end = rig.time_s() + WARMUP_SLOT_S;
            // Ramp the belt and load in the first 5 s of the slot, then sweep, then roll.
            settle(rig, &setup, 5.0).map_err(|r| CalibrationError::Refused(setup.name.clone(), r))?;
            let t0 = rig.time_s();
            let n = (setup.path.duration_s() * SETPOINT_RATE_HZ).ceil() as usize;
            for k in 0..=n {
                let t = k as f64 / SETPOINT_RATE_HZ;
                rig.apply_setpoint(&setpoint(&setup, setup.path.at(t)))
                    .map_err(|r| CalibrationError::Refused(setup.name.clone(), r))?;
                rig.run_until(t0 + t + 1.0 / SETPOINT_RATE_HZ, &mut |_| {});
            }
            rig.apply_setpoint(&setpoint(&setup, 0.0)).map_err(|r| CalibrationError::Refused(setup.name.clone(), r))?;
            let mut last = Vec::new();
            rig.run_until(slot_end, &mut |s| last.push(s.trdtempc_c));
            if i + 1 == GRAPH_SWEEP_CASES.len() {
                let tail: Vec<f64> = last.iter().rev().take(100).copied().collect();
                temps.push(tail.iter().sum::<f64>() / tail.len().max(1) as f64);
            }
        }
    }
    Ok(temps)
}

/// The representative GS2MF FreeRolling procedure for the wear check (reference §7, §8, §10): a
/// heating sweep, graph sweeps (×5) before and after, and per pressure (2.1, 2.6, 3.3 bar) 14
/// force & moment sweeps: three asymmetric-load sweeps to 16° (load factors 1.8/0.6, 1.6/0.4,
/// 1.4/0.2 of Fz0 at ∓5°), one with 1.8° camber, one with adverse (+3°) camber, two low-slip
/// sweeps to 4° at ±3°, three to 22° at 0.8° camber (0.6/1.0/1.4 Fz0), two vertical-load sweeps
/// (as 18° sweeps at 0.5 Fz0: they cost little energy, §7) and two adverse sweeps at ±3°
/// (medium asymmetric load). Every sweep is the GS2MF variable rate (2/30 °/s, 4°) with a
/// thermal pause to 45 °C (120 s time-out, as the thesis's rig).
pub fn representative_freerolling(fz0_n: f64) -> Vec<SweepSetup> {
    let mk = |name: String, fz: f64, camber: f64, max: f64, p: f64, coupling: Option<(f64, f64)>| SweepSetup {
        name,
        axis: SweepAxis::Lateral,
        path: SlipPath::variable(max, 2.0, 30.0, 4.0_f64.min(max)),
        fz_n: fz,
        speed_mps: SPEED_MPS,
        camber_deg: camber,
        pressure_pa: p,
        slip_angle_deg: 0.0,
        load_coupling: coupling,
    };
    let graph_max = 15.0;
    let mut v = vec![mk("Heating".into(), 6000.0, 0.0, 12.0, PRESSURE_PA, None)];
    for (i, &(fz, c)) in GRAPH_SWEEP_CASES.iter().enumerate() {
        v.push(mk(format!("Graph1_{}", i + 1), fz, c, graph_max, PRESSURE_PA, None));
    }
    let (high, medium, low) = (Some((1.8, 0.6)), Some((1.6, 0.4)), Some((1.4, 0.2)));
    for p in [210_000.0, 260_000.0, 330_000.0] {
        // (load factor of Fz0, camber deg, max slip angle deg, asymmetric load factors)
        type Case = (f64, f64, f64, Option<(f64, f64)>);
        let list: [Case; 14] = [
            (1.0, 0.0, 16.0, high),
            (1.0, 0.0, 16.0, medium),
            (1.0, 0.0, 16.0, low),
            (1.0, -1.8, 16.0, medium),
            (1.0, 3.0, 16.0, medium),
            (1.0, 3.0, 4.0, None),
            (1.0, -3.0, 4.0, None),
            (0.6, 0.8, 22.0, None),
            (1.0, 0.8, 22.0, None),
            (1.4, 0.8, 22.0, None),
            (0.5, 0.0, 18.0, None),
            (0.5, 0.0, 18.0, None),
            (1.0, 3.0, 16.0, medium),
            (1.0, -3.0, 16.0, medium),
        ];
        for (i, (k, c, max, coupling)) in list.into_iter().enumerate() {
            v.push(mk(format!("FM_{:.1}bar_{}", p / 1e5, i + 1), k * fz0_n, c, max, p, coupling));
        }
    }
    for (i, &(fz, c)) in GRAPH_SWEEP_CASES.iter().enumerate() {
        v.push(mk(format!("Graph2_{}", i + 1), fz, c, graph_max, PRESSURE_PA, None));
    }
    v
}

fn radius_at_reference(rig: &mut VirtualRig) -> Result<f64, CalibrationError> {
    let setup = SweepSetup {
        name: "RadiusRef".into(),
        axis: SweepAxis::Lateral,
        path: SlipPath::constant(0.0, 1.0),
        fz_n: 6000.0,
        speed_mps: SPEED_MPS,
        camber_deg: 0.0,
        pressure_pa: PRESSURE_PA,
        slip_angle_deg: 0.0,
        load_coupling: None,
    };
    settle(rig, &setup, 6.0).map_err(|r| CalibrationError::Refused(setup.name.clone(), r))?;
    let mut r = Vec::new();
    let t = rig.time_s() + 2.0;
    rig.run_until(t, &mut |s| r.push(s.dstwowhc_m));
    Ok(r.iter().sum::<f64>() / r.len().max(1) as f64)
}

/// The thesis's FreeRolling variable-rate investigation (Table 3.6.2-B, 32 sweeps after the
/// warm-up), every sweep to ±28° at 6,000 N as the comparison sweeps: the variable-rate graph
/// sweep (LR4/HR12/TH4) five times, constant rates 4–30 °/s, thresholds 2–10°, low rates 2–8 °/s
/// and high rates 6–30 °/s. The thesis measured 1.4 mm of wear over it (§3.6.2); that sets
/// `wear.wear_mm_per_mj`.
pub fn investigation_freerolling() -> Vec<SweepSetup> {
    let mk = |name: String, path: SlipPath| SweepSetup {
        name,
        axis: SweepAxis::Lateral,
        path,
        fz_n: FREEROLLING_LOAD_N,
        speed_mps: SPEED_MPS,
        camber_deg: 0.0,
        pressure_pa: PRESSURE_PA,
        slip_angle_deg: 0.0,
        load_coupling: None,
    };
    let var = |lr: f64, hr: f64, th: f64| SlipPath::variable(28.0, lr, hr, th);
    let mut v = vec![mk("sw1".into(), var(4.0, 12.0, 4.0))];
    for r in [4.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0, 25.0, 30.0] {
        v.push(mk(format!("sw_const_{r}"), SlipPath::constant(28.0, r)));
    }
    for th in [2.0, 4.0, 6.0, 8.0, 10.0] {
        v.push(mk(format!("sw_th_{th}"), var(4.0, 12.0, th)));
    }
    for lr in [2.0, 4.0, 6.0, 8.0] {
        v.push(mk(format!("sw_lr_{lr}"), var(lr, 12.0, 4.0)));
    }
    for hr in [6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0, 25.0, 30.0] {
        v.push(mk(format!("sw_hr_{hr}"), var(4.0, hr, 4.0)));
    }
    v.push(mk("sw32".into(), var(4.0, 12.0, 4.0)));
    v
}

/// The thesis's GS2MF FreeRolling duration (§4.5) [s]: the representative procedure repeats its
/// force & moment block until the simulated procedure is this long, the best proxy the thesis
/// gives for how much sweeping (so sliding energy) the procedure holds.
pub const GS2MF_FREEROLLING_S: f64 = 4080.0;

/// Runs `sweeps` (each with a thermal pause to 45 °C, 120 s time-out) on a fresh, new tyre after
/// the warm-up; with `until_s`, keeps cycling the sweeps after the first six (the force & moment
/// block) until the procedure has lasted that long, then runs the last five (graph sweeps).
pub fn run_wear_procedure(
    cfg: &RigConfig,
    params: &TyreParams,
    sweeps: &[SweepSetup],
    until_s: Option<f64>,
) -> Result<WearCheck, CalibrationError> {
    let mut rig = VirtualRig::new(cfg.clone(), params.clone(), cfg.seed)?;
    let t_start = rig.time_s();
    run_warmup(&mut rig, 2)?;
    let r0 = radius_at_reference(&mut rig)?;
    let worn0 = rig.truth().tread_worn_mm;
    let e0 = rig.truth().sliding_energy_j;
    let run = |rig: &mut VirtualRig, s: &SweepSetup| -> Result<(), CalibrationError> {
        settle(rig, s, 3.0).map_err(|r| CalibrationError::Refused(s.name.clone(), r))?;
        run_sweep(rig, s, BASELINE_C, 120.0).map_err(|r| CalibrationError::Refused(s.name.clone(), r))?;
        Ok(())
    };
    let mut count = 0;
    match until_s {
        Some(end) if sweeps.len() > 11 => {
            let (head, rest) = sweeps.split_at(6);
            let (block, tail) = rest.split_at(rest.len() - 5);
            for s in head {
                run(&mut rig, s)?;
                count += 1;
            }
            // Reserve the graph sweeps' share of the time (their length in the first pass).
            let mut i = 0;
            let reserve = 5.0 * 60.0;
            while rig.time_s() - t_start < end - reserve {
                run(&mut rig, &block[i % block.len()])?;
                i += 1;
                count += 1;
            }
            for s in tail {
                run(&mut rig, s)?;
                count += 1;
            }
        }
        _ => {
            for s in sweeps {
                run(&mut rig, s)?;
                count += 1;
            }
        }
    }
    let r1 = radius_at_reference(&mut rig)?;
    let truth = rig.truth();
    let loss = truth.tread_worn_mm - worn0;
    Ok(WearCheck {
        sweeps: count,
        sliding_energy_mj: (truth.sliding_energy_j - e0) * 1e-6,
        tread_loss_mm: loss,
        measured_radius_loss_mm: (r0 - r1) * 1e3,
        procedure_s: rig.time_s() - t_start,
        pass: (1.0..=3.0).contains(&loss),
    })
}

/// The wear check: the representative GS2MF FreeRolling, its force & moment block repeated to
/// the thesis's 4,080 s.
pub fn run_wear_check(cfg: &RigConfig, params: &TyreParams) -> Result<WearCheck, CalibrationError> {
    run_wear_procedure(cfg, params, &representative_freerolling(params.fnomin_n()), Some(GS2MF_FREEROLLING_S))
}

/// Runs the whole calibration: both tables, the warm-up check and the wear check.
pub fn run_calibration(cfg: &RigConfig, params: &TyreParams) -> Result<CalibrationReport, CalibrationError> {
    let mut outcomes = Vec::new();
    let mut freerolling = Vec::new();
    let mut brkdrv = Vec::new();
    let pre = preconditioned_rig(cfg, params)?;
    for (i, kind) in SweepKind::ALL.into_iter().enumerate() {
        let s = freerolling_setup(kind);
        let o = comparison_sweep(&pre, &s)?;
        freerolling.push(row(kind, &o, THESIS_FREEROLLING[i]));
        outcomes.push((s.name.clone(), s.axis, o));
    }
    for (i, kind) in SweepKind::ALL.into_iter().enumerate() {
        let s = brkdrv_setup(kind);
        let o = comparison_sweep(&pre, &s)?;
        brkdrv.push(row(kind, &o, THESIS_BRKDRV[i]));
        outcomes.push((s.name.clone(), s.axis, o));
    }
    let s = brkdrv_optimum_setup();
    let o = comparison_sweep(&pre, &s)?;
    let brkdrv_optimum = row(SweepKind::Variable, &o, THESIS_BRKDRV[2]);
    outcomes.push((s.name.clone(), s.axis, o));
    let mut failures = Vec::new();
    check_table("FreeRolling", &freerolling, &mut failures);
    check_table("BrkDrv", &brkdrv, &mut failures);

    let mut warm_cfg = cfg.clone();
    warm_cfg.environment.initial_tyre_temp_c = 20.0;
    let mut rig = VirtualRig::new(warm_cfg, params.clone(), cfg.seed)?;
    let temps = run_warmup(&mut rig, 2)?;
    let warmup = WarmupCheck {
        after_block1_c: temps[0],
        after_block2_c: temps[1],
        block_s: WARMUP_SLOT_S * GRAPH_SWEEP_CASES.len() as f64,
        pass: (40.0..=45.0).contains(&temps[1]),
    };
    if !warmup.pass {
        failures.push(format!("warm-up: {:.1} °C after two blocks, want 40–45 °C", warmup.after_block2_c));
    }
    let wear = run_wear_check(cfg, params)?;
    let investigation_wear = run_wear_procedure(cfg, params, &investigation_freerolling(), None)?;
    if !wear.pass {
        failures.push(format!("wear: {:.2} mm over the representative procedure, want 1–3 mm", wear.tread_loss_mm));
    }
    Ok(CalibrationReport { freerolling, brkdrv, brkdrv_optimum, warmup, wear, investigation_wear, failures, outcomes })
}

/// The report as a table for people.
pub fn format_report(r: &CalibrationReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for (name, table, rows) in [("FreeRolling", "3.6.2-H", &r.freerolling), ("BrkDrv", "3.6.2-I", &r.brkdrv)] {
        let var = if name == "BrkDrv" { "variable = 10/60 %/s, 10 % (sw14)" } else { "variable = 2/30 °/s, 4°" };
        let _ = writeln!(s, "{name} (thesis Table {table}; {var}): virtual rig | thesis");
        let _ = writeln!(
            s,
            "  {:<14} {:>16} {:>18} {:>20} {:>9} {:>11}",
            "sweep", "hysteresis N", "peak TRDTEMPC °C", "sweep+cool s", "sweep s", "energy kJ"
        );
        for row in rows.iter() {
            let _ = writeln!(
                s,
                "  {:<14} {:>7.0} | {:>6.0} {:>8.1} | {:>7.1} {:>9.2} | {:>8.2} {:>9.2} {:>11.1}{}",
                row.sweep.name(),
                row.hysteresis_n,
                row.thesis.hysteresis_n,
                row.peak_temp_c,
                row.thesis.peak_temp_c,
                row.sweep_plus_cool_s,
                row.thesis.sweep_plus_cool_s,
                row.sweep_s,
                row.sliding_energy_kj,
                if row.cooled { "" } else { "  (pause timed out)" }
            );
        }
    }
    let o = &r.brkdrv_optimum;
    let _ = writeln!(
        s,
        "  {:<14} {:>7.0} | {:>6} {:>8.1} | {:>7} {:>9.2} | {:>8} {:>9.2} {:>11.1}  (2 % optimum of Table 3.6.2-E, ungraded: the thesis's row is sw14, 10 % threshold)",
        "variable_th2", o.hysteresis_n, "", o.peak_temp_c, "", o.sweep_plus_cool_s, "", o.sweep_s, o.sliding_energy_kj
    );
    let w = &r.warmup;
    let _ = writeln!(
        s,
        "Warm-up from 20 °C: {:.1} °C after block 1 (thesis 31 °C), {:.1} °C after block 2 at {:.0} s (thesis 42 °C at 430 s; want 40–45 °C)",
        w.after_block1_c,
        w.after_block2_c,
        2.0 * w.block_s
    );
    let x = &r.wear;
    let _ = writeln!(
        s,
        "Wear over a representative GS2MF FreeRolling ({} sweeps, {:.0} s, {:.2} MJ sliding): {:.2} mm tread (DSTWOWHC −{:.1} mm; want 1–3 mm)",
        x.sweeps, x.procedure_s, x.sliding_energy_mj, x.tread_loss_mm, x.measured_radius_loss_mm
    );
    let x = &r.investigation_wear;
    let _ = writeln!(
        s,
        "Wear over the thesis's FreeRolling investigation (Table 3.6.2-B, {} sweeps, {:.0} s, {:.2} MJ): {:.2} mm (thesis 1.4 mm; sets wear_mm_per_mj)",
        x.sweeps, x.procedure_s, x.sliding_energy_mj, x.tread_loss_mm
    );
    if r.failures.is_empty() {
        let _ = writeln!(s, "PASS: every criterion met");
    } else {
        let _ = writeln!(s, "FAIL: {} criteria missed:", r.failures.len());
        for f in &r.failures {
            let _ = writeln!(s, "  - {f}");
        }
    }
    s
}
