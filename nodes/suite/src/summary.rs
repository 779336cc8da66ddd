//! The run summary: where the rig time went, against the thesis's §11 table.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Rig time of one (sub-)procedure.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ProcedureTimes {
    pub name: String,
    /// Rig time spent in it (sweeps, holds, settling, thermal pauses; not tyre changes) [s].
    pub rig_time_s: f64,
    /// Time in data steps (sweeps, holds, warm-up) [s].
    pub sweep_time_s: f64,
    /// Time waiting on the thermal gate [s].
    pub thermal_pause_s: f64,
    /// Data steps run.
    pub sweeps: u32,
    /// Thermal pauses released by the time-out (the next sweep started hot).
    pub timeouts: u32,
    /// Rig time by section [s].
    pub sections: BTreeMap<String, f64>,
}

/// An alarm raised during the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Alarm {
    /// `WARN` or `ERROR`.
    pub level: String,
    /// Which check: `thermal_timeout`, `thermal_sensor`, `envelope`, `load_rating`, `wear`, …
    pub check: String,
    pub message: String,
    pub rig_time_s: f64,
}

/// Everything a run reports.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// The procedure file's name (`gs2mf`, `square_matrix`, …).
    pub procedure: String,
    /// The whole run including tyre changes [s].
    pub total_rig_time_s: f64,
    /// Tyre specimens used.
    pub tyres_used: u32,
    /// Per (sub-)procedure, in run order.
    pub procedures: Vec<ProcedureTimes>,
    /// Tyre changes and their rig time [s].
    pub tyre_changes: u32,
    pub tyre_change_time_s: f64,
    pub alarms: Vec<Alarm>,
    /// The procedure reached its end.
    pub completed: bool,
    /// Simulator truth: tread worn per specimen [mm] (virtual rig only).
    pub wear_mm_true: Vec<f64>,
    /// Tread worn as the online monitor measured it from DSTWOWHC, per specimen [mm].
    pub wear_mm_measured: Vec<f64>,
    /// Data steps in the whole run.
    pub sweeps: u32,
    /// Thermal time-outs in the whole run.
    pub timeouts: u32,
    /// Highest TRDTEMPC seen at a sweep's start and during sweeps [°C].
    pub max_sweep_start_temp_c: f64,
    pub max_temp_c: f64,
    /// The adaptive plan's decisions, in order (`--plan adaptive`; empty otherwise).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub adaptive: Vec<AdaptiveChoice>,
}

/// One decision of the adaptive plan, as the run summary reports it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveChoice {
    /// Rig time of the decision [s].
    #[serde(with = "adaptive::nan_as_null")]
    pub rig_time_s: f64,
    /// The slot.
    pub slot: usize,
    /// The chosen sweep; empty when the slot closed.
    pub sweep: String,
    /// Predicted value, (% of peak)², and cost [s].
    #[serde(with = "adaptive::nan_as_null")]
    pub value: f64,
    #[serde(with = "adaptive::nan_as_null")]
    pub cost_s: f64,
    /// Predicted tread it wears \[mm\] (0 when closing, or in a log from before wear counted).
    #[serde(default)]
    pub wear_mm: f64,
    /// The wear rate that prediction used \[mm/MJ\]: the configured one, or weighed with the
    /// monitor's measurement (0 when closing, or in a log from before it was recorded).
    #[serde(default)]
    pub wear_rate_mm_per_mj: f64,
    /// Predicted error before and after it, and the slot's target, % of peak.
    #[serde(with = "adaptive::nan_as_null")]
    pub error_pct: f64,
    #[serde(with = "adaptive::nan_as_null")]
    pub error_after_pct: f64,
    #[serde(with = "adaptive::nan_as_null")]
    pub target_pct: f64,
    /// Why.
    pub reason: String,
}

