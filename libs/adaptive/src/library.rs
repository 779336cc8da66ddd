//! The candidate library: the sweeps of an expanded procedure that the plan may choose among,
//! cut out of it, and the fixed plan that remains, with a slot where each run of candidates was.
//!
//! What stays fixed is what the thesis needs whatever the tyre teaches: warm-up, the heating
//! sweep, graph sweeps first and last, on-centre and rolling radius, step-steer, static
//! longitudinal, tyre changes. Every other sweep (force & moment, vertical-load, pure
//! longitudinal, combined, inflation-pressure, extreme sweeps) is a candidate, with the
//! pressure changes around them: the plan makes its own pressure changes.

use procedure::plan::PlanStep;
use procedure::primitives::{free_rolling_ref, pressure_change, settle, thermal_pause_setpoint};
use procedure::sweep::{SlipAxis, Trajectory};
use procedure::{PauseModel, Plan, RigLimits, RigMode, Setpoint, StepKind};
use serde::{Deserialize, Serialize};

use crate::config::AdaptiveConfig;
use crate::extent::Extent;
use crate::model::{ModelView, Target};

/// Sections whose sweeps always run (name prefixes, as the procedure files name them).
pub const FIXED_SECTIONS: [&str; 3] = ["warmup", "heating_sweep", "graph_sweep"];

/// What a candidate measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CandidateKind {
    /// Slip angle (or a load sweep at a held slip angle), free rolling: FY, MZ and MX.
    Lateral,
    /// Slip ratio at (close to) zero slip angle.
    Longitudinal,
    /// Slip ratio at a held slip angle.
    Combined,
}

impl CandidateKind {
    /// The targets its points inform.
    pub fn targets(self) -> &'static [Target] {
        match self {
            CandidateKind::Lateral => &[Target::FyPure, Target::MzPure, Target::MxPure],
            CandidateKind::Longitudinal => &[Target::FxPure],
            CandidateKind::Combined => &[Target::FxCombined, Target::FyCombined],
        }
    }
}

/// One sweep the plan may run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Position in [`Library::candidates`].
    pub id: usize,
    /// The sweep's thesis-style name.
    pub name: String,
    /// Its section in the procedure.
    pub section: String,
    /// The slot it belongs to.
    pub slot: usize,
    /// What it measures.
    pub kind: CandidateKind,
    /// Hard on the tyre (high slip angle or load): run after every other useful candidate.
    pub severe: bool,
    /// Its inflation pressure \[bar\].
    pub pressure_bar: f64,
    /// Free-rolling reference hold before it \[s\] (longitudinal sweeps), 0 if none.
    pub ref_s: f64,
    /// Predicted cool-down after it \[s\] (the sequencer's pause model).
    pub pause_s: f64,
    /// The sweep step as the procedure expanded it.
    pub sweep: PlanStep,
    /// Planned points (setpoints spread evenly over the sweep) for the linearisation.
    pub points: Vec<Setpoint>,
    /// How far it reaches into the envelope (its planned and check points).
    #[serde(default)]
    pub extent: Extent,
}

impl Candidate {
    /// The steps that run it from where the rig is (`from`): a pressure change if the pressure
    /// differs, a settle, the free-rolling reference, the sweep. `index` and `restart_from` are
    /// relative to the first returned step (the sequencer offsets them when it inserts them).
    pub fn group(&self, from: Setpoint, limits: &RigLimits) -> Vec<PlanStep> {
        let mut out = Vec::new();
        let mut cur = from;
        let mut group = 0;
        let mk = |index: usize, restart_from: usize, seg: procedure::primitives::Segment, name: String| PlanStep {
            index,
            name,
            kind: seg.kind,
            procedure: self.sweep.procedure.clone(),
            section_index: self.sweep.section_index,
            sweep_index: None,
            duration_s: seg.duration_s(),
            trajectory: seg.trajectory,
            thermal_pause_after: seg.thermal_pause_after,
            restart_from,
            specimen: self.sweep.specimen.clone(),
        };
        if (cur.pressure_bar - self.pressure_bar).abs() > 1e-9 {
            let pc = pressure_change(cur, self.pressure_bar, limits.pressure_change_s);
            cur = pc.trajectory.end();
            let name = pc.type_name.clone();
            out.push(mk(0, 0, pc, name));
            // A completed pressure change is not repeated when the sweep after it restarts.
            group = 1;
        }
        let start = self.sweep.trajectory.start();
        let mut target = start;
        if self.ref_s > 0.0 {
            target.mode = RigMode::FreeRolling;
        }
        let s = settle(cur, target, limits);
        out.push(mk(out.len(), group, s, "Settle".into()));
        if self.ref_s > 0.0 {
            let r = free_rolling_ref(start, self.ref_s);
            out.push(mk(out.len(), group, r, "FreeRollingRef".into()));
        }
        let mut sweep = self.sweep.clone();
        sweep.index = out.len();
        sweep.restart_from = group;
        out.push(sweep);
        out
    }

