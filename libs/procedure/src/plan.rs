//! The expanded plan: an ordered list of steps, each a named trajectory with its kind, planned
//! duration and whether a thermal pause follows; and estimates of rig time.

use crate::setpoint::{EnvelopeViolation, RigLimits};
use crate::sweep::Trajectory;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What a plan step is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepKind {
    /// A slip or vertical-load sweep (data; usually followed by a thermal pause).
    Sweep,
    /// Data taken while holding or stepping (on-centre, rolling radius, step-steer, static drag).
    Hold,
    /// Moving between load cases, modes or speeds (no data of interest).
    Settle,
    /// Warm-up sweeps.
    WarmUp,
    /// Free-rolling reference hold before a longitudinal sweep (capture VX1, W1).
    FreeRollingRef,
    /// Inflation pressure change.
    PressureChange,
    /// Tyre change (rig in its safe state).
    TyreChange,
}

impl StepKind {
    /// Data steps carry a thesis-style sweep name and a sweep index.
    pub fn is_data(self) -> bool {
        matches!(self, Self::Sweep | Self::Hold | Self::WarmUp)
    }
}

/// One step of a plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanStep {
    /// Position in [`Plan::steps`].
    pub index: usize,
    /// Thesis-style name for data steps (`FreeRoll_sw14_VariableRate_LR2_HR30_TH4_1`), a
    /// descriptive one otherwise (`Settle`, `PressureChange_2.6bar`, `TyreChange_B`).
    pub name: String,
    /// Kind.
    pub kind: StepKind,
    /// The (sub-)procedure the step belongs to, e.g. `gs2mf_brkdrv` inside the suite.
    pub procedure: String,
    /// Index into [`Plan::sections`].
    pub section_index: usize,
    /// 0-based index among the plan's data steps, for data steps.
    pub sweep_index: Option<u32>,
    /// The setpoints.
    pub trajectory: Trajectory,
    /// Planned duration \[s\] (the trajectory's; thermal pauses are not included).
    pub duration_s: f64,
    /// Whether the sequencer waits on the thermal gate after this step.
    pub thermal_pause_after: bool,
    /// Where a resumed run restarts if this step was interrupted: the first step of its group
    /// (the settle and free-rolling reference before a sweep belong to the sweep).
    pub restart_from: usize,
    /// Tyre specimen mounted during this step.
    pub specimen: String,
}

/// A section of the plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SectionInfo {
    /// Name, e.g. `force_moment_2.1bar`.
    pub name: String,
    /// The (sub-)procedure it belongs to.
    pub procedure: String,
}

/// An expanded procedure, ready for the sequencer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Procedure name (file's `[procedure] name`), e.g. `gs2mf`.
    pub procedure: String,
    /// Human title.
    pub title: String,
    /// Nominal load Fz0 the loads were computed from \[N\].
    pub fz0_n: f64,
    /// Sections in order.
    pub sections: Vec<SectionInfo>,
    /// Steps in order.
    pub steps: Vec<PlanStep>,
}

/// A step that leaves the rig envelope.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("step {index} `{name}` leaves the rig envelope: {violation}")]
pub struct PlanEnvelopeError {
    /// Step index.
    pub index: usize,
    /// Step name.
    pub name: String,
    /// What was outside.
    pub violation: EnvelopeViolation,
}

/// Planned rig time by category.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PlanSummary {
    /// Sum of all step durations (no thermal pauses) \[s\].
    pub setpoint_time_s: f64,
    /// Time by kind \[s\].
    pub time_by_kind_s: BTreeMap<String, f64>,
    /// Data steps.
    pub data_steps: usize,
    /// Sweeps (StepKind::Sweep).
    pub sweeps: usize,
    /// Thermal pauses that will follow steps.
    pub thermal_pauses: usize,
    /// Tyre changes.
    pub tyre_changes: usize,
}

/// A simple cool-down model for time estimates: each thermal pause lasts
/// `base_s + per_slip_s · ∫|slip|dt / (1 unit)`, capped at `timeout_s`; slip-ratio integrals
/// are scaled to degrees by `deg_per_slip_ratio`.
///
/// Defaults are fitted by hand to the thesis: a variable-rate 2/30 °/s sweep to 16° cools in
/// ~25 s (§3.6: 32 s to ~22°); a Square Matrix HAS sweep (±28° at 12 °/s) hits the 120 s
/// time-out (§4.4: 1,600 s for 12 sweeps); BrkDrv 10/60 %/s to ±25 % ≈ 9 s, constant 10 %/s
/// ≈ 16 s (§3.6).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PauseModel {
    /// Floor of every pause \[s\].
    pub base_s: f64,
    /// Seconds of cooling per deg·s of slip exposure.
    pub per_slip_s: f64,
    /// Slip-ratio → degree equivalence for the exposure integral.
    pub deg_per_slip_ratio: f64,
    /// The thermal gate's time-out \[s\] (thesis: 120 s).
    pub timeout_s: f64,
}

impl Default for PauseModel {
    fn default() -> Self {
        Self { base_s: 8.0, per_slip_s: 0.6, deg_per_slip_ratio: 10.0, timeout_s: 120.0 }
    }
}