/// The thesis's §11 rig-time table, for comparison: (row, seconds).
pub fn thesis_rig_times(procedure: &str) -> Vec<(&'static str, f64)> {
    match procedure {
        "gs2mf" => vec![
            ("gs2mf_freerolling", 4080.0),
            ("gs2mf_brkdrv", 2875.0),
            ("gs2mf_staticlong", 877.0),
            ("tyre changes (2 x 900 s)", 1800.0),
            ("total", 9632.0),
        ],
        "square_matrix" => vec![("3 pressures", 26850.0), ("tyre changes (10 x 900 s)", 9000.0), ("total", 35850.0)],
        "gs2mf_freerolling" => vec![("gs2mf_freerolling", 4080.0)],
        "gs2mf_brkdrv" => vec![("gs2mf_brkdrv", 2875.0)],
        "gs2mf_staticlong" => vec![("gs2mf_staticlong", 877.0)],
        _ => vec![],
    }
}

impl RunSummary {
    /// The summary as a table, with the thesis's figures beside ours where it has them.
    pub fn table(&self) -> String {
        let thesis: BTreeMap<&str, f64> = thesis_rig_times(&self.procedure).into_iter().collect();
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{:<28} {:>11} {:>10} {:>11} {:>7} {:>8} {:>11}",
            "procedure", "rig time s", "sweeps s", "pauses s", "sweeps", "timeouts", "thesis s"
        );
        for p in &self.procedures {
            let th = thesis.get(p.name.as_str()).map_or("-".to_owned(), |v| format!("{v:.0}"));
            let _ = writeln!(
                s,
                "{:<28} {:>11.0} {:>10.0} {:>11.0} {:>7} {:>8} {:>11}",
                p.name, p.rig_time_s, p.sweep_time_s, p.thermal_pause_s, p.sweeps, p.timeouts, th
            );
        }
        let tc_key = thesis.keys().find(|k| k.starts_with("tyre changes")).copied();
        let _ = writeln!(
            s,
            "{:<28} {:>11.0} {:>10} {:>11} {:>7} {:>8} {:>11}",
            format!("tyre changes ({})", self.tyre_changes),
            self.tyre_change_time_s,
            "",
            "",
            "",
            "",
            tc_key.and_then(|k| thesis.get(k)).map_or("-".to_owned(), |v| format!("{v:.0}"))
        );
        let _ = writeln!(
            s,
            "{:<28} {:>11.0} {:>10} {:>11} {:>7} {:>8} {:>11}",
            format!("total ({} tyres)", self.tyres_used),
            self.total_rig_time_s,
            "",
            "",
            self.sweeps,
            self.timeouts,
            thesis.get("total").map_or("-".to_owned(), |v| format!("{v:.0}"))
        );
        s
    }
}

/// Builds a [`RunSummary`] from what the cores report, sample by sample.
#[derive(Debug, Default)]
pub(crate) struct SummaryBuilder {
    pub summary: RunSummary,
    current: Option<(String, String)>, // (procedure, section)
    in_tyre_change: bool,
}

impl SummaryBuilder {
    pub fn new(procedure: &str) -> Self {
        Self { summary: RunSummary { procedure: procedure.to_owned(), ..Default::default() }, ..Default::default() }
    }

    pub(crate) fn entry(&mut self, name: &str) -> &mut ProcedureTimes {
        if let Some(i) = self.summary.procedures.iter().position(|p| p.name == name) {
            return &mut self.summary.procedures[i];
        }
        self.summary.procedures.push(ProcedureTimes { name: name.to_owned(), ..Default::default() });
        self.summary.procedures.last_mut().expect("just pushed")
    }

    /// The procedure state as published (its phase says where the time goes).
    pub fn on_state(&mut self, st: &tyre_msgs::ProcedureState) {
        self.in_tyre_change = st.phase == tyre_msgs::ProcedureState::PHASE_TYRE_CHANGE;
        if !st.procedure.is_empty() {
            self.current = Some((st.procedure.clone(), st.section.clone()));
        }
    }