    /// Predicted rig time from `from` to the end of its cool-down \[s\]: pressure change,
    /// settle, reference hold, sweep, and the pause model's cool-down scaled by `pause_scale`
    /// (how the pauses so far compared with the model).
    pub fn cost_s(&self, from: Setpoint, limits: &RigLimits, pause_scale: f64) -> f64 {
        let steps: f64 = self.group(from, limits).iter().map(|s| s.duration_s).sum();
        steps + self.pause_s * pause_scale
    }

    /// Sliding energy of the sweep as `view` predicts it \[J\] (midpoint rule, steps of at most
    /// 0.5 s); `None` without a model.
    pub fn sliding_energy_j(&self, view: &dyn ModelView) -> Option<f64> {
        let d = self.sweep.duration_s.max(0.0);
        let n = (d / 0.5).ceil().max(1.0) as usize;
        let dt = d / n as f64;
        (0..n).try_fold(0.0, |e, j| {
            let sp = self.sweep.trajectory.at((j as f64 + 0.5) * dt);
            view.sliding_power_w(&sp).map(|p| e + p * dt)
        })
    }

    /// Where the rig is after it and its cool-down.
    pub fn end(&self) -> Setpoint {
        let end = self.sweep.trajectory.end();
        if self.sweep.thermal_pause_after { thermal_pause_setpoint(&end) } else { end }
    }
}

/// A place in the fixed plan where chosen candidates go.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Slot {
    /// Position in [`Library::slots`].
    pub id: usize,
    /// Index in the fixed plan of the step the chosen sweeps run before.
    pub at: usize,
    /// Its candidates (ids), in the procedure's order.
    pub candidates: Vec<usize>,
    /// The predicted cost of running all of them as the procedure does \[s\].
    pub full_cost_s: f64,
}

/// The candidates of a procedure and the fixed plan around them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Library {
    /// The plan without the candidates (and the pressure changes between them).
    pub fixed: Plan,
    /// Slots, in plan order.
    pub slots: Vec<Slot>,
    /// Every candidate.
    pub candidates: Vec<Candidate>,
    /// The envelope and profile limits the groups are built with.
    pub limits: RigLimits,
}

/// A plan without candidates.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("procedure `{0}` has no sweep an adaptive plan could choose (every sweep is in a fixed section)")]
pub struct NoCandidates(pub String);

fn is_candidate(plan: &Plan, st: &PlanStep) -> bool {
    let section = plan.sections.get(st.section_index).map_or("", |s| s.name.as_str());
    st.kind == StepKind::Sweep
        && !st.name.contains("GraphSweep")
        && !FIXED_SECTIONS.iter().any(|p| section.starts_with(p))
}

fn kind_of(traj: &Trajectory) -> CandidateKind {
    match traj {
        Trajectory::Sweep(s) if s.axis == SlipAxis::SlipRatio => {
            if s.base.slip_angle_deg.abs() < 0.5 {
                CandidateKind::Longitudinal
            } else {
                CandidateKind::Combined
            }
        }
        _ => CandidateKind::Lateral,
    }
}

