//! The sequencer's typed configuration (TOML, `deny_unknown_fields`, [`SequencerConfig::validate`]).

use adaptive::AdaptiveConfig;
use procedure::{PauseModel, RigLimits};
use serde::{Deserialize, Serialize};

/// Sequencer configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SequencerConfig {
    /// Rate the shell calls `step` at and streams setpoints \[Hz\].
    pub control_rate_hz: f64,
    /// `ProcedureState` is published on change and at least this often \[s\] (2 Hz).
    pub state_period_s: f64,
    /// A `ThermalState` older than this (by its stamp, in rig time) cannot release a pause \[s\].
    pub thermal_stale_after_s: f64,
    /// A release must be judged at least this long after the pause began \[s\]: a gate still
    /// open from before the sweep has not seen the sweep's heat yet.
    pub min_thermal_pause_s: f64,
    /// Cool-down model behind the ETA: each remaining pause is estimated from its sweep's slip
    /// exposure, scaled by how the observed pauses compared with the model so far.
    pub pause_model: PauseModel,
    /// The rig envelope: setpoints outside it are refused. Its profile limits also shape the
    /// ramps the sequencer builds itself (pause, resume).
    pub envelope: RigLimits,
    /// No fresh `ThermalState` for this long (rig time, by stamp) while a procedure runs raises
    /// an alarm \[s\]. Pauses never release on a stale state whatever this says.
    pub thermal_alarm_after_s: f64,
    /// The rig went silent (the shell's watchdog): e-stop instead of holding zero slip.
    pub estop_on_rig_silence: bool,
    /// When the silent rig's samples come back, rerun the interrupted sweep's group at once
    /// (else wait for an operator RESUME).
    pub resume_after_rig_silence: bool,
    /// Which plan runs: the procedure as written, or adaptive (`docs/adaptive-plan.md`).
    pub plan: PlanKind,
    /// How the adaptive plan chooses and stops (used with `plan = "adaptive"`).
    pub adaptive: AdaptiveConfig,
}

/// Which plan the sequencer runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanKind {
    /// Every step of the procedure, in order.
    #[default]
    Fixed,
    /// The procedure's fixed parts; its other sweeps chosen one at a time by the live model's
    /// predicted variance reduction per rig second, until the model is predicted good enough.
    Adaptive,
}

impl std::str::FromStr for PlanKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "fixed" => Ok(Self::Fixed),
            "adaptive" => Ok(Self::Adaptive),
            other => Err(format!("expected `fixed` or `adaptive`, got `{other}`")),
        }
    }
}

impl Default for SequencerConfig {
    fn default() -> Self {
        Self {
            control_rate_hz: 100.0,
            state_period_s: 0.5,
            thermal_stale_after_s: 2.0,
            min_thermal_pause_s: 1.0,
            pause_model: PauseModel::default(),
            envelope: RigLimits::default(),
            thermal_alarm_after_s: 0.5,
            estop_on_rig_silence: false,
            resume_after_rig_silence: true,
            plan: PlanKind::Fixed,
            adaptive: AdaptiveConfig::default(),
        }
    }
}

/// A configuration value out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("sequencer config `{key}`: {message}")]
pub struct ConfigError {
    /// The key.
    pub key: &'static str,
    /// What was expected.
    pub message: String,
}

impl SequencerConfig {
    /// Parse from TOML text (errors carry toml's line/column in the message).
    pub fn from_toml(src: &str) -> Result<Self, ConfigError> {
        let cfg: Self = toml::from_str(src).map_err(|e| ConfigError { key: "toml", message: e.to_string() })?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// Check ranges.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let pos = [
            ("control_rate_hz", self.control_rate_hz),
            ("state_period_s", self.state_period_s),
            ("thermal_stale_after_s", self.thermal_stale_after_s),
            ("thermal_alarm_after_s", self.thermal_alarm_after_s),
        ];
        for (key, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                return Err(ConfigError { key, message: format!("expected a positive number, got {v}") });
            }
        }
        let m = &self.pause_model;
        for (key, v) in [
            ("min_thermal_pause_s", self.min_thermal_pause_s),
            ("pause_model.base_s", m.base_s),
            ("pause_model.per_slip_s", m.per_slip_s),
            ("pause_model.deg_per_slip_ratio", m.deg_per_slip_ratio),
            ("pause_model.timeout_s", m.timeout_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ConfigError { key, message: format!("expected a number ≥ 0, got {v}") });
            }
        }
        self.adaptive
            .validate()
            .map_err(|(key, message)| ConfigError { key: "adaptive", message: format!("`{key}`: {message}") })?;
        self.envelope.validate().map_err(|message| ConfigError { key: "envelope", message })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_toml_round_trip() {
        let c = SequencerConfig::default();
        c.validate().unwrap();
        let s = toml::to_string(&c).unwrap();
        assert_eq!(SequencerConfig::from_toml(&s).unwrap(), c);
    }

    #[test]
    fn rejects_unknown_and_bad_values() {
        let e = SequencerConfig::from_toml("control_rate_hz = 100.0\nfoo = 1\n").unwrap_err();
        assert!(e.message.contains("foo"), "{e}");
        let e = SequencerConfig::from_toml("state_period_s = 0.0\n").unwrap_err();
        assert_eq!(e.key, "state_period_s");
        let e = SequencerConfig::from_toml("[envelope]\nmax_fz_n = -1.0\n").unwrap_err();
        assert_eq!(e.key, "envelope");
        let e = SequencerConfig::from_toml("plan = \"adaptive\"\n[adaptive]\ntarget_ratio = 0.5\n").unwrap_err();
        assert!(e.key == "adaptive" && e.message.contains("target_ratio"), "{e}");
        let c = SequencerConfig::from_toml("plan = \"adaptive\"\n").unwrap();
        assert_eq!(c.plan, PlanKind::Adaptive);
    }
}
