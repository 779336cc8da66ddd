//! Expansion of a procedure document and the run's inputs into a [`Plan`].

use crate::file::{PressureSlot, ProcedureDoc, ProcedureError, SectionSpec, StepKindSpec, StepSpec};
use crate::load_index::fz0_n;
use crate::plan::{Plan, PlanStep, SectionInfo, StepKind};
use crate::primitives::{self as prim, Segment, StaticDragParams, StepSteerParams, WarmUpParams};
use crate::setpoint::{RigLimits, RigMode, Setpoint};
use crate::sweep::{ASYM_SATURATION_DEG, CamberCoupling, LoadCoupling, RateLaw, SlipAxis, SlipPath};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Which law variable-rate sweeps run under.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepStyle {
    /// As written: the thesis's variable-rate ("shark tooth") sweeps.
    #[default]
    Variable,
    /// Every variable-rate sweep becomes continually variable
    /// ([`RateLaw::continuous_from_variable`]); graph sweeps stay as they are.
    Continuous,
}

impl std::str::FromStr for SweepStyle {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "variable" => Ok(Self::Variable),
            "continuous" => Ok(Self::Continuous),
            other => Err(format!("expected `variable` or `continuous`, got `{other}`")),
        }
    }
}

/// What a run needs besides the procedure file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RunInputs {
    /// ETRTO load index of the tyre (drives Fz0).
    pub load_index: u32,
    /// The tyre's nominal load Fz0 \[N\] when given directly, replacing the load index's:
    /// tyres outside the ETRTO table (a race tyre's ~1 kN). The graph sweeps' absolute loads
    /// (written for the thesis's tyre) then scale by Fz0 / 6,759 N (load index 110's Fz0).
    #[serde(default)]
    pub fz0_n: Option<f64>,
    /// The three inflation pressures (low, mid, high) \[bar\].
    pub pressures_bar: [f64; 3],
    /// Nominal speed \[m/s\] (thesis: 16.6 m/s).
    pub nominal_speed_mps: f64,
    /// Variable or continually variable sweeps.
    pub sweeps: SweepStyle,
    /// Rig envelope and profile limits.
    pub limits: RigLimits,
}

impl Default for RunInputs {
    /// The thesis's tyre: LI 110, 2.1 / 2.6 / 3.3 bar, 16.6 m/s.
    fn default() -> Self {
        Self {
            load_index: 110,
            fz0_n: None,
            pressures_bar: [2.1, 2.6, 3.3],
            nominal_speed_mps: 16.6,
            sweeps: SweepStyle::Variable,
            limits: RigLimits::default(),
        }
    }
}

impl RunInputs {
    fn validate(&self) -> Result<(), ProcedureError> {
        if !self.pressures_bar.iter().all(|p| p.is_finite() && *p > 0.0) {
            return Err(ProcedureError::BadInput {
                key: "pressures_bar",
                message: format!("expected three positive pressures, got {:?}", self.pressures_bar),
            });
        }
        if let Some(f) = self.fz0_n
            && !(f.is_finite() && f > 0.0)
        {
            return Err(ProcedureError::BadInput {
                key: "fz0_n",
                message: format!("expected a positive load, got {f}"),
            });
        }
        if !(self.nominal_speed_mps.is_finite() && self.nominal_speed_mps > 0.0) {
            return Err(ProcedureError::BadInput {
                key: "nominal_speed_mps",
                message: format!("expected a positive speed, got {}", self.nominal_speed_mps),
            });
        }
        self.limits.validate().map_err(|message| ProcedureError::BadInput { key: "limits", message })
    }
}

/// Expand `doc` with `inputs` into a plan, checked against the rig envelope.
pub fn expand(doc: &ProcedureDoc, inputs: &RunInputs) -> Result<Plan, ProcedureError> {
    inputs.validate()?;
    let fz0 = match inputs.fz0_n {
        Some(f) => f,
        None => fz0_n(inputs.load_index)?,
    };
    let h = &doc.spec.procedure;
    let mut b = Builder {
        inputs: *inputs,
        fz0,
        steps: Vec::new(),
        sections: Vec::new(),
        cur: None,
        specimen: if h.count_first_mount { None } else { Some(h.specimen.clone()) },
        tyre_change_s: h.tyre_change_s,
        counters: HashMap::new(),
        repeats: HashMap::new(),
        data_index: 0,
    };
    b.doc(doc, None)?;
    let plan =
        Plan { procedure: h.name.clone(), title: h.title.clone(), fz0_n: fz0, sections: b.sections, steps: b.steps };
    plan.check_envelope(&inputs.limits)?;
    Ok(plan)
}

