//! The wear rate measured on the tyre under test, as the monitor reports it on `/diagnostics`:
//! its wear status ([`topics::WEAR_STATUS`]) carries the rate and its standard error as
//! key-values once two zero-slip holds of one load case have shown the radius shrink. The
//! adaptive sequencer node reads it from there ([`crate::Sequencer::on_wear_rate`]); headless,
//! the run hands the monitor core's figure over directly.

use adaptive::MeasuredWearRate;
use tyre_msgs::diagnostic_msgs::DiagnosticArray;
use tyre_msgs::topics;

/// The measured wear rate in a `/diagnostics` message, if it holds the monitor's wear status
/// with both figures as finite numbers. Anything else (another node's statuses, a wear
/// status before the rate is measurable, a value that does not parse) is `None`: the planner
/// keeps what it has.
pub fn measured_wear_rate(msg: &DiagnosticArray) -> Option<MeasuredWearRate> {
    let status = msg.status.iter().rev().find(|s| s.name == topics::WEAR_STATUS)?;
    let number = |key: &str| -> Option<f64> {
        let v = status.values.iter().find(|kv| kv.key == key)?.value.trim().parse::<f64>().ok()?;
        v.is_finite().then_some(v)
    };
    Some(MeasuredWearRate {
        mm_per_mj: number(topics::WEAR_RATE_KEY)?,
        sd_mm_per_mj: number(topics::WEAR_RATE_SD_KEY)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tyre_msgs::diagnostic_msgs::{DiagnosticStatus, KeyValue};

    fn status(name: &str, values: &[(&str, &str)]) -> DiagnosticStatus {
        DiagnosticStatus {
            name: name.into(),
            values: values.iter().map(|(k, v)| KeyValue { key: (*k).into(), value: (*v).into() }).collect(),
            ..DiagnosticStatus::default()
        }
    }

    #[test]
    fn the_monitors_wear_status_gives_the_rate_and_nothing_else_does() {
        let rate = [(topics::WEAR_RATE_KEY, "0.31"), (topics::WEAR_RATE_SD_KEY, "0.02")];
        let msg = DiagnosticArray {
            status: vec![status("tyrerig monitor: load_rating", &rate), status(topics::WEAR_STATUS, &rate)],
            ..DiagnosticArray::default()
        };
        assert_eq!(measured_wear_rate(&msg), Some(MeasuredWearRate { mm_per_mj: 0.31, sd_mm_per_mj: 0.02 }));

        let only_other = DiagnosticArray { status: vec![status("tyrerig monitor: chatter", &rate)], ..msg.clone() };
        assert_eq!(measured_wear_rate(&only_other), None);
        let not_yet = DiagnosticArray { status: vec![status(topics::WEAR_STATUS, &[("value", "NaN")])], ..msg.clone() };
        assert_eq!(measured_wear_rate(&not_yet), None);
        let garbled = DiagnosticArray {
            status: vec![status(
                topics::WEAR_STATUS,
                &[(topics::WEAR_RATE_KEY, "fast"), (topics::WEAR_RATE_SD_KEY, "0.1")],
            )],
            ..msg.clone()
        };
        assert_eq!(measured_wear_rate(&garbled), None);
        let nan = DiagnosticArray {
            status: vec![status(
                topics::WEAR_STATUS,
                &[(topics::WEAR_RATE_KEY, "NaN"), (topics::WEAR_RATE_SD_KEY, "0.1")],
            )],
            ..msg
        };
        assert_eq!(measured_wear_rate(&nan), None);
    }
}
