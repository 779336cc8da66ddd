//! Alarms for the operator's log: a `/diagnostics` verdict that rose (OK → WARN, WARN → ERROR)
//! or a new thermal time-out, the same rule `suite::summary_from_log` lists alarms by. The
//! monitor repeats every verdict with every report; repeating them in a log would bury the one
//! that matters.

use std::collections::BTreeMap;
use tyre_msgs::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus as DS};

/// One alarm.
#[derive(Debug, Clone, PartialEq)]
pub struct Alarm {
    /// `DiagnosticStatus` level (WARN or ERROR).
    pub level: u8,
    /// The check's name (`wear`, `thermal_timeout`, …).
    pub check: String,
    pub message: String,
    /// Rig time of the verdict [s].
    pub rig_time_s: f64,
}

/// Remembers each check's last verdict and reports the ones that rose.
#[derive(Debug, Clone, Default)]
pub struct AlarmDetector {
    last: BTreeMap<String, (u8, String)>,
}

impl AlarmDetector {
    pub fn on_diagnostics(&mut self, d: &DiagnosticArray) -> Vec<Alarm> {
        let mut out = Vec::new();
        for s in &d.status {
            // Statuses are named "<node>: <check>".
            let check = s.name.rsplit(": ").next().unwrap_or(&s.name).to_owned();
            let (old_level, old_message) = self.last.get(&check).cloned().unwrap_or((DS::OK, String::new()));
            let rose =
                s.level > old_level || (check == "thermal_timeout" && s.level >= DS::WARN && s.message != old_message);
            if rose && matches!(s.level, DS::WARN | DS::ERROR) {
                out.push(Alarm {
                    level: s.level,
                    check: check.clone(),
                    message: s.message.clone(),
                    rig_time_s: d.header.stamp.as_secs_f64(),
                });
            }
            self.last.insert(check, (s.level, s.message.clone()));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::std_msgs::Header;

    fn diag(t: i32, statuses: &[(&str, u8, &str)]) -> DiagnosticArray {
        DiagnosticArray {
            header: Header { stamp: tyre_msgs::builtin_interfaces::Time { sec: t, nanosec: 0 }, ..Header::default() },
            status: statuses
                .iter()
                .map(|(n, l, m)| DS { name: format!("quality: {n}"), level: *l, message: (*m).into(), ..DS::default() })
                .collect(),
        }
    }

    #[test]
    fn only_rising_verdicts_and_new_timeouts_are_alarms() {
        let mut a = AlarmDetector::default();
        assert!(a.on_diagnostics(&diag(1, &[("wear", DS::OK, "fine")])).is_empty());
        let up = a.on_diagnostics(&diag(2, &[("wear", DS::WARN, "3 mm")]));
        assert_eq!(up.len(), 1);
        assert_eq!((up[0].check.as_str(), up[0].level, up[0].rig_time_s), ("wear", DS::WARN, 2.0));
        // The same verdict repeated is not a new alarm; ERROR after WARN is.
        assert!(a.on_diagnostics(&diag(3, &[("wear", DS::WARN, "3.1 mm")])).is_empty());
        assert_eq!(a.on_diagnostics(&diag(4, &[("wear", DS::ERROR, "5 mm")])).len(), 1);
        // Every new hot start is one.
        assert_eq!(a.on_diagnostics(&diag(5, &[("thermal_timeout", DS::WARN, "sweep 3 hot")])).len(), 1);
        assert!(a.on_diagnostics(&diag(6, &[("thermal_timeout", DS::WARN, "sweep 3 hot")])).is_empty());
        assert_eq!(a.on_diagnostics(&diag(7, &[("thermal_timeout", DS::WARN, "sweep 9 hot")])).len(), 1);
    }
}