struct Builder {
    inputs: RunInputs,
    fz0: f64,
    steps: Vec<PlanStep>,
    sections: Vec<SectionInfo>,
    /// Where the rig is at the end of the last step (None before the first).
    cur: Option<Setpoint>,
    specimen: Option<String>,
    tyre_change_s: f64,
    /// Sweep numbers per config tag (`sw1`, `sw2`, … per procedure).
    counters: HashMap<String, u32>,
    /// Repeat numbers per identical sweep.
    repeats: HashMap<String, u32>,
    data_index: u32,
}

/// Context of one section instance.
struct Ctx<'a> {
    procedure: &'a str,
    tag: &'a str,
    section_index: usize,
    pressure_slot: Option<PressureSlot>,
    /// The section's absolute pressure (`pressure_bar` / `pressures_bar`), if it gives one.
    pressure_bar: Option<f64>,
    mode: RigMode,
    specimen: String,
    ref_s: f64,
}

impl Builder {
    fn doc(&mut self, doc: &ProcedureDoc, specimen_override: Option<&str>) -> Result<(), ProcedureError> {
        for (inc, sub) in &doc.includes {
            self.doc(sub, inc.specimen.as_deref().or(specimen_override))?;
        }
        let h = &doc.spec.procedure;
        for sec in &doc.spec.section {
            let s: &SectionSpec = sec.get_ref();
            let specimen = s
                .specimen
                .clone()
                .or_else(|| specimen_override.map(str::to_owned))
                .unwrap_or_else(|| h.specimen.clone());
            let slots: Vec<(Option<PressureSlot>, Option<f64>)> =
                match (&s.pressures, s.pressure, &s.pressures_bar, s.pressure_bar) {
                    (Some(ps), ..) => ps.iter().map(|p| (Some(*p), None)).collect(),
                    (None, Some(p), ..) => vec![(Some(p), None)],
                    (None, None, Some(bars), _) => bars.iter().map(|b| (None, Some(*b))).collect(),
                    (None, None, None, Some(b)) => vec![(None, Some(b))],
                    (None, None, None, None) => vec![(None, None)],
                };
            for (slot, bar) in slots {
                let name = match (slot, bar, s.pressures.is_some() || s.pressures_bar.is_some()) {
                    (Some(p), _, true) => {
                        format!("{}_{}bar", s.name, prim::fmt_num(self.inputs.pressures_bar[p.index()]))
                    }
                    (None, Some(b), true) => format!("{}_{}bar", s.name, prim::fmt_num(b)),
                    _ => s.name.clone(),
                };
                let specimen = match (s.specimen_per_pressure, slot) {
                    (true, Some(p)) => format!("{specimen}_{}", slot_name(p)),
                    _ => specimen.clone(),
                };
                self.mount(&specimen, &h.name);
                self.sections.push(SectionInfo { name, procedure: h.name.clone() });
                let ctx = Ctx {
                    procedure: &h.name,
                    tag: &h.config_tag,
                    section_index: self.sections.len() - 1,
                    pressure_slot: slot,
                    pressure_bar: bar,
                    mode: s.mode.unwrap_or(h.mode),
                    specimen: specimen.clone(),
                    ref_s: h.free_rolling_ref_s,
                };
                for st in &s.step {
                    self.step(&ctx, st.get_ref())?;
                }
            }
        }
        Ok(())
    }