    /// `dt_s` of rig time passed while running.
    pub fn add_time(&mut self, dt_s: f64) {
        self.summary.total_rig_time_s += dt_s;
        if self.in_tyre_change {
            self.summary.tyre_change_time_s += dt_s;
        } else if let Some((p, sec)) = self.current.clone() {
            let e = self.entry(&p);
            e.rig_time_s += dt_s;
            *e.sections.entry(sec).or_default() += dt_s;
        }
    }

    pub fn on_event(&mut self, ev: &sequencer::core::SequencerEvent) {
        use sequencer::core::SequencerEvent as E;
        match ev {
            E::SweepStarted { procedure, .. } => {
                self.entry(procedure).sweeps += 1;
                self.summary.sweeps += 1;
            }
            E::SweepEnded { duration_s, .. } => {
                if let Some((p, _)) = self.current.clone() {
                    self.entry(&p).sweep_time_s += duration_s;
                }
            }
            E::ThermalPauseEnded { duration_s, timed_out, .. } => {
                if let Some((p, _)) = self.current.clone() {
                    let e = self.entry(&p);
                    e.thermal_pause_s += duration_s;
                    if *timed_out {
                        e.timeouts += 1;
                    }
                }
                if *timed_out {
                    self.summary.timeouts += 1;
                }
            }
            E::TyreChange { .. } => self.summary.tyre_changes += 1,
            E::SweepChosen {
                slot,
                name,
                value,
                cost_s,
                wear_mm,
                wear_rate_mm_per_mj,
                error_pct,
                error_after_pct,
                target_pct,
                reason,
            } => {
                self.summary.adaptive.push(AdaptiveChoice {
                    rig_time_s: self.summary.total_rig_time_s,
                    slot: *slot,
                    sweep: name.clone(),
                    value: *value,
                    cost_s: *cost_s,
                    wear_mm: *wear_mm,
                    wear_rate_mm_per_mj: *wear_rate_mm_per_mj,
                    error_pct: *error_pct,
                    error_after_pct: *error_after_pct,
                    target_pct: *target_pct,
                    reason: reason.clone(),
                });
            }
            E::SlotClosed { slot, error_pct, reason, .. } => self.summary.adaptive.push(AdaptiveChoice {
                rig_time_s: self.summary.total_rig_time_s,
                slot: *slot,
                error_pct: *error_pct,
                error_after_pct: *error_pct,
                target_pct: f64::NAN,
                reason: reason.clone(),
                ..AdaptiveChoice::default()
            }),
            E::Completed { .. } => self.summary.completed = true,
            _ => {}
        }
    }

    pub fn alarm(&mut self, level: &str, check: &str, message: String, rig_time_s: f64) {
        self.summary.alarms.push(Alarm { level: level.to_owned(), check: check.to_owned(), message, rig_time_s });
    }
}

/// Why a log could not be summarised.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct LogSummaryError(pub String);

/// The measured wear of each specimen from a log: the last finite `wear_mm` of the quality
/// reports published while it was on the rig (specimens are separated by the starts of tyre
/// changes). A specimen with no finite figure (no wear hold measured yet) is left out, and so
/// is everything when the log has no quality reports (the monitor did not run).
fn wear_by_specimen(reports: &[(u64, tyre_msgs::QualityReport)], tyre_changes_at_s: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    let mut specimen = 0;
    let mut last: Option<f64> = None;
    for (_, r) in reports {
        let t = r.header.stamp.as_secs_f64();
        while specimen < tyre_changes_at_s.len() && t >= tyre_changes_at_s[specimen] {
            out.extend(last.take());
            specimen += 1;
        }
        if r.wear_mm.is_finite() {
            last = Some(r.wear_mm);
        }
    }
    out.extend(last);
    out
}