impl PauseModel {
    /// Estimated thermal pause after `step` (0 if none follows) \[s\].
    pub fn pause_after_s(&self, step: &PlanStep) -> f64 {
        if !step.thermal_pause_after {
            return 0.0;
        }
        let exposure = match &step.trajectory {
            Trajectory::Sweep(s) => {
                let k = match s.axis {
                    crate::sweep::SlipAxis::SlipAngle => 1.0,
                    crate::sweep::SlipAxis::SlipRatio => self.deg_per_slip_ratio,
                };
                // Load scales friction power: normalise by 6 kN, a mid load. A slip angle held
                // through a longitudinal sweep slides laterally the whole time (combined sweeps).
                let fz = s.at(0.0).fz_n.max(1.0) / 6000.0;
                let held_sa = match s.axis {
                    crate::sweep::SlipAxis::SlipRatio => s.base.slip_angle_deg.abs() * s.path.duration_s(),
                    crate::sweep::SlipAxis::SlipAngle => 0.0,
                };
                (s.path.slip_time_integral() * k + held_sa) * fz
            }
            Trajectory::Keyframes(kf) => {
                let f = kf.frames();
                f.windows(2)
                    .map(|w| {
                        let dt = w[1].t_s - w[0].t_s;
                        let sa = 0.5 * (w[0].sp.slip_angle_deg.abs() + w[1].sp.slip_angle_deg.abs());
                        let fz = 0.5 * (w[0].sp.fz_n + w[1].sp.fz_n) / 6000.0;
                        sa * fz * dt
                    })
                    .sum()
            }
        };
        (self.base_s + self.per_slip_s * exposure).min(self.timeout_s)
    }
}

impl Plan {
    /// Total planned setpoint time (no thermal pauses) \[s\].
    pub fn planned_duration_s(&self) -> f64 {
        self.steps.iter().map(|s| s.duration_s).sum()
    }

    /// Planned time from the start of step `from` to the end \[s\].
    pub fn remaining_from_s(&self, from: usize) -> f64 {
        self.steps.iter().skip(from).map(|s| s.duration_s).sum()
    }

    /// Number of data steps (the `sweep_count` of `ProcedureState`).
    pub fn sweep_count(&self) -> u32 {
        self.steps.iter().filter(|s| s.sweep_index.is_some()).count() as u32
    }

    /// Summary of planned time.
    pub fn summary(&self) -> PlanSummary {
        let mut s = PlanSummary::default();
        for st in &self.steps {
            s.setpoint_time_s += st.duration_s;
            let key = serde_json_like_kind(st.kind);
            *s.time_by_kind_s.entry(key).or_insert(0.0) += st.duration_s;
            s.data_steps += usize::from(st.kind.is_data());
            s.sweeps += usize::from(st.kind == StepKind::Sweep);
            s.thermal_pauses += usize::from(st.thermal_pause_after);
            s.tyre_changes += usize::from(st.kind == StepKind::TyreChange);
        }
        s
    }

    /// Planned time plus thermal pauses estimated by `model` \[s\].
    pub fn estimate_total_s(&self, model: &PauseModel) -> f64 {
        self.steps.iter().map(|s| s.duration_s + model.pause_after_s(s)).sum()
    }

    /// Check every step against the rig envelope.
    /// Check every step against the rig envelope: every setpoint inside it, and no slip moving
    /// faster than the rig can slew.
    pub fn check_envelope(&self, limits: &RigLimits) -> Result<(), PlanEnvelopeError> {
        for st in &self.steps {
            let err = |violation| PlanEnvelopeError { index: st.index, name: st.name.clone(), violation };
            for sp in st.trajectory.check_points() {
                limits.check(&sp).map_err(err)?;
            }
            let (sa_rate, sr_rate) = st.trajectory.max_slip_rates();
            // A little slack: keyframe times are sums of divisions.
            let slack = 1.0 + 1e-9;
            if sa_rate > limits.max_slip_angle_rate_dps * slack {
                return Err(err(EnvelopeViolation {
                    axis: "slip_angle_rate_dps",
                    value: sa_rate,
                    limit: limits.max_slip_angle_rate_dps,
                }));
            }
            if sr_rate > limits.max_slip_ratio_rate_ps * slack {
                return Err(err(EnvelopeViolation {
                    axis: "slip_ratio_rate_ps",
                    value: sr_rate,
                    limit: limits.max_slip_ratio_rate_ps,
                }));
            }
        }
        Ok(())
    }

    /// A short fingerprint of the plan (procedure, Fz0, step names, durations, loads, pressures,
    /// speeds), stored in checkpoints so a resume against a different plan is refused.
    pub fn fingerprint(&self) -> u64 {
        // FNV-1a: stable across builds and platforms, unlike `DefaultHasher`.
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for b in bytes {
                h ^= u64::from(*b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        // Quantised so that harmless float noise does not change it; loads, pressures and speeds
        // are in, so a checkpoint of another tyre (load index) or pressure set is refused.
        let q = |x: f64, k: f64| ((x * k).round() as i64).to_le_bytes();
        eat(self.procedure.as_bytes());
        eat(&q(self.fz0_n, 1.0));
        for s in &self.steps {
            eat(s.name.as_bytes());
            eat(&q(s.duration_s, 1000.0));
            let sp = s.trajectory.start();
            eat(&q(sp.fz_n, 1.0));
            eat(&q(sp.pressure_bar, 1000.0));
            eat(&q(sp.speed_mps, 1000.0));
        }
        h
    }
}

fn serde_json_like_kind(k: StepKind) -> String {
    match k {
        StepKind::Sweep => "sweep",
        StepKind::Hold => "hold",
        StepKind::Settle => "settle",
        StepKind::WarmUp => "warm_up",
        StepKind::FreeRollingRef => "free_rolling_ref",
        StepKind::PressureChange => "pressure_change",
        StepKind::TyreChange => "tyre_change",
    }
    .to_owned()
}