    /// Insert a tyre change when the specimen changes.
    fn mount(&mut self, specimen: &str, procedure: &str) {
        if self.specimen.as_deref() == Some(specimen) {
            return;
        }
        self.specimen = Some(specimen.to_owned());
        self.sections.push(SectionInfo { name: format!("tyre_change_{specimen}"), procedure: procedure.to_owned() });
        let seg = prim::tyre_change(self.tyre_change_s, specimen);
        let index = self.steps.len();
        self.steps.push(PlanStep {
            index,
            name: seg.type_name.clone(),
            kind: StepKind::TyreChange,
            procedure: procedure.to_owned(),
            section_index: self.sections.len() - 1,
            sweep_index: None,
            duration_s: seg.duration_s(),
            trajectory: seg.trajectory,
            thermal_pause_after: false,
            restart_from: index,
            specimen: specimen.to_owned(),
        });
        // A freshly mounted tyre: rig parked, not rolling.
        self.cur = None;
    }

    fn push_raw(&mut self, ctx: &Ctx, seg: Segment, name: String, group: usize) {
        let index = self.steps.len();
        let sweep_index = seg.kind.is_data().then(|| {
            let i = self.data_index;
            self.data_index += 1;
            i
        });
        self.cur = Some(if seg.thermal_pause_after {
            prim::thermal_pause_setpoint(&seg.trajectory.end())
        } else {
            seg.trajectory.end()
        });
        self.steps.push(PlanStep {
            index,
            name,
            kind: seg.kind,
            procedure: ctx.procedure.to_owned(),
            section_index: ctx.section_index,
            sweep_index,
            duration_s: seg.duration_s(),
            trajectory: seg.trajectory,
            thermal_pause_after: seg.thermal_pause_after,
            restart_from: group,
            specimen: ctx.specimen.clone(),
        });
    }

    /// Push a data segment with its pressure change, settle and free-rolling reference.
    fn push(&mut self, ctx: &Ctx, seg: Segment) {
        let group = self.steps.len();
        let start = seg.trajectory.start();
        let lim = self.inputs.limits;
        let cur = self.cur.unwrap_or(Setpoint {
            mode: RigMode::FreeRolling,
            fz_n: lim.min_fz_n.max(0.1 * self.fz0),
            pressure_bar: start.pressure_bar,
            ..Setpoint::default()
        });
        let mut group = group;
        if (cur.pressure_bar - start.pressure_bar).abs() > 1e-9 {
            let pc = prim::pressure_change(cur, start.pressure_bar, lim.pressure_change_s);
            let name = pc.type_name.clone();
            self.push_raw(ctx, pc, name, group);
            // A completed pressure change is not repeated when the sweep after it restarts.
            group = self.steps.len();
        }
        let cur = self.cur.unwrap_or(cur);
        let longitudinal = seg.kind == StepKind::Sweep && start.mode == RigMode::Coupled;
        let target = if longitudinal {
            let mut t = start;
            t.mode = RigMode::FreeRolling;
            t
        } else {
            start
        };
        if !same(&cur, &target) {
            let s = prim::settle(cur, target, &lim);
            self.push_raw(ctx, s, "Settle".into(), group);
        }
        if longitudinal {
            let r = prim::free_rolling_ref(start, ctx.ref_s);
            self.push_raw(ctx, r, "FreeRollingRef".into(), group);
        }
        // Only data steps take a sweep number; a standstill keeps its plain name.
        let name = if seg.kind.is_data() { self.name(ctx.tag, &seg) } else { seg.type_name.clone() };
        self.push_raw(ctx, seg, name, group);
    }

    fn name(&mut self, tag: &str, seg: &Segment) -> String {
        let n = self.counters.entry(tag.to_owned()).or_insert(0);
        *n += 1;
        let n = *n;
        let t = &seg.trajectory;
        let d = t.duration_s();
        let key = format!("{tag}|{}|{:?}|{:?}|{:?}|{d:.3}", seg.type_name, t.start(), t.at(0.37 * d), t.at(0.71 * d));
        let r = self.repeats.entry(key).or_insert(0);
        *r += 1;
        format!("{tag}_sw{n}_{}_{}", seg.type_name, r)
    }