/// Summarises a recorded run from its `procedure/state`, `thermal/state`, `/diagnostics` and
/// `quality/report` topics alone, so it works for any log: a DDS run, a headless one, a real rig's.
/// Resolution is the state's publishing period (on change, at least 2 Hz).
pub fn summary_from_log(log: &mcaplog::LogReader, namespace: &str) -> Result<RunSummary, LogSummaryError> {
    use tyre_msgs::{ProcedureState as PS, QualityReport, ThermalState as TS, diagnostic_msgs::DiagnosticArray};
    let ns = namespace.trim_end_matches('/');
    let err = |e: mcaplog::LogError| LogSummaryError(e.to_string());
    let states = log.typed::<PS>(&format!("{ns}/{}", tyre_msgs::topics::PROCEDURE_STATE)).map_err(err)?;
    let thermal = log.typed::<TS>(&format!("{ns}/{}", tyre_msgs::topics::THERMAL_STATE)).map_err(err)?;
    let diags = log.typed::<DiagnosticArray>(tyre_msgs::topics::DIAGNOSTICS).map_err(err)?;
    let reports = log.typed::<QualityReport>(&format!("{ns}/{}", tyre_msgs::topics::QUALITY_REPORT)).map_err(err)?;
    let mut tyre_changes_at_s = Vec::new();
    let mut b =
        SummaryBuilder::new(log.metadata().get("procedure").and_then(|m| m.get("name")).map_or("", |s| s.as_str()));
    let mut prev: Option<&PS> = None;
    let mut seen_sweeps = std::collections::BTreeSet::new();
    for (_, st) in &states {
        if let Some(p) = prev {
            let dt = st.header.stamp.as_secs_f64() - p.header.stamp.as_secs_f64();
            b.on_state(p);
            if dt > 0.0 && p.phase != PS::PHASE_IDLE && p.phase != PS::PHASE_COMPLETE {
                b.add_time(dt);
                let name = p.procedure.clone();
                if p.phase == PS::PHASE_THERMAL_PAUSE {
                    b.entry(&name).thermal_pause_s += dt;
                } else if p.phase == PS::PHASE_SWEEP {
                    b.entry(&name).sweep_time_s += dt;
                }
            }
            if st.phase == PS::PHASE_TYRE_CHANGE && p.phase != PS::PHASE_TYRE_CHANGE {
                b.summary.tyre_changes += 1;
                tyre_changes_at_s.push(st.header.stamp.as_secs_f64());
            }
        } else if st.phase == PS::PHASE_TYRE_CHANGE {
            b.summary.tyre_changes += 1;
        }
        if st.phase == PS::PHASE_SWEEP && seen_sweeps.insert((st.procedure.clone(), st.sweep_index)) {
            b.entry(&st.procedure.clone()).sweeps += 1;
            b.summary.sweeps += 1;
        }
        if b.summary.procedure.is_empty() && !st.procedure.is_empty() {
            b.summary.procedure = st.procedure.clone();
        }
        prev = Some(st);
    }
    if let Some(last) = prev {
        b.summary.completed = last.phase == PS::PHASE_COMPLETE;
    }
    let mut was_timed_out = false;
    for (_, th) in &thermal {
        let timed_out = th.status == TS::STATUS_TIMED_OUT;
        if timed_out && !was_timed_out {
            b.summary.timeouts += 1;
        }
        was_timed_out = timed_out;
    }
    // /diagnostics repeats every verdict with every report; an alarm is a verdict that rose
    // (OK → WARN, WARN → ERROR), as the monitor raises them live, and every new hot start.
    let mut last: std::collections::BTreeMap<String, (u8, String)> = std::collections::BTreeMap::new();
    for (_, d) in &diags {
        for s in &d.status {
            use tyre_msgs::diagnostic_msgs::DiagnosticStatus as DS;
            let check = s.name.rsplit(": ").next().unwrap_or(&s.name).to_owned();
            let (old_level, old_message) = last.get(&check).cloned().unwrap_or((DS::OK, String::new()));
            let raised =
                s.level > old_level || (check == "thermal_timeout" && s.level >= DS::WARN && s.message != old_message);
            let level = match s.level {
                DS::WARN => "WARN",
                DS::ERROR => "ERROR",
                _ => "",
            };
            if raised && !level.is_empty() {
                b.alarm(level, &check, s.message.clone(), d.header.stamp.as_secs_f64());
            }
            last.insert(check, (s.level, s.message.clone()));
        }
    }
    b.summary.tyres_used = b.summary.tyre_changes.max(1);
    b.summary.wear_mm_measured = wear_by_specimen(&reports, &tyre_changes_at_s);
    (b.summary.max_temp_c, b.summary.max_sweep_start_temp_c) = sweep_temperatures(&states, &thermal);
    b.summary.adaptive = adaptive_decisions(&diags);
    Ok(b.summary)
}

