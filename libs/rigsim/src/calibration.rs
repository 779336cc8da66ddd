//! Calibration of the virtual rig against the thesis: the comparison sweeps of Tables 3.6.2-H
//! (FreeRolling) and 3.6.2-I (BrkDrv), the BrkDrv threshold analysis (§3.6.2), the warm-up
//! check (§3.4) and the wear check (§3.9). The acceptance test (`tests/calibration.rs`) runs it
//! for every noise seed 0..=9 and requires every criterion for each.
//!
//! # The comparison sweeps
//! Each sweep runs on a fresh rig (same seed) with a broken-in, new-tread tyre brought to the
//! 45 °C baseline as the thesis's procedures bring it ([`preconditioned_rig`]: the two warm-up
//! blocks from 20 °C, a heating sweep, a thermal pause at the sweep's conditions until the
//! thermal gate releases at 45 °C); the sweep runs 0 → −max → +max → 0, and a zero-slip thermal
//! pause follows until the gate releases again. The thesis gives rates and thresholds, not
//! loads and ranges; chosen here:
//! - **Range**: ±28° and ±30 %. The thesis's 30 °/s sweep went to ±28° (Fig. 3.6.1-B); with
//!   that range its sweep times (112°/4 °/s = 28 s, 122.27 − 94.3 s cool-down = 27.97 s) and the
//!   BrkDrv ones (10 %/s: 28.6 − 16.2 = 12.4 s; 40 %/s: 12.23 − 8.8 = 3.43 s) fit ±30 % plus
//!   0.4 s of free-rolling reference before the sweep ([`BRKDRV_REFERENCE_HOLD_S`]).
//! - **Load**: 6,000 N for FreeRolling (the graph-sweep nominal load; peak FYW "just over
//!   6,000 N" in Fig. 3.6.2-J) and 5,000 N for BrkDrv (peak FX ≈ 6,000–6,450 N, Fig. 3.6.2-W).
//! - **Speed** 16.6 m/s (LONGVL, the procedure's nominal), camber 0°, 2.6 bar.
//!
//! # Why the graded BrkDrv variable row has a 10 % threshold
//! The issue describes the row as "variable 10/60 %/s with 2 % threshold", the GS2MF optimum
//! (Table 3.6.2-E). The thesis's figures in that column (1,050 N, 73.1 °C, 12.72 s) are not of a
//! 2 % sweep: the investigation schedule (Table 3.6.2-C, seed text ~line 2193) lists
//! `BrkDrv_sw14_VariableRate_LR10_HR60_TH10`; the high-rate analysis (~line 2300) says the
//! 60 %/s sweep, sw14, peaked at 73.1 °C and took 9.2 s to cool; and the comparison (~lines
//! 2440–2445, 2475, 2500) uses sw14 as "the closest sweep to the optimal variable rate setup",
//! which "has a slightly different threshold to the optimal setup" (a small influence on runtime,
//! none on tyre performance, says the thesis). The only 2 % sweep the thesis times is
//! `BrkDrv_sw15` (LR10/**HR30**/TH2) in the threshold analysis. So the graded row is sw14
//! (10 %, [`BRKDRV_VARIABLE_THRESHOLD`]); the 2 % optimum ([`brkdrv_optimum_setup`]) is run
//! and reported beside it (table row `variable_th2`, JSON `brkdrv_optimum_th2`), ungraded.
//! One tension stays: 12.72 s minus sw14's 9.2 s cool-down (or the 8.8 s of ~line 2514) leaves
//! 3.5–3.9 s of sweep, shorter than any LR10/TH10 sweep can be (its ±10 % at 10 %/s alone takes
//! 4 s); at ±30 % the virtual sw14 sweeps for 5.73 s. The thesis's text does not resolve it.
//!
//! # The threshold analysis (graded)
//! What the thesis does state of the 2 % threshold (§3.6.2, ~line 2340): at LR10/HR30 a 2 %
//! threshold gave a sweep of "a little over 6 s", an 18 % threshold one "just over 10 s". Both
//! sweeps run here ([`run_threshold_check`]) at ±40 % ([`THRESHOLD_ANALYSIS_RANGE`], the range
//! is not stated; see there why ±40 %), and the measured durations (sweep start to LONGSLIP back
//! at zero) must lie in [6, 6.9] s and [10, 11.5] s ("a little over X" read as X to X + 15 %,
//! [`THRESHOLD_DURATION_TOLERANCE`]) with their difference within ±1 s of 4 s (a figure that does
//! not depend on the range). Their peak temperatures are printed beside the thesis's 77.1 /
//! 84.9 °C, ungraded: load and start temperature of those sweeps are not stated, and at the
//! comparison load and this range the virtual tyre runs hotter (~94 °C).
//!
//! # Figures
//! - **Mechanical hysteresis** (thesis §3.6.1, reference §3): the largest minus the smallest
//!   force at zero slip over the sweep's passes through zero, read as an engineer reads it off
//!   the force-vs-slip plot rather than from single noisy samples ([`zero_pass_forces`]): for
//!   each pass of the commanded path through zero (the middle crossing and the return to zero;
//!   not the departure from rest), a least-squares straight line of force against the measured
//!   slip through that pass's samples within ±1° ([`HYSTERESIS_WINDOW_DEG`], the on-centre
//!   range) or ±2 % ([`HYSTERESIS_WINDOW_SLIP_RATIO`], the slip-stiffness range), evaluated at
//!   zero slip. On the return to zero only the approach is used, up to the first sample at zero:
//!   the force that relaxes afterwards at standstill slip is not a zero crossing. (The former
//!   reading — interpolating between the two samples either side of every sign change of the
//!   measured slip — let sensor noise around zero after the sweep pick the relaxing force a
//!   sample or two late: FreeRolling 30 °/s hysteresis 2,422–4,024 N over seeds 0–8.)
//! - **Peak temperature**: the largest TRDTEMPC sample of sweep and pause.
//! - **Sweep + cool**: path duration + thermal pause, the pause ending where the thermal gate
//!   of the live procedure (`nodes/thermal`) would release it: its 0.5 s running median of
//!   TRDTEMPC at or below 45 °C ([`ReleaseFilter`]), so the times are the pauses a GS2MF run on
//!   this rig sees.
//!
//! # Pass criteria (the issue's)
//! Peak temperatures within ±10 %, sweep + cool-down within ±20 %, hysteresis within ±30 % (or
//! ±300 N where the thesis's value is below 1,000 N), and in every column the three sweeps
//! rank as in the thesis. Two sweeps the thesis gives the same value (BrkDrv hysteresis, 1,050 N
//! both) impose no order on each other. Plus the threshold analysis above, the warm-up (40–45 °C
//! after two blocks) and the wear (1–3 mm over a representative GS2MF FreeRolling).

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

    /// The passes of the path through zero slip, in time order: every sign change (a
    /// crossing, the window reaches both sides of it) and every arrival back at zero that the
    /// path does not leave at once (the end of a sweep: the window lies before it). The
    /// departure from rest at the start is not a pass: the tyre has not been on the other side.
    pub fn zero_passes(&self) -> Vec<ZeroPass> {
        let moving: Vec<(f64, f64, f64, f64)> = self.segments.iter().copied().filter(|s| s.2 != s.3).collect();
        let mut out = Vec::new();
        for (i, &(t0, t1, s0, s1)) in moving.iter().enumerate() {
            let rate = ((s1 - s0) / (t1 - t0)).abs();
            if s0 * s1 < 0.0 {
                out.push(ZeroPass { time_s: t0 + (-s0) / (s1 - s0) * (t1 - t0), rate, arrival: false });
            } else if s1 == 0.0 && s0 != 0.0 {
                // Leaves zero again at once (a constant-rate sweep's middle crossing is built from
                // an arrival and a departure): a crossing.
                let leaves = moving.get(i + 1).is_some_and(|n| n.2 == 0.0 && (n.0 - t1).abs() < 1e-9);
                out.push(ZeroPass { time_s: t1, rate, arrival: !leaves });
            }
        }
        out
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

/// A pass of a [`SlipPath`] through zero slip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZeroPass {
    /// Path time at which the commanded slip is zero [s].
    pub time_s: f64,
    /// Commanded slip rate there [deg/s or 1/s].
    pub rate: f64,
    /// The path arrives at zero and stays (end of a sweep); otherwise it crosses.
    pub arrival: bool,
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
    /// Mechanical hysteresis at zero slip [N] (largest − smallest of `zero_pass_forces_n`).
    pub hysteresis_n: f64,
    /// Force at zero slip on each pass of the path through zero ([`zero_pass_forces`]) [N].
    pub zero_pass_forces_n: Vec<f64>,
    /// Largest TRDTEMPC sample in sweep + pause [°C].
    pub peak_temp_c: f64,
    /// TRDTEMPC when the sweep started [°C].
    pub start_temp_c: f64,
    /// Path duration [s].
    pub sweep_s: f64,
    /// Thermal pause from the end of the path until the thermal gate's rule releases
    /// ([`ReleaseFilter`]) [s] (the timeout if it never did).
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

/// The thermal gate's release filter, as the live procedure applies it (`nodes/thermal`, its
/// default `spike_filter`): a running median of TRDTEMPC over the last
/// [`GATE_MEDIAN_WINDOW_S`] of samples (never fewer than [`GATE_MIN_SAMPLES`]), fed with every
/// sample, sweep included; a pause ends at the first sample after which the median is at or
/// below the baseline. The calibration times cool-downs with this rule so its figures are the
/// pauses a procedure on this rig would see. (The rule is restated here because `libs/` do not
/// depend on `nodes/`: a change to the gate's `SpikeFilterConfig::default()` must be made here
/// too; `nodes/thermal/tests/release_rule_in_rigsim.rs` fails until it is.)
#[derive(Debug, Clone, Default)]
pub struct ReleaseFilter {
    samples: std::collections::VecDeque<(f64, f64)>,
    scratch: Vec<f64>,
}

/// Window of the thermal gate's running median [s] (`nodes/thermal` `spike_filter.window_s`).
pub const GATE_MEDIAN_WINDOW_S: f64 = 0.5;
/// Fewest samples the gate's median needs (`nodes/thermal` `spike_filter.min_samples`).
pub const GATE_MIN_SAMPLES: usize = 3;

impl ReleaseFilter {
    /// Feeds one temperature sample at rig time `t_s`.
    pub fn push(&mut self, t_s: f64, temp_c: f64) {
        self.samples.push_back((t_s, temp_c));
        while self.samples.len() > GATE_MIN_SAMPLES
            && self.samples.front().is_some_and(|&(t, _)| t_s - t > GATE_MEDIAN_WINDOW_S)
        {
            self.samples.pop_front();
        }
    }

    /// The running median; `None` until the window holds [`GATE_MIN_SAMPLES`].
    pub fn median(&mut self) -> Option<f64> {
        let n = self.samples.len();
        if n < GATE_MIN_SAMPLES {
            return None;
        }
        self.scratch.clear();
        self.scratch.extend(self.samples.iter().map(|&(_, v)| v));
        self.scratch.sort_by(f64::total_cmp);
        let mid = n / 2;
        Some(if n % 2 == 1 { self.scratch[mid] } else { 0.5 * (self.scratch[mid - 1] + self.scratch[mid]) })
    }
}

/// The thermal pause: zero slip at `setup`'s load and speed until the thermal gate's release
/// filter ([`ReleaseFilter`], already fed with the sweep's samples) is at `baseline_c`; returns
/// the rig time of the releasing sample, or `None` when `timeout_s` passed first.
pub fn thermal_pause(
    rig: &mut VirtualRig,
    setup: &SweepSetup,
    baseline_c: f64,
    timeout_s: f64,
    filter: &mut ReleaseFilter,
    samples: &mut Vec<RigSample>,
) -> Result<Option<f64>, crate::SetpointRefusal> {
    rig.apply_setpoint(&setpoint(setup, 0.0))?;
    let t_start = rig.time_s();
    let dt = 1.0 / SETPOINT_RATE_HZ;
    let mut released = None;
    let mut t = t_start;
    while t < t_start + timeout_s && released.is_none() {
        t += dt;
        rig.run_until(t, &mut |s| {
            samples.push(s.clone());
            filter.push(s.runtime_s, s.trdtempc_c);
            if released.is_none() && filter.median().is_some_and(|m| m <= baseline_c) {
                released = Some(s.runtime_s);
            }
        });
    }
    Ok(released)
}

/// Runs one sweep from the rig's present state, then the zero-slip pause until the thermal
/// gate's rule ([`ReleaseFilter`]) releases at `baseline_c` or `cool_timeout_s` has passed.
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
    let mut filter = ReleaseFilter::default();
    for s in &samples {
        filter.push(s.runtime_s, s.trdtempc_c);
    }
    // The pause is timed from the end of the path (the servo may still be arriving).
    let pause = thermal_pause(rig, setup, baseline_c, cool_timeout_s, &mut filter, &mut samples)?;
    let (cooled, cool_s) = match pause {
        Some(t) => (true, t - t_end),
        None => (false, rig.time_s() - t_end),
    };
    let start_temp_c = samples.first().map_or(f64::NAN, |s| s.trdtempc_c);
    let peak_temp_c = samples.iter().map(|s| s.trdtempc_c).fold(f64::NEG_INFINITY, f64::max);
    let passes = zero_pass_forces(&samples, setup.axis, &setup.path, t0, hysteresis_window(setup.axis));
    let hysteresis_n = hysteresis_of(&passes);
    Ok(SweepOutcome {
        hysteresis_n,
        zero_pass_forces_n: passes,
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

/// Half-width of the hysteresis fit window around zero slip, lateral [deg]: the on-centre
/// range the thesis reads cornering stiffness, RSAT and RCF in (±1°, §3.11).
pub const HYSTERESIS_WINDOW_DEG: f64 = 1.0;
/// Half-width of the hysteresis fit window around zero slip, longitudinal [-]: the GS2MF BrkDrv
/// threshold, "a suitably wide range of data from which to extract accurate slip stiffness"
/// (§3.6.2), i.e. where FX is still near-linear in slip.
pub const HYSTERESIS_WINDOW_SLIP_RATIO: f64 = 0.02;

/// The fit window's half-width for `axis` ([`HYSTERESIS_WINDOW_DEG`],
/// [`HYSTERESIS_WINDOW_SLIP_RATIO`]).
pub fn hysteresis_window(axis: SweepAxis) -> f64 {
    match axis {
        SweepAxis::Lateral => HYSTERESIS_WINDOW_DEG,
        SweepAxis::Longitudinal => HYSTERESIS_WINDOW_SLIP_RATIO,
    }
}

/// Time the measured slip may trail the commanded path into and out of a pass (servo lag and
/// its settling) [s]: the pass's samples are looked for this much beyond its commanded window.
pub const PASS_SERVO_MARGIN_S: f64 = 0.1;
/// A measured slip angle within this of zero counts as having arrived there [deg] (3× the
/// sensor's 1σ noise).
pub const ARRIVAL_TOLERANCE_DEG: f64 = 0.03;
/// A measured slip ratio within this of zero counts as having arrived there [-] (≈ 2.5× the
/// coupled drive's combined sensor noise and controller wander).
pub const ARRIVAL_TOLERANCE_SLIP_RATIO: f64 = 0.001;

/// The force at zero slip on each pass of `path` through zero ([`SlipPath::zero_passes`]), as
/// an engineer reads it off the force-vs-slip plot: a least-squares straight line of force
/// (FYW or FX) against the *measured* slip (SLIPANGL or LONGSLIP) through that pass's samples
/// with |measured slip| ≤ `window`, evaluated at zero slip. A pass's samples are those around
/// the time its commanded slip is within ±`window` of zero (plus [`PASS_SERVO_MARGIN_S`] for
/// the servo): both sides of a crossing; for an arrival (the end of a sweep) only the approach,
/// up to and including the first sample at which the measured slip has reached zero (within
/// [`ARRIVAL_TOLERANCE_DEG`] / [`ARRIVAL_TOLERANCE_SLIP_RATIO`]), so the force relaxing after
/// the slip has stopped is not read. `t0` is the rig time the path started at. Fewer than three
/// samples or no spread of slip: the mean force of the samples; no samples: the pass is left
/// out.
pub fn zero_pass_forces(samples: &[RigSample], axis: SweepAxis, path: &SlipPath, t0: f64, window: f64) -> Vec<f64> {
    type Reading = fn(&RigSample) -> (f64, f64);
    let (get, tol): (Reading, f64) = match axis {
        SweepAxis::Lateral => (|s| (s.slipangl_deg, s.fyw_n), ARRIVAL_TOLERANCE_DEG),
        SweepAxis::Longitudinal => (|s| (s.longslip, s.fx_n), ARRIVAL_TOLERANCE_SLIP_RATIO),
    };
    let mut out = Vec::new();
    for pass in path.zero_passes() {
        let half = window / pass.rate.max(1e-12);
        let lo = t0 + pass.time_s - half - PASS_SERVO_MARGIN_S;
        let hi = t0 + pass.time_s + half + PASS_SERVO_MARGIN_S;
        // The side the slip comes from: the path just before the pass.
        let side = path.at(pass.time_s - 0.5 * half).signum();
        let mut pts: Vec<(f64, f64)> = Vec::new();
        for s in samples.iter().filter(|s| s.runtime_s >= lo && s.runtime_s <= hi) {
            let (x, y) = get(s);
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            if x.abs() <= window {
                pts.push((x, y));
            }
            if pass.arrival && s.runtime_s >= t0 + pass.time_s - half && x * side <= tol {
                break;
            }
        }
        if pts.is_empty() {
            continue;
        }
        let n = pts.len() as f64;
        let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
        let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
        let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let f0 = if pts.len() >= 3 && sxx > 1e-12 * window * window * n { my - sxy / sxx * mx } else { my };
        out.push(f0);
    }
    out
}

/// Mechanical hysteresis from the forces at the zero passes (thesis §3.6.1): largest −
/// smallest; 0 with fewer than two passes.
pub fn hysteresis_of(forces_n: &[f64]) -> f64 {
    if forces_n.len() < 2 {
        return 0.0;
    }
    let hi = forces_n.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lo = forces_n.iter().copied().fold(f64::INFINITY, f64::min);
    hi - lo
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
/// 3.6.2-E ([`BRKDRV_OPTIMUM_THRESHOLD`]) is run and reported beside it, ungraded; the thesis's
/// own statement about the 2 % threshold is graded in [`run_threshold_check`]. See the module doc.
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
    freerolling_sweep(format!("FreeRoll_{}", kind.name()), path)
}

/// A FreeRolling sweep at the comparison conditions (load, speed, pressure, camber 0°).
fn freerolling_sweep(name: String, path: SlipPath) -> SweepSetup {
    SweepSetup {
        name,
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
    let mut filter = ReleaseFilter::default();
    thermal_pause(&mut rig, setup, BASELINE_C, COOL_TIMEOUT_S, &mut filter, &mut sink).map_err(refused)?;
    run_sweep(&mut rig, setup, BASELINE_C, COOL_TIMEOUT_S).map_err(refused)
}

/// Slip-ratio range of the threshold-analysis sweeps [-]. The thesis does not state it. At the
/// comparison sweeps' ±30 % the 2 % and 18 % sweeps (LR10/HR30, with the 0.4 s reference hold)
/// would last 4.9 s and 9.2 s, not "a little over 6 s" and "just over 10 s" (§3.6.2); ±40 % —
/// a slip-ratio range GS2MF itself uses (combined segments at SR ±0.4, §5) — gives 6.27 s and
/// 10.53 s. The difference of the two durations does not depend on the range (4 × 16 % ×
/// (1/10 − 1/30) s = 4.27 s against the thesis's ~4 s) and is graded as well.
pub const THRESHOLD_ANALYSIS_RANGE: f64 = 0.40;
/// Thresholds of the threshold analysis the thesis gives durations for [-] (§3.6.2, Table
/// 3.6.2-C `BrkDrv_sw15` TH2 and `BrkDrv_sw23` TH18, both LR10/HR30).
pub const THRESHOLD_ANALYSIS_THRESHOLDS: [f64; 2] = [0.02, 0.18];
/// The thesis's durations of those sweeps [s]: "a little over 6s" and "just over 10s" (§3.6.2,
/// read off Fig. 3.6.2-S).
pub const THESIS_THRESHOLD_DURATIONS_S: [f64; 2] = [6.0, 10.0];
/// "A little over" / "just over" X is graded as X ≤ duration ≤ (1 + this)·X [-].
pub const THRESHOLD_DURATION_TOLERANCE: f64 = 0.15;
/// The 18 % − 2 % duration difference must be within this of the thesis's ~4 s [s].
pub const THRESHOLD_DIFFERENCE_TOLERANCE_S: f64 = 1.0;
/// The thesis's peak temperatures of those sweeps [°C] (77.1 and 84.9 °C, §3.6.2): printed,
/// not graded (their start temperature and load are not stated).
pub const THESIS_THRESHOLD_PEAKS_C: [f64; 2] = [77.1, 84.9];

/// One threshold-analysis sweep (BrkDrv LR10/HR30 at `threshold`, ±[`THRESHOLD_ANALYSIS_RANGE`],
/// the comparison sweeps' load, speed and reference hold).
pub fn threshold_setup(threshold: f64) -> SweepSetup {
    let mut s = brkdrv_setup(SweepKind::Variable);
    s.name = format!("BrkDrv_threshold_LR10_HR30_TH{:.0}", threshold * 100.0);
    s.path = SlipPath::variable(THRESHOLD_ANALYSIS_RANGE, 0.10, 0.30, threshold)
        .with_reference_hold(BRKDRV_REFERENCE_HOLD_S);
    s
}

/// The threshold analysis on the virtual rig.
#[derive(Debug, Clone, Serialize)]
pub struct ThresholdCheck {
    /// Thresholds [-].
    pub thresholds: [f64; 2],
    /// Measured sweep durations [s]: sweep start (reference hold) to the first sample with
    /// LONGSLIP back at zero (within [`ARRIVAL_TOLERANCE_SLIP_RATIO`]) after the path's end.
    pub duration_s: [f64; 2],
    /// The thesis's durations [s].
    pub thesis_duration_s: [f64; 2],
    /// Peak TRDTEMPC [°C] (ungraded).
    pub peak_temp_c: [f64; 2],
    /// The thesis's peaks [°C].
    pub thesis_peak_temp_c: [f64; 2],
    /// Slip-ratio range assumed [-].
    pub range: f64,
    /// Whether both durations and their difference are within tolerance.
    pub pass: bool,
}

/// When the measured slip of `o` (a longitudinal sweep of `path`) is back at zero: the first
/// sample at or after the path's final arrival minus 0.5 s with |LONGSLIP| within
/// [`ARRIVAL_TOLERANCE_SLIP_RATIO`] once the path has left zero, measured from the sweep start [s].
fn measured_duration_s(o: &SweepOutcome, path: &SlipPath) -> f64 {
    let end = path.duration_s();
    o.samples
        .iter()
        .find(|s| {
            let tau = s.runtime_s - o.start_time_s;
            tau >= end - 0.5 && s.longslip.abs() <= ARRIVAL_TOLERANCE_SLIP_RATIO
        })
        .map_or(f64::NAN, |s| s.runtime_s - o.start_time_s)
}

/// Runs the threshold analysis from `preconditioned` and grades its durations.
pub fn run_threshold_check(preconditioned: &VirtualRig) -> Result<ThresholdCheck, CalibrationError> {
    let mut duration_s = [f64::NAN; 2];
    let mut peak_temp_c = [f64::NAN; 2];
    for (i, th) in THRESHOLD_ANALYSIS_THRESHOLDS.into_iter().enumerate() {
        let s = threshold_setup(th);
        let o = comparison_sweep(preconditioned, &s)?;
        duration_s[i] = measured_duration_s(&o, &s.path);
        peak_temp_c[i] = o.peak_temp_c;
    }
    let t = THESIS_THRESHOLD_DURATIONS_S;
    let within = |d: f64, x: f64| d >= x && d <= (1.0 + THRESHOLD_DURATION_TOLERANCE) * x;
    let diff_ok = ((duration_s[1] - duration_s[0]) - (t[1] - t[0])).abs() <= THRESHOLD_DIFFERENCE_TOLERANCE_S;
    Ok(ThresholdCheck {
        thresholds: THRESHOLD_ANALYSIS_THRESHOLDS,
        duration_s,
        thesis_duration_s: t,
        peak_temp_c,
        thesis_peak_temp_c: THESIS_THRESHOLD_PEAKS_C,
        range: THRESHOLD_ANALYSIS_RANGE,
        pass: within(duration_s[0], t[0]) && within(duration_s[1], t[1]) && diff_ok,
    })
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
    /// The noise seed the report was made with.
    pub seed: u64,
    /// FreeRolling rows (constant_low, constant_high, variable).
    pub freerolling: Vec<Row>,
    /// BrkDrv rows.
    pub brkdrv: Vec<Row>,
    /// The BrkDrv 2 % optimum variable-rate sweep (Table 3.6.2-E), beside the thesis's variable
    /// figures but not graded (see [`BRKDRV_VARIABLE_THRESHOLD`]).
    pub brkdrv_optimum: Row,
    /// The thesis's BrkDrv threshold analysis (2 % vs 18 % at LR10/HR30), graded on durations.
    pub threshold_analysis: ThresholdCheck,
    /// Warm-up check.
    pub warmup: WarmupCheck,
    /// Wear check.
    pub wear: WearCheck,
    /// Wear over the thesis's 32-sweep investigation (Table 3.6.2-B; thesis: 1.4 mm).
    pub investigation_wear: WearCheck,
    /// The same criteria applied to the BrkDrv table with the 2 % optimum in the variable row
    /// (the wording), in words; informational, not part of [`Self::pass`].
    pub brkdrv_optimum_as_variable_misses: Vec<String>,
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
    let mk = freerolling_sweep;
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
    let threshold_analysis = run_threshold_check(&pre)?;
    let mut failures = Vec::new();
    check_table("FreeRolling", &freerolling, &mut failures);
    check_table("BrkDrv", &brkdrv, &mut failures);
    // The issue words the variable row as the 2 % optimum: judge that table too, and say what
    // it misses, so nothing about the choice of the graded row is hidden.
    let mut brkdrv_optimum_as_variable_misses = Vec::new();
    let as_worded = [brkdrv[0].clone(), brkdrv[1].clone(), brkdrv_optimum.clone()];
    check_table("BrkDrv (2 % in the variable row)", &as_worded, &mut brkdrv_optimum_as_variable_misses);
    if !threshold_analysis.pass {
        let d = threshold_analysis.duration_s;
        failures.push(format!(
            "BrkDrv threshold analysis: sweeps of {:.2} s (2 %) and {:.2} s (18 %), want {}–{:.1} s and {}–{:.1} s, difference {:.2} s within ±{} s of 4 s",
            d[0],
            d[1],
            THESIS_THRESHOLD_DURATIONS_S[0],
            THESIS_THRESHOLD_DURATIONS_S[0] * (1.0 + THRESHOLD_DURATION_TOLERANCE),
            THESIS_THRESHOLD_DURATIONS_S[1],
            THESIS_THRESHOLD_DURATIONS_S[1] * (1.0 + THRESHOLD_DURATION_TOLERANCE),
            d[1] - d[0],
            THRESHOLD_DIFFERENCE_TOLERANCE_S
        ));
    }

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
    Ok(CalibrationReport {
        seed: cfg.seed,
        freerolling,
        brkdrv,
        brkdrv_optimum,
        threshold_analysis,
        warmup,
        wear,
        investigation_wear,
        brkdrv_optimum_as_variable_misses,
        failures,
        outcomes,
    })
}

/// Why the graded BrkDrv variable row is the 10 % threshold sweep, in one line for the table.
pub const BRKDRV_VARIABLE_NOTE: &str = "graded variable = BrkDrv_sw14 (LR10/HR60, 10 % threshold): the thesis \
names sw14 as the sweep behind Table 3.6.2-I's variable column (\"closest sweep to the optimal\", only its \
threshold differs) and quotes sw14's 73.1 °C; the 2 % optimum is run and printed, ungraded";

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
        "  {:<14} {:>7.0} | {:>6} {:>8.1} | {:>7} {:>9.2} | {:>8} {:>9.2} {:>11.1}  (2 % optimum, ungraded)",
        "variable_th2", o.hysteresis_n, "", o.peak_temp_c, "", o.sweep_plus_cool_s, "", o.sweep_s, o.sliding_energy_kj
    );
    let _ = writeln!(s, "  Note: {BRKDRV_VARIABLE_NOTE}.");
    if r.brkdrv_optimum_as_variable_misses.is_empty() {
        let _ = writeln!(s, "  With the 2 % optimum in the variable row every BrkDrv criterion is met too.");
    } else {
        let _ = writeln!(s, "  With the 2 % optimum in the variable row instead (informational):");
        for m in &r.brkdrv_optimum_as_variable_misses {
            let _ = writeln!(s, "    - {m}");
        }
    }
    let t = &r.threshold_analysis;
    let _ = writeln!(
        s,
        "BrkDrv threshold analysis (LR10/HR30, ±{:.0} % assumed): sweep {:.2} s at 2 % (thesis a little over 6 s), {:.2} s at 18 % (just over 10 s), difference {:.2} s (~4 s){}; peaks {:.1} / {:.1} °C (thesis {:.1} / {:.1}, ungraded)",
        t.range * 100.0,
        t.duration_s[0],
        t.duration_s[1],
        t.duration_s[1] - t.duration_s[0],
        if t.pass { "" } else { "  MISSED" },
        t.peak_temp_c[0],
        t.peak_temp_c[1],
        t.thesis_peak_temp_c[0],
        t.thesis_peak_temp_c[1]
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

/// Runs the whole calibration once per seed (each with `cfg` but that noise seed).
pub fn run_calibration_seeds(
    cfg: &RigConfig,
    params: &TyreParams,
    seeds: impl IntoIterator<Item = u64>,
) -> Result<Vec<CalibrationReport>, CalibrationError> {
    seeds
        .into_iter()
        .map(|seed| {
            let mut c = cfg.clone();
            c.seed = seed;
            run_calibration(&c, params)
        })
        .collect()
}

/// Smallest and largest of one figure over seeds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Range {
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Range {
    fn of(values: impl IntoIterator<Item = f64>) -> Range {
        values.into_iter().fold(Range { min: f64::INFINITY, max: f64::NEG_INFINITY }, |r, v| Range {
            min: r.min.min(v),
            max: r.max.max(v),
        })
    }
}

/// One table row's figures over seeds.
#[derive(Debug, Clone, Serialize)]
pub struct RowSpread {
    /// Which table ("freerolling", "brkdrv", "brkdrv_optimum_th2").
    pub table: &'static str,
    /// Which sweep.
    pub sweep: SweepKind,
    /// Hysteresis over seeds [N].
    pub hysteresis_n: Range,
    /// Peak TRDTEMPC over seeds [°C].
    pub peak_temp_c: Range,
    /// Sweep + cool-down over seeds [s].
    pub sweep_plus_cool_s: Range,
    /// The thesis's figures.
    pub thesis: Figures,
}

/// Every figure's spread over several seeds' reports.
#[derive(Debug, Clone, Serialize)]
pub struct SeedSpread {
    /// The seeds.
    pub seeds: Vec<u64>,
    /// Seeds whose report missed a criterion.
    pub failed_seeds: Vec<u64>,
    /// Per row.
    pub rows: Vec<RowSpread>,
    /// Threshold-analysis durations at 2 % and 18 % [s].
    pub threshold_duration_s: [Range; 2],
    /// Warm-up: TRDTEMPC after block 2 [°C].
    pub warmup_after_block2_c: Range,
    /// Wear over the representative GS2MF FreeRolling [mm].
    pub wear_mm: Range,
}

/// The spread of every figure over `reports` (one per seed).
pub fn seed_spread(reports: &[CalibrationReport]) -> SeedSpread {
    let mut rows = Vec::new();
    for (table, get) in [
        ("freerolling", (|r: &CalibrationReport| r.freerolling.clone()) as fn(&CalibrationReport) -> Vec<Row>),
        ("brkdrv", |r| r.brkdrv.clone()),
        ("brkdrv_optimum_th2", |r| vec![r.brkdrv_optimum.clone()]),
    ] {
        let Some(first) = reports.first() else { break };
        for (i, row) in get(first).iter().enumerate() {
            let all: Vec<Row> = reports.iter().map(|r| get(r)[i].clone()).collect();
            rows.push(RowSpread {
                table,
                sweep: row.sweep,
                hysteresis_n: Range::of(all.iter().map(|r| r.hysteresis_n)),
                peak_temp_c: Range::of(all.iter().map(|r| r.peak_temp_c)),
                sweep_plus_cool_s: Range::of(all.iter().map(|r| r.sweep_plus_cool_s)),
                thesis: row.thesis,
            });
        }
    }
    SeedSpread {
        seeds: reports.iter().map(|r| r.seed).collect(),
        failed_seeds: reports.iter().filter(|r| !r.pass()).map(|r| r.seed).collect(),
        rows,
        threshold_duration_s: [
            Range::of(reports.iter().map(|r| r.threshold_analysis.duration_s[0])),
            Range::of(reports.iter().map(|r| r.threshold_analysis.duration_s[1])),
        ],
        warmup_after_block2_c: Range::of(reports.iter().map(|r| r.warmup.after_block2_c)),
        wear_mm: Range::of(reports.iter().map(|r| r.wear.tread_loss_mm)),
    }
}

/// The spread as a compact table for people.
pub fn format_spread(sp: &SeedSpread) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let seeds = match (sp.seeds.first(), sp.seeds.last()) {
        (Some(a), Some(b)) => format!("{a}..={b}"),
        _ => "none".into(),
    };
    let _ = writeln!(s, "Spread over {} seeds ({seeds}): min–max | thesis", sp.seeds.len());
    let _ = writeln!(s, "  {:<28} {:>20} {:>20} {:>22}", "sweep", "hysteresis N", "peak TRDTEMPC °C", "sweep+cool s");
    for r in &sp.rows {
        let _ = writeln!(
            s,
            "  {:<28} {:>6.0}–{:<5.0}|{:>6.0} {:>6.1}–{:<5.1}|{:>6.1} {:>6.2}–{:<6.2}|{:>7.2}",
            format!("{} {}", r.table, r.sweep.name()),
            r.hysteresis_n.min,
            r.hysteresis_n.max,
            r.thesis.hysteresis_n,
            r.peak_temp_c.min,
            r.peak_temp_c.max,
            r.thesis.peak_temp_c,
            r.sweep_plus_cool_s.min,
            r.sweep_plus_cool_s.max,
            r.thesis.sweep_plus_cool_s
        );
    }
    let [a, b] = sp.threshold_duration_s;
    let _ = writeln!(
        s,
        "  threshold analysis: 2 % {:.2}–{:.2} s (thesis >6), 18 % {:.2}–{:.2} s (thesis >10); warm-up {:.1}–{:.1} °C; wear {:.2}–{:.2} mm",
        a.min,
        a.max,
        b.min,
        b.max,
        sp.warmup_after_block2_c.min,
        sp.warmup_after_block2_c.max,
        sp.wear_mm.min,
        sp.wear_mm.max
    );
    if sp.failed_seeds.is_empty() {
        let _ = writeln!(s, "PASS for every seed");
    } else {
        let _ = writeln!(s, "FAIL for seeds {:?}", sp.failed_seeds);
    }
    s
}