    fn base(&self, ctx: &Ctx, st: &StepSpec, slot: Option<PressureSlot>) -> Setpoint {
        // A step's own slot first, then the section's bar or slot, else the middle pressure.
        let pressure_bar = match (slot, ctx.pressure_bar) {
            (None, Some(bar)) => bar,
            _ => self.inputs.pressures_bar[slot.or(ctx.pressure_slot).unwrap_or(PressureSlot::Mid).index()],
        };
        Setpoint {
            mode: st.mode.unwrap_or(ctx.mode),
            pressure_bar,
            speed_mps: st.speed_mps.unwrap_or(self.inputs.nominal_speed_mps),
            fz_n: self.fz0,
            ..Setpoint::default()
        }
    }

    fn step(&mut self, ctx: &Ctx, st: &StepSpec) -> Result<(), ProcedureError> {
        let slots: Vec<Option<PressureSlot>> = match (&st.pressures, st.pressure) {
            (Some(ps), _) => ps.iter().copied().map(Some).collect(),
            (None, Some(p)) => vec![Some(p)],
            (None, None) => vec![None],
        };
        let loads: Vec<f64> = st
            .loads
            .clone()
            .or(st.load.map(|l| vec![l]))
            .unwrap_or_else(|| vec![1.0])
            .iter()
            .map(|f| f * self.fz0)
            .collect();
        let sas: Vec<f64> =
            st.slip_angles_deg.clone().or(st.slip_angle_deg.map(|a| vec![a])).unwrap_or_else(|| vec![0.0]);
        let cambers: Vec<f64> = st.cambers_deg.clone().or(st.camber_deg.map(|c| vec![c])).unwrap_or_else(|| vec![0.0]);
        let lim = self.inputs.limits;
        let repeat = st.repeat.unwrap_or(1);
        let mut segs: Vec<Segment> = Vec::new();
        let kind = st.kind.unwrap_or(StepKindSpec::Hold);
        for slot in slots {
            let base = self.base(ctx, st, slot);
            match kind {
                StepKindSpec::Sweep => {
                    for _ in 0..repeat {
                        for &sa in &sas {
                            for &c in &cambers {
                                self.sweeps(st, base, sa, c, &loads, &mut segs);
                            }
                        }
                    }
                }
                StepKindSpec::VerticalLoad => {
                    let rate = st.slip_rate_dps.unwrap_or(lim.max_slip_angle_rate_dps);
                    for _ in 0..repeat {
                        for &sa in &sas {
                            let mut b = base;
                            b.camber_deg = cambers[0];
                            segs.push(prim::vertical_load_sweep(
                                sa,
                                st.low_load.unwrap_or(0.2) * self.fz0,
                                st.high_load.unwrap_or(1.8) * self.fz0,
                                rate,
                                b,
                                &lim,
                            ));
                        }
                    }
                }
                StepKindSpec::OnCentre => {
                    for &sa in &sas {
                        let mut b = base;
                        b.camber_deg = cambers[0];
                        segs.push(prim::on_centre_holds(sa, &loads, st.hold_s.unwrap_or(10.0), b, &lim));
                    }
                }
                StepKindSpec::RollingRadius => {
                    let speeds = st.speeds_mps.clone().unwrap_or_else(|| vec![base.speed_mps]);
                    for v in speeds {
                        segs.push(prim::rolling_radius_steps(&loads, v, st.hold_s.unwrap_or(8.0), base, &lim));
                    }
                }
                StepKindSpec::StepSteer => {
                    let p = StepSteerParams {
                        roll_speed_mps: st.roll_speed_mps.unwrap_or(1.0),
                        pre_roll_s: st.pre_roll_s.unwrap_or(2.0),
                        distance_m: st.distance_m.unwrap_or(1.5),
                        steer_rate_dps: st.steer_rate_dps.unwrap_or(10.0),
                    };
                    for &fz in &loads {
                        for &sa in &sas {
                            segs.push(prim::step_steer(sa, fz, &p, base, &lim));
                        }
                    }
                }
                StepKindSpec::StaticLong => {
                    let p = StaticDragParams {
                        displacement_m: st.displacement_m.unwrap_or(0.1),
                        belt_speed_mps: st.belt_speed_mps.unwrap_or(0.025),
                        roll_speed_mps: st.roll_speed_mps.unwrap_or(1.0),
                        roll_s: st.roll_s.unwrap_or(3.0),
                    };
                    for _ in 0..repeat {
                        for &fz in &loads {
                            segs.push(prim::static_drag(fz, &p, base, &lim));
                        }
                    }
                }
                StepKindSpec::WarmUp => {
                    let p = WarmUpParams {
                        blocks: st.blocks.unwrap_or(2),
                        peak_deg: st.peak_deg.unwrap_or(8.0),
                        rate_dps: st.rate_dps.unwrap_or(4.0),
                        roll_s: st.roll_s.unwrap_or(20.0),
                    };
                    let mut b = base;
                    b.mode = RigMode::FreeRolling;
                    segs.extend(prim::warm_up(&p, &loads, b));
                }
                StepKindSpec::GraphSweeps => {
                    let block = st.block.unwrap_or(prim::GraphBlock::FreeRolling);
                    let mut b = base;
                    // Graph sweeps are identical for every tyre: the nominal 16.6 m/s unless
                    // the file says otherwise, whatever the run's nominal speed.
                    b.speed_mps = st.speed_mps.unwrap_or(16.6);
                    // Written for the thesis's tyre class; a tyre given by its Fz0 (another
                    // class) gets the same load factors of its own Fz0.
                    let load_scale = match self.inputs.fz0_n {
                        Some(f) => f / fz0_n(crate::load_index::THESIS_LOAD_INDEX)?,
                        None => 1.0,
                    };
                    segs.extend(prim::graph_sweep_block_scaled(block, self.inputs.pressures_bar, b, load_scale));
                }
                StepKindSpec::Standstill => {
                    // Belt stopped, wheel loaded, zero slip: the settle before it brings the
                    // belt to rest at the rig's acceleration and ramps the load.
                    let mut sp = base;
                    sp.mode = RigMode::FreeRolling;
                    sp.speed_mps = 0.0;
                    sp.fz_n = st.fz_n.unwrap_or(loads[0]);
                    sp.camber_deg = cambers[0];
                    let k = crate::sweep::Keyframes::start(sp).hold(st.hold_s.unwrap_or(0.0));
                    segs.push(Segment {
                        kind: StepKind::Settle,
                        type_name: st.label.clone().unwrap_or_else(|| "Standstill".into()),
                        trajectory: crate::sweep::Trajectory::Keyframes(k),
                        thermal_pause_after: false,
                    });
                }
                StepKindSpec::Hold => {
                    let mut sp = base;
                    sp.fz_n = st.fz_n.unwrap_or(loads[0]);
                    sp.camber_deg = cambers[0];
                    sp.slip_angle_deg = sas[0];
                    let k = crate::sweep::Keyframes::start(sp).hold(st.hold_s.unwrap_or(0.0));
                    segs.push(Segment {
                        kind: StepKind::Hold,
                        type_name: st.label.clone().unwrap_or_else(|| "Hold".into()),
                        trajectory: crate::sweep::Trajectory::Keyframes(k),
                        thermal_pause_after: false,
                    });
                }
            }
        }
        for mut s in segs {
            if let (Some(label), true) = (&st.label, !matches!(kind, StepKindSpec::Hold | StepKindSpec::Standstill)) {
                s.type_name = format!("{label}_{}", s.type_name);
            }
            if let Some(tp) = st.thermal_pause {
                s.thermal_pause_after = tp;
            }
            self.push(ctx, s);
        }
        Ok(())
    }

