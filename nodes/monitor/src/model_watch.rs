//! The monitor's view of the live fit (`model/state`, `tyre_msgs/ModelState`): what a control
//! room wants to know during the test without reading coefficient tables — how many stages are
//! identified, which are still waiting and why, when each became identified, and whether an
//! update failed or a stage that was identified lost it again.
//!
//! Pure: the quality node, the headless runner and `tyrerig report` feed it the same messages
//! and get the same verdicts. Time is each message's stamp (rig time).

use std::collections::BTreeMap;

use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use tyre_msgs::std_msgs::Header;
use tyre_msgs::{ModelStage, ModelState};

/// Name of the `/diagnostics` status the watch publishes.
pub const DIAGNOSTIC_NAME: &str = "tyrerig monitor: live_model";

/// How the fit's error begins when an update had nothing to fit yet (`mffit::FitError::NoData`):
/// the model is waiting for data, which is no failure.
pub const WAITING_FOR_DATA: &str = "no usable data";

/// One stage as the watch has seen it over the run.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StageHistory {
    /// Stage name (`fy_pure`, ...).
    pub stage: String,
    /// Channel (`FY`, ...).
    pub channel: String,
    /// Status in the latest update (`ModelStage::WAITING`/`FITTING`/`IDENTIFIED`).
    pub status: u8,
    /// Why it is not identified (latest update; empty when it is).
    pub reason: String,
    /// Rig time [s] of the first update that reported it identified.
    pub first_identified_s: Option<f64>,
    /// (rig time s, NRMSE % of peak) of every update that fitted it.
    pub nrmse_trace: Vec<(f64, f64)>,
    /// Points fitted in the latest update.
    pub points: u32,
    /// Largest relative standard deviation |σ/value| over its coefficients in the latest update
    /// (infinite when one is unidentified, NaN while waiting).
    pub worst_rel_std: f64,
    /// The coefficient with that σ/value.
    pub worst_key: String,
    /// Times it went from identified back to fitting or waiting.
    pub lost_identification: u32,
}

/// A change worth a line in the log (and an alarm-like entry in the report).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelEvent {
    /// Rig time [s].
    pub rig_time_s: f64,
    /// `OK` for progress (a stage identified), `WARN` for a stage that lost it or a failed update.
    pub level: u8,
    /// What happened.
    pub message: String,
}

/// What one `ModelState` produced.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelWatchOutput {
    /// The one-line summary (for the node's log).
    pub summary: String,
    /// Changes since the previous update.
    pub events: Vec<ModelEvent>,
    /// `/diagnostics` with the watch's status.
    pub diagnostics: DiagnosticArray,
}

/// Follows the live fit's model state over a run.
#[derive(Debug, Clone, Default)]
pub struct ModelWatch {
    stages: BTreeMap<String, StageHistory>,
    order: Vec<String>,
    updates: u32,
    failed_updates: u32,
    last_error: String,
    last_rig_time_s: f64,
    last_update_wall_s: f64,
    final_seen: bool,
    events: Vec<ModelEvent>,
}

impl ModelWatch {
    /// An empty watch.
    pub fn new() -> Self {
        Self::default()
    }

    /// One update of the live fit.
    pub fn on_model_state(&mut self, st: &ModelState) -> ModelWatchOutput {
        let t = st.header.stamp.as_secs_f64();
        self.updates += 1;
        self.last_rig_time_s = t;
        self.last_update_wall_s = st.update_wall_s;
        self.final_seen |= st.final_update;
        let mut events = Vec::new();
        let waiting = st.error.starts_with(WAITING_FOR_DATA);
        if !st.error.is_empty() && !waiting {
            self.failed_updates += 1;
            events.push(ModelEvent {
                rig_time_s: t,
                level: DiagnosticStatus::WARN,
                message: format!("update {} failed: {}", st.update_index, st.error),
            });
        }
        self.last_error = if waiting { String::new() } else { st.error.clone() };
        for s in &st.stages {
            if !self.stages.contains_key(&s.stage) {
                self.order.push(s.stage.clone());
            }
            let h = self.stages.entry(s.stage.clone()).or_insert_with(|| StageHistory {
                stage: s.stage.clone(),
                channel: s.channel.clone(),
                ..StageHistory::default()
            });
            let was_identified = h.status == ModelStage::IDENTIFIED;
            h.status = s.status;
            h.reason = s.status_reason.clone();
            h.points = s.points;
            (h.worst_rel_std, h.worst_key) = worst_rel_std(s);
            if s.status != ModelStage::WAITING && s.nrmse_pct.is_finite() {
                h.nrmse_trace.push((t, s.nrmse_pct));
            }
            if s.status == ModelStage::IDENTIFIED && h.first_identified_s.is_none() {
                h.first_identified_s = Some(t);
                events.push(ModelEvent {
                    rig_time_s: t,
                    level: DiagnosticStatus::OK,
                    message: format!("{} identified after {} ({:.2} % NRMSE)", s.stage, st.last_sweep, s.nrmse_pct),
                });
            }
            if was_identified && s.status != ModelStage::IDENTIFIED {
                h.lost_identification += 1;
                events.push(ModelEvent {
                    rig_time_s: t,
                    level: DiagnosticStatus::WARN,
                    message: format!(
                        "{} no longer identified after {}: {}",
                        s.stage,
                        st.last_sweep,
                        if s.status_reason.is_empty() { "no reason given" } else { &s.status_reason }
                    ),
                });
            }
        }
        self.events.extend(events.iter().cloned());
        ModelWatchOutput { summary: self.summary(), events, diagnostics: self.diagnostics() }
    }

