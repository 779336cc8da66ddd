//! The views the node adds to the suite's topics: JSON messages shaped for Foxglove panels
//! (tables, gauges, indicators, XY plots), each on a channel under `<namespace>/foxglove/`.
//!
//! | channel | schema | what | when |
//! |---|---|---|---|
//! | `foxglove/plan` | `tyrerig.Plan` | the run's sweeps with planned time and status | start, each new sweep |
//! | `foxglove/progress` | `tyrerig.Progress` | phase, sweep k of n, %, ETA, gate, wear | view rate |
//! | `foxglove/sweep_trace` | `tyrerig.SweepTrace` | the running sweep's forces over slip | view rate |
//! | `foxglove/sweep_trace_previous` | `tyrerig.SweepTrace` | the sweep before it, complete | end of each sweep |
//! | `foxglove/alarms` | `foxglove.Log` | alarms as they rise, phase changes, commands | on event |
//! | `foxglove/model` | `tyrerig.Model` | the live fit: stages identified, NRMSE, 95 % bands over slip ([`crate::model`]) | each `model/state` |

use serde::Serialize;

/// One of the node's own channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum View {
    Plan,
    Progress,
    SweepTrace,
    PreviousSweepTrace,
    Alarms,
    Model,
}

impl View {
    pub const ALL: [View; 6] =
        [View::Plan, View::Progress, View::SweepTrace, View::PreviousSweepTrace, View::Alarms, View::Model];

    /// Name relative to the namespace.
    pub fn relative_name(self) -> &'static str {
        match self {
            View::Plan => "foxglove/plan",
            View::Progress => "foxglove/progress",
            View::SweepTrace => "foxglove/sweep_trace",
            View::PreviousSweepTrace => "foxglove/sweep_trace_previous",
            View::Alarms => "foxglove/alarms",
            View::Model => "foxglove/model",
        }
    }

    pub fn full_name(self, namespace: &str) -> String {
        format!("{}/{}", namespace.trim_end_matches('/'), self.relative_name())
    }

    pub fn schema_name(self) -> &'static str {
        match self {
            View::Plan => "tyrerig.Plan",
            View::Progress => "tyrerig.Progress",
            View::SweepTrace | View::PreviousSweepTrace => "tyrerig.SweepTrace",
            // Foxglove's own log schema: the Log panel shows it as it does ROS logs.
            View::Alarms => "foxglove.Log",
            View::Model => "tyrerig.Model",
        }
    }

    /// JSON Schema of the messages (lets Foxglove offer the fields in its message-path editor).
    pub fn json_schema(self) -> String {
        match self {
            View::Plan => PLAN_SCHEMA.to_owned(),
            View::Progress => PROGRESS_SCHEMA.to_owned(),
            View::SweepTrace | View::PreviousSweepTrace => TRACE_SCHEMA.to_owned(),
            View::Alarms => LOG_SCHEMA.to_owned(),
            View::Model => crate::model::MODEL_SCHEMA.to_owned(),
        }
    }

    /// How many past messages a client that subscribes late is sent (as DDS transient-local
    /// does for the suite's state and event topics).
    pub fn latched(self) -> usize {
        match self {
            View::Plan | View::Progress | View::SweepTrace | View::PreviousSweepTrace | View::Model => 1,
            View::Alarms => 1000,
        }
    }
}

/// `foxglove/plan`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanView {
    pub procedure: String,
    pub title: String,
    pub sweep_count: u32,
    /// Planned setpoint time without thermal pauses [s].
    pub setpoint_time_s: f64,
    /// With the predicted thermal pauses [s].
    pub estimated_total_s: f64,
    /// Index of the sweep running or next (= sweep_count when done).
    pub current_sweep: u32,
    pub sweeps: Vec<PlannedSweep>,
}

/// One data step of the plan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlannedSweep {
    pub sweep_index: u32,
    pub name: String,
    pub kind: String,
    pub section: String,
    pub planned_s: f64,
    pub thermal_pause_after: bool,
    /// `done`, `running` or `to do`.
    pub status: &'static str,
}

/// `foxglove/progress`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ProgressView {
    /// Rig time of the latest message [s].
    pub rig_time_s: f64,
    pub procedure: String,
    pub phase: String,
    pub phase_code: u8,
    pub section: String,
    pub sweep_name: String,
    /// "k / n", 1-based.
    pub sweep: String,
    pub sweep_index: u32,
    pub sweep_count: u32,
    pub progress_pct: f64,
    pub elapsed_rig_time_s: f64,
    pub eta_s: f64,
    /// ETA in words ("1 h 05 min").
    pub eta: String,
    pub sweep_started_hot: bool,
    /// Why the sweep runs (`ProcedureState.plan_reason`: empty for a fixed procedure).
    pub plan_reason: String,
    /// Adaptive plan: predicted error after the chosen sweep [% of peak], 0 otherwise.
    pub predicted_error_pct: f64,
    pub gate: GateView,
    pub quality_level: String,
    pub wear_mm: f64,
    pub wear_forecast_mm: f64,
    pub alarms: u32,
}

/// The thermal gate as the progress view shows it.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct GateView {
    pub status: String,
    pub gate_open: bool,
    pub filtered_temp_c: f64,
    pub baseline_c: f64,
    /// filtered − baseline: how far the tread still has to cool [K].
    pub above_baseline_k: f64,
    pub predicted_wait_s: f64,
    /// Rig time the gate is predicted to release at [s] (NaN when no pause is running).
    pub predicted_release_s: f64,
}