    fn sweeps(&self, st: &StepSpec, base: Setpoint, sa: f64, camber: f64, loads_n: &[f64], out: &mut Vec<Segment>) {
        let is_pct = st.peak_pct.is_some() || st.waypoints_pct.is_some();
        let (axis, k) = if is_pct { (SlipAxis::SlipRatio, 0.01) } else { (SlipAxis::SlipAngle, 1.0) };
        let (rate, lo, hi, th, peak, wps) = if is_pct {
            (st.rate_pct_ps, st.low_rate_pct_ps, st.high_rate_pct_ps, st.threshold_pct, st.peak_pct, &st.waypoints_pct)
        } else {
            (st.rate_dps, st.low_rate_dps, st.high_rate_dps, st.threshold_deg, st.peak_deg, &st.waypoints_deg)
        };
        let law = match (rate, lo, hi, th) {
            (Some(r), ..) => RateLaw::Constant { rate: r * k },
            (None, Some(lo), Some(hi), Some(th)) => match self.inputs.sweeps {
                SweepStyle::Variable => RateLaw::Variable { low_rate: lo * k, high_rate: hi * k, threshold: th * k },
                SweepStyle::Continuous => RateLaw::continuous_from_variable(lo * k, hi * k, th * k, axis),
            },
            // Validation guarantees one of the two forms.
            _ => RateLaw::Constant { rate: 1.0 },
        };
        let path = match (peak, wps) {
            (_, Some(w)) => SlipPath::new(w.iter().map(|x| x * k).collect(), law),
            (Some(p), None) => SlipPath::full_cycle(p * k, law),
            (None, None) => SlipPath::full_cycle(0.0, law),
        };
        let mut b = base;
        b.mode = st.mode.unwrap_or(if is_pct { RigMode::Coupled } else { base.mode });
        if !is_pct && b.mode == RigMode::Coupled {
            b.mode = RigMode::FreeRolling;
        }
        b.slip_angle_deg = if is_pct { sa } else { 0.0 };
        let sat = st.saturation_deg.unwrap_or(ASYM_SATURATION_DEG);
        let camber_c = match st.camber_coupling_deg {
            Some(g) => CamberCoupling::Coupled { gain_deg: g, saturation_deg: sat },
            None => CamberCoupling::Constant { camber_deg: camber },
        };
        let asym = st.asym.map(|a| a.factors()).or(st.asym_factors.map(|[n, p]| (n, p)));
        let loads: Vec<LoadCoupling> = if let Some((n, p)) = asym {
            let mut c = LoadCoupling::asymmetric(self.fz0, n, p, st.adverse.unwrap_or(false));
            if let LoadCoupling::Asymmetric { saturation_deg, .. } = &mut c {
                *saturation_deg = sat;
            }
            vec![c]
        } else if let Some(f) = st.fz_n {
            vec![LoadCoupling::Constant { fz_n: f }]
        } else {
            loads_n.iter().map(|&fz_n| LoadCoupling::Constant { fz_n }).collect()
        };
        for load in loads {
            let mut bb = b;
            bb.fz_n = load.at(0.0);
            bb.camber_deg = camber_c.at(0.0);
            let mut seg = prim::slip_sweep(axis, path.clone(), bb, load, camber_c);
            if let Some(tag) = asym_tag(st) {
                seg.type_name = format!("{}_{}", seg.type_name, tag);
            }
            out.push(seg);
        }
    }
}