    /// Stages in the order the fit reports them.
    pub fn stages(&self) -> impl Iterator<Item = &StageHistory> {
        self.order.iter().filter_map(|k| self.stages.get(k))
    }

    /// Every event so far.
    pub fn events(&self) -> &[ModelEvent] {
        &self.events
    }

    /// Updates seen.
    pub fn updates(&self) -> u32 {
        self.updates
    }

    /// Updates that reported an error.
    pub fn failed_updates(&self) -> u32 {
        self.failed_updates
    }

    /// Whether the procedure's final update has been seen.
    pub fn final_seen(&self) -> bool {
        self.final_seen
    }

    /// Stages identified / all stages reported.
    pub fn identified(&self) -> (usize, usize) {
        (self.stages.values().filter(|h| h.status == ModelStage::IDENTIFIED).count(), self.stages.len())
    }

    /// `identified 5/9 · waiting: fx_pure (no slip-ratio sweep yet), ... · update 12 (0.31 s)`.
    pub fn summary(&self) -> String {
        let (n_id, n) = self.identified();
        let mut s = format!("live model: {n_id}/{n} stages identified");
        let not: Vec<String> = self
            .stages()
            .filter(|h| h.status != ModelStage::IDENTIFIED)
            .map(|h| {
                let status = ModelStage::status_name(h.status);
                if h.reason.is_empty() {
                    format!("{} {status}", h.stage)
                } else {
                    format!("{} {status} ({})", h.stage, h.reason)
                }
            })
            .collect();
        if !not.is_empty() {
            s.push_str("; ");
            s.push_str(&not.join("; "));
        }
        s.push_str(&format!("; update {} took {:.2} s", self.updates, self.last_update_wall_s));
        if !self.last_error.is_empty() {
            s.push_str(&format!("; FAILED: {}", self.last_error));
        }
        s
    }

    /// The watch's `/diagnostics` status: OK while the fit progresses, WARN when the latest
    /// update failed or a stage lost its identification, with one value per stage.
    pub fn diagnostics(&self) -> DiagnosticArray {
        let kv = |k: &str, v: String| KeyValue { key: k.to_owned(), value: v };
        let lost = self.stages.values().any(|h| h.lost_identification > 0 && h.status != ModelStage::IDENTIFIED);
        let level = if !self.last_error.is_empty() || lost { DiagnosticStatus::WARN } else { DiagnosticStatus::OK };
        let (n_id, n) = self.identified();
        let mut values = vec![
            kv("updates", self.updates.to_string()),
            kv("failed_updates", self.failed_updates.to_string()),
            kv("identified", format!("{n_id}/{n}")),
            kv("last_update_wall_s", format!("{:.3}", self.last_update_wall_s)),
            kv("rig_time_s", format!("{:.3}", self.last_rig_time_s)),
        ];
        for h in self.stages() {
            let nrmse = h.nrmse_trace.last().map_or("-".to_owned(), |(_, v)| format!("{v:.2} %"));
            values.push(kv(&h.stage, format!("{} · {nrmse}", ModelStage::status_name(h.status))));
        }
        DiagnosticArray {
            header: Header::iso_w(self.last_rig_time_s),
            status: vec![DiagnosticStatus {
                level,
                name: DIAGNOSTIC_NAME.to_owned(),
                message: self.summary(),
                hardware_id: String::new(),
                values,
            }],
        }
    }
}