/// `foxglove/alarms`: `foxglove.Log` in JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LogLine {
    pub timestamp: LogTime,
    /// 1 DEBUG, 2 INFO, 3 WARNING, 4 ERROR, 5 FATAL.
    pub level: u8,
    pub message: String,
    pub name: String,
    pub file: String,
    pub line: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LogTime {
    pub sec: u32,
    pub nsec: u32,
}

impl LogTime {
    pub fn from_secs_f64(t_s: f64) -> Self {
        let t = t_s.max(0.0);
        let sec = t.floor();
        Self { sec: sec as u32, nsec: ((t - sec) * 1e9).min(999_999_999.0) as u32 }
    }
}

pub const LOG_INFO: u8 = 2;
pub const LOG_WARNING: u8 = 3;
pub const LOG_ERROR: u8 = 4;

/// "1 h 05 min", "12 min 30 s", "45 s".
pub fn duration_words(s: f64) -> String {
    if !s.is_finite() || s < 0.0 {
        return "—".to_owned();
    }
    let total = s.round() as u64;
    let (h, m, sec) = (total / 3600, (total % 3600) / 60, total % 60);
    if h > 0 {
        format!("{h} h {m:02} min")
    } else if m > 0 {
        format!("{m} min {sec:02} s")
    } else {
        format!("{sec} s")
    }
}

const PLAN_SCHEMA: &str = r#"{"type":"object","properties":{
"procedure":{"type":"string"},"title":{"type":"string"},"sweep_count":{"type":"integer"},
"setpoint_time_s":{"type":"number"},"estimated_total_s":{"type":"number"},"current_sweep":{"type":"integer"},
"sweeps":{"type":"array","items":{"type":"object","properties":{"sweep_index":{"type":"integer"},
"name":{"type":"string"},"kind":{"type":"string"},"section":{"type":"string"},"planned_s":{"type":"number"},
"thermal_pause_after":{"type":"boolean"},"status":{"type":"string"}}}}}}"#;

const PROGRESS_SCHEMA: &str = r#"{"type":"object","properties":{
"rig_time_s":{"type":"number"},"procedure":{"type":"string"},"phase":{"type":"string"},"phase_code":{"type":"integer"},
"section":{"type":"string"},"sweep_name":{"type":"string"},"sweep":{"type":"string"},"sweep_index":{"type":"integer"},
"sweep_count":{"type":"integer"},"progress_pct":{"type":"number"},"elapsed_rig_time_s":{"type":"number"},
"eta_s":{"type":"number"},"eta":{"type":"string"},"sweep_started_hot":{"type":"boolean"},
"plan_reason":{"type":"string"},"predicted_error_pct":{"type":"number"},
"gate":{"type":"object","properties":{"status":{"type":"string"},"gate_open":{"type":"boolean"},
"filtered_temp_c":{"type":"number"},"baseline_c":{"type":"number"},"above_baseline_k":{"type":"number"},
"predicted_wait_s":{"type":"number"},"predicted_release_s":{"type":"number"}}},
"quality_level":{"type":"string"},"wear_mm":{"type":"number"},"wear_forecast_mm":{"type":"number"},
"alarms":{"type":"integer"}}}"#;

const TRACE_SCHEMA: &str = r#"{"type":"object","properties":{"sweep_name":{"type":"string"},"sweep_index":{"type":"integer"},
"samples":{"type":"integer"},"slip_angle_deg":{"type":"array","items":{"type":"number"}},
"slip_ratio":{"type":"array","items":{"type":"number"}},"fyw_n":{"type":"array","items":{"type":"number"}},
"fx_n":{"type":"array","items":{"type":"number"}},"mzw_nm":{"type":"array","items":{"type":"number"}},
"fzw_n":{"type":"array","items":{"type":"number"}}}}"#;

const LOG_SCHEMA: &str = r#"{"title":"foxglove.Log","type":"object","properties":{
"timestamp":{"type":"object","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0}}},
"level":{"type":"integer","minimum":0,"maximum":5},"message":{"type":"string"},"name":{"type":"string"},
"file":{"type":"string"},"line":{"type":"integer","minimum":0}}}"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemas_are_json_and_name_every_serialised_field() {
        for v in View::ALL {
            let schema: serde_json::Value =
                serde_json::from_str(&v.json_schema()).unwrap_or_else(|e| panic!("{v:?}: {e}"));
            assert_eq!(schema["type"], "object", "{v:?}");
        }
        let check = |schema: &str, value: serde_json::Value| {
            let schema: serde_json::Value = serde_json::from_str(schema).expect("schema");
            for key in value.as_object().expect("object").keys() {
                assert!(schema["properties"].get(key).is_some(), "schema lacks {key}");
            }
        };
        check(PROGRESS_SCHEMA, serde_json::to_value(ProgressView::default()).expect("json"));
        check(TRACE_SCHEMA, serde_json::to_value(crate::trace::SweepTrace::default()).expect("json"));
    }

    #[test]
    fn durations_in_words() {
        assert_eq!(duration_words(3_930.0), "1 h 05 min");
        assert_eq!(duration_words(750.0), "12 min 30 s");
        assert_eq!(duration_words(45.2), "45 s");
        assert_eq!(duration_words(f64::NAN), "—");
    }

    #[test]
    fn log_time_splits_seconds() {
        assert_eq!(LogTime::from_secs_f64(12.25), LogTime { sec: 12, nsec: 250_000_000 });
        assert_eq!(LogTime::from_secs_f64(-1.0), LogTime { sec: 0, nsec: 0 });
    }
}