/// The adaptive plan's decisions from their `/diagnostics` records (`sequencer: adaptive`, one
/// per decision; `sequencer::decisions`): a DDS run's summary lists them as the headless one does.
fn adaptive_decisions(diags: &[(u64, tyre_msgs::diagnostic_msgs::DiagnosticArray)]) -> Vec<AdaptiveChoice> {
    let mut out: Vec<AdaptiveChoice> = Vec::new();
    for (_, d) in diags {
        for s in d.status.iter().filter(|s| s.name == "sequencer: adaptive") {
            let get = |k: &str| s.values.iter().find(|kv| kv.key == k).map(|kv| kv.value.as_str());
            let num = |k: &str| get(k).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN);
            let sweep = get("sweep").unwrap_or("").to_owned();
            let error_pct = num("predicted_error_pct");
            let choice = AdaptiveChoice {
                rig_time_s: get("rig_time_s")
                    .and_then(|v| v.parse().ok())
                    .unwrap_or_else(|| d.header.stamp.as_secs_f64()),
                slot: get("slot").and_then(|v| v.parse().ok()).unwrap_or(0),
                value: if sweep.is_empty() { 0.0 } else { num("value_pct2") },
                cost_s: if sweep.is_empty() { 0.0 } else { num("cost_s") },
                wear_mm: get("wear_mm").and_then(|v| v.parse().ok()).unwrap_or(0.0),
                wear_rate_mm_per_mj: get("wear_rate_mm_per_mj").and_then(|v| v.parse().ok()).unwrap_or(0.0),
                error_pct,
                error_after_pct: if sweep.is_empty() { error_pct } else { num("predicted_error_after_pct") },
                target_pct: num("target_pct"),
                // "chose <sweep>: <reason>" or "slot <n> closed after <k> sweeps: <reason>".
                reason: s.message.split_once(": ").map_or(s.message.clone(), |(_, r)| r.to_owned()),
                sweep,
            };
            // A recorder that saw a record twice (a repeated publication) lists it once.
            if !out
                .iter()
                .any(|c| c.rig_time_s == choice.rig_time_s && c.slot == choice.slot && c.sweep == choice.sweep)
            {
                out.push(choice);
            }
        }
    }
    out
}

/// Highest tread centre temperature (TRDTEMPC as the thermal gate received it) during sweeps,
/// and at their starts, as the headless runner counts them live: each `thermal/state` is read
/// in the phase of the newest `procedure/state` at or before it. 0 without thermal states.
fn sweep_temperatures(
    states: &[(u64, tyre_msgs::ProcedureState)],
    thermal: &[(u64, tyre_msgs::ThermalState)],
) -> (f64, f64) {
    use tyre_msgs::ProcedureState as PS;
    let (mut peak, mut at_start) = (0.0_f64, 0.0_f64);
    // The number of states at or before the thermal state in hand.
    let mut seen = 0;
    let mut started: Option<(String, u32)> = None;
    for (_, th) in thermal {
        let t = th.header.stamp.as_secs_f64();
        while seen < states.len() && states[seen].1.header.stamp.as_secs_f64() <= t {
            seen += 1;
        }
        let Some((_, st)) = seen.checked_sub(1).map(|i| &states[i]) else { continue };
        if st.phase != PS::PHASE_SWEEP || !th.trdtempc_c.is_finite() {
            continue;
        }
        peak = peak.max(th.trdtempc_c);
        let this = (st.procedure.clone(), st.sweep_index);
        if started.as_ref() != Some(&this) {
            at_start = at_start.max(th.trdtempc_c);
            started = Some(this);
        }
    }
    (peak, at_start)
}