impl Library {
    /// Cuts the candidates out of `plan`. `pause` predicts each one's cool-down.
    pub fn from_plan(
        plan: &Plan,
        pause: &PauseModel,
        limits: &RigLimits,
        cfg: &AdaptiveConfig,
    ) -> Result<Self, NoCandidates> {
        let steps = &plan.steps;
        let n = steps.len();
        // Candidate sweeps and their groups (settle, free-rolling reference).
        let mut removed = vec![false; n];
        let mut cand_at: Vec<usize> = Vec::new();
        for (i, st) in steps.iter().enumerate() {
            if is_candidate(plan, st) {
                for r in removed.iter_mut().take(i + 1).skip(st.restart_from.min(i)) {
                    *r = true;
                }
                cand_at.push(i);
            }
        }
        if cand_at.is_empty() {
            return Err(NoCandidates(plan.procedure.clone()));
        }
        // Pressure changes next to a candidate go too: the plan changes pressure itself, and a
        // settle moves the pressure when a slot closes.
        for i in 0..n {
            if steps[i].kind != StepKind::PressureChange {
                continue;
            }
            let next = (i + 1..n).find(|&j| steps[j].kind != StepKind::PressureChange);
            let prev = (0..i).rev().find(|&j| steps[j].kind != StepKind::PressureChange);
            if next.is_some_and(|j| removed[j]) || prev.is_some_and(|j| removed[j]) {
                removed[i] = true;
            }
        }
        // The fixed plan, renumbered; a slot where each run of removed steps was.
        let mut fixed_steps: Vec<PlanStep> = Vec::new();
        let mut new_index = vec![usize::MAX; n];
        let mut slots: Vec<Slot> = Vec::new();
        let mut candidates: Vec<Candidate> = Vec::new();
        let mut in_run = false;
        for (i, st) in steps.iter().enumerate() {
            if removed[i] {
                if !in_run {
                    slots.push(Slot {
                        id: slots.len(),
                        at: fixed_steps.len(),
                        candidates: Vec::new(),
                        full_cost_s: 0.0,
                    });
                    in_run = true;
                }
                if cand_at.contains(&i) {
                    let slot = slots.len() - 1;
                    let c = candidate(plan, i, candidates.len(), slot, pause, cfg);
                    slots[slot].full_cost_s +=
                        steps[st.restart_from.min(i)..=i].iter().map(|s| s.duration_s).sum::<f64>() + c.pause_s;
                    slots[slot].candidates.push(c.id);
                    candidates.push(c);
                }
                continue;
            }
            in_run = false;
            new_index[i] = fixed_steps.len();
            fixed_steps.push(st.clone());
        }
        let mut data = 0u32;
        for (k, st) in fixed_steps.iter_mut().enumerate() {
            st.index = k;
            st.restart_from = new_index.get(st.restart_from).copied().filter(|&x| x != usize::MAX).unwrap_or(k).min(k);
            st.sweep_index = st.kind.is_data().then(|| {
                data += 1;
                data - 1
            });
        }
        // Slots at the very end run before nothing: `at` = the fixed plan's length.
        let fixed = Plan { steps: fixed_steps, ..plan.clone() };
        Ok(Library { fixed, slots, candidates, limits: *limits })
    }

    /// Candidate by id.
    pub fn candidate(&self, id: usize) -> Option<&Candidate> {
        self.candidates.get(id)
    }

    /// The slot at fixed-plan index `at`.
    pub fn slot_at(&self, at: usize) -> Option<&Slot> {
        self.slots.iter().find(|s| s.at == at)
    }
}

fn candidate(plan: &Plan, i: usize, id: usize, slot: usize, pause: &PauseModel, cfg: &AdaptiveConfig) -> Candidate {
    let st = &plan.steps[i];
    let ref_s: f64 = plan.steps[st.restart_from.min(i)..i]
        .iter()
        .filter(|s| s.kind == StepKind::FreeRollingRef)
        .map(|s| s.duration_s)
        .sum();
    let d = st.duration_s;
    let k = cfg.points_per_sweep.max(2);
    let points: Vec<Setpoint> = (0..k).map(|j| st.trajectory.at(d * (j as f64 + 0.5) / k as f64)).collect();
    let mut reach = st.trajectory.check_points();
    reach.extend_from_slice(&points);
    // A sweep has at least its planned points (k ≥ 2), so it has an extent.
    let extent = Extent::of(&reach).unwrap_or_default();
    let severe = extent.slip_angle_abs_max_deg >= cfg.severe_slip_angle_deg - 1e-9
        || extent.fz_max_n >= cfg.severe_load_factor * plan.fz0_n - 1e-6;
    Candidate {
        id,
        name: st.name.clone(),
        section: plan.sections.get(st.section_index).map(|s| s.name.clone()).unwrap_or_default(),
        slot,
        kind: kind_of(&st.trajectory),
        severe,
        pressure_bar: st.trajectory.start().pressure_bar,
        ref_s,
        pause_s: pause.pause_after_s(st),
        sweep: st.clone(),
        points,
        extent,
    }
}