/// Largest |σ/value| over a stage's coefficients (a zero value counts its σ as absolute) and
/// its key.
fn worst_rel_std(s: &ModelStage) -> (f64, String) {
    if s.status == ModelStage::WAITING || s.coefficients.is_empty() {
        return (f64::NAN, String::new());
    }
    s.coefficients
        .iter()
        .map(|c| {
            let r = if c.value != 0.0 { (c.std / c.value).abs() } else { c.std.abs() };
            (if r.is_nan() { f64::INFINITY } else { r }, c.key.clone())
        })
        .fold((0.0, String::new()), |a, b| if b.0 > a.0 { b } else { a })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::ModelCoefficient;

    fn stage(name: &str, status: u8, nrmse: f64, reason: &str) -> ModelStage {
        ModelStage {
            status,
            stage: name.to_owned(),
            channel: "FY".to_owned(),
            status_reason: reason.to_owned(),
            points: 100,
            nrmse_pct: nrmse,
            coefficients: vec![ModelCoefficient { key: "PCY1".into(), value: 1.5, std: 0.03 }],
            ..ModelStage::default()
        }
    }

    fn state(t: f64, stages: Vec<ModelStage>, error: &str) -> ModelState {
        ModelState {
            header: Header::iso_w(t),
            last_sweep: "FreeRolling/Fz1".into(),
            error: error.to_owned(),
            stages,
            ..ModelState::default()
        }
    }

    #[test]
    fn a_stage_is_reported_identified_once_with_its_time() {
        let mut w = ModelWatch::new();
        let o = w.on_model_state(&state(100.0, vec![stage("fy_pure", ModelStage::FITTING, 3.0, "PCY1 unpinned")], ""));
        assert!(o.events.is_empty());
        assert!(o.summary.contains("0/1"), "{}", o.summary);
        assert!(o.summary.contains("PCY1 unpinned"), "{}", o.summary);
        let o = w.on_model_state(&state(200.0, vec![stage("fy_pure", ModelStage::IDENTIFIED, 2.0, "")], ""));
        assert_eq!(o.events.len(), 1);
        assert!(o.events[0].message.starts_with("fy_pure identified"));
        let o = w.on_model_state(&state(300.0, vec![stage("fy_pure", ModelStage::IDENTIFIED, 1.9, "")], ""));
        assert!(o.events.is_empty());
        let h = w.stages().next().unwrap();
        assert_eq!(h.first_identified_s, Some(200.0));
        assert_eq!(h.nrmse_trace.len(), 3);
        assert!((h.worst_rel_std - 0.02).abs() < 1e-12);
        assert_eq!(h.worst_key, "PCY1");
        assert_eq!(o.diagnostics.status[0].level, DiagnosticStatus::OK);
    }

    #[test]
    fn a_lost_identification_and_a_failed_update_warn() {
        let mut w = ModelWatch::new();
        w.on_model_state(&state(100.0, vec![stage("mz_pure", ModelStage::IDENTIFIED, 2.0, "")], ""));
        let o =
            w.on_model_state(&state(200.0, vec![stage("mz_pure", ModelStage::FITTING, 2.0, "QBZ9 σ infinite")], ""));
        assert_eq!(o.diagnostics.status[0].level, DiagnosticStatus::WARN);
        assert!(o.events[0].message.contains("QBZ9"));
        let o =
            w.on_model_state(&state(300.0, vec![stage("mz_pure", ModelStage::IDENTIFIED, 2.0, "")], "solver diverged"));
        assert_eq!(o.diagnostics.status[0].level, DiagnosticStatus::WARN);
        assert!(o.summary.contains("FAILED: solver diverged"));
        assert_eq!(w.failed_updates(), 1);
        let o = w.on_model_state(&state(400.0, vec![stage("mz_pure", ModelStage::IDENTIFIED, 2.0, "")], ""));
        assert_eq!(o.diagnostics.status[0].level, DiagnosticStatus::OK);
        assert_eq!(w.stages().next().unwrap().lost_identification, 1);
    }

    #[test]
    fn an_update_without_data_yet_is_waiting_not_failed() {
        let mut w = ModelWatch::new();
        let o = w.on_model_state(&state(
            5.0,
            vec![stage("fy_pure", ModelStage::WAITING, f64::NAN, "no data")],
            "no usable data: no force & moment sweeps in the data",
        ));
        assert_eq!(w.failed_updates(), 0);
        assert!(o.events.is_empty());
        assert_eq!(o.diagnostics.status[0].level, DiagnosticStatus::OK);
        assert!(!o.summary.contains("FAILED"), "{}", o.summary);
    }

    #[test]
    fn waiting_stages_have_no_error_trace_and_an_unidentified_sigma_is_infinite() {
        let mut w = ModelWatch::new();
        let mut s = stage("fx_pure", ModelStage::FITTING, 5.0, "");
        s.coefficients[0].std = f64::INFINITY;
        w.on_model_state(&state(10.0, vec![stage("fy_pure", ModelStage::WAITING, f64::NAN, "no data"), s], ""));
        let v: Vec<_> = w.stages().collect();
        assert!(v[0].nrmse_trace.is_empty() && v[0].worst_rel_std.is_nan());
        assert!(v[1].worst_rel_std.is_infinite());
        assert_eq!(w.identified(), (0, 2));
    }
}