fn slot_name(p: PressureSlot) -> &'static str {
    match p {
        PressureSlot::Low => "low",
        PressureSlot::Mid => "mid",
        PressureSlot::High => "high",
    }
}

/// Suffix naming the asymmetric-load case (`AsymMedium`, `AsymHighAdverse`) so different load
/// cases do not look like repeats of one another.
fn asym_tag(st: &StepSpec) -> Option<String> {
    let base = match (st.asym, st.asym_factors) {
        (Some(a), _) => format!("Asym{a:?}"),
        (None, Some([n, p])) => format!("Asym{}-{}", prim::fmt_num(n), prim::fmt_num(p)),
        (None, None) => return None,
    };
    Some(if st.adverse.unwrap_or(false) { format!("{base}Adverse") } else { base })
}

fn same(a: &Setpoint, b: &Setpoint) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() < 1e-9;
    a.mode == b.mode
        && close(a.slip_angle_deg, b.slip_angle_deg)
        && close(a.slip_ratio, b.slip_ratio)
        && close(a.fz_n, b.fz_n)
        && close(a.camber_deg, b.camber_deg)
        && close(a.pressure_bar, b.pressure_bar)
        && close(a.speed_mps, b.speed_mps)
        && close(a.belt_displacement_m, b.belt_displacement_m)
}
