//! Typed, validated configuration of the thermal gate.
//!
//! Every field has a default, so an empty TOML table is a valid configuration that reproduces the
//! thesis's rig (45 °C baseline on the centre tread temperature, 120 s time-out). Values the
//! thesis does not give (filter window, stale and stuck limits, cooling-model priors) are named
//! here and documented field by field.

use serde::{Deserialize, Serialize};

/// Errors from loading or validating a [`ThermalConfig`].
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The TOML text did not parse or did not match the schema (unknown key, wrong type …).
    #[error("thermal config: {0}")]
    Toml(#[from] toml::de::Error),
    /// A value is outside its allowed range.
    #[error("thermal config: `{key}` = {value} is invalid: expected {expected}")]
    Invalid {
        /// Dotted key of the offending value, e.g. `spike_filter.window_s`.
        key: &'static str,
        /// The value found.
        value: f64,
        /// What the value must satisfy.
        expected: &'static str,
    },
}

/// Weights of the three tread surface temperatures in the gate's temperature.
///
/// The gate uses `Σ wᵢ·Tᵢ / Σ wᵢ` over the channels with a non-zero weight; channels with a zero
/// weight are ignored completely (a broken, unused laser cannot hold the gate).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TempWeights {
    /// Weight of TRDTEMPI (inner tread surface) (-).
    pub inner: f64,
    /// Weight of TRDTEMPC (centre tread surface) (-).
    pub centre: f64,
    /// Weight of TRDTEMPO (outer tread surface) (-).
    pub outer: f64,
}

impl Default for TempWeights {
    /// Centre only: what the thesis's rig used (§3.5).
    fn default() -> Self {
        Self { inner: 0.0, centre: 1.0, outer: 0.0 }
    }
}

/// Flash-spike filter: a running median over a sliding time window.
///
/// Why a median: the laser sees only the outermost surface, and flash temperatures above 140 °C
/// that vanish within moments are normal (§5). A median over a window rejects any excursion that
/// lasts less than half the window completely, whatever its amplitude and in either direction (a
/// spike up would delay the release, a drop-out down could release early). A low-pass filter
/// would instead smear a 150 °C spike into a bias of several degrees for seconds; a rate limiter
/// would clip it but still carry part of it through. The price is a delay of about half the
/// window on genuine changes, negligible against cooling time constants of tens of seconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpikeFilterConfig {
    /// Length of the median window (s). Spikes shorter than half of it are rejected.
    pub window_s: f64,
    /// Samples the window must hold before its median may release the gate (-).
    pub min_samples: u32,
}

impl Default for SpikeFilterConfig {
    fn default() -> Self {
        Self { window_s: 0.5, min_samples: 3 }
    }
}

/// Stuck-sensor detection.
///
/// A real laser pyrometer's reading flickers in its last digit; a reading that stays identical
/// for `after_s` while the tyre should be changing means a frozen channel (a dead transmitter
/// repeating its last value, a frozen bridge buffer). "Should be changing" is: a sweep is running
/// (friction heats the tread), or a thermal pause is running and the cooling model expects the
/// temperature to move by at least `min_expected_change_c` within `after_s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StuckConfig {
    /// Unchanged-reading duration that declares a channel stuck (s).
    pub after_s: f64,
    /// Two readings closer than this count as identical (°C).
    pub tolerance_c: f64,
    /// During a pause, only judge "stuck" if the cooling model expects at least this change
    /// over `after_s` (°C).
    pub min_expected_change_c: f64,
}

impl Default for StuckConfig {
    fn default() -> Self {
        Self { after_s: 5.0, tolerance_c: 1e-9, min_expected_change_c: 0.5 }
    }
}

/// Warm-up target (§3.4: two blocks of warm-up sweeps reach 42 °C; the aim is 40–45 °C).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WarmUpConfig {
    /// Lower end of the warm-up target: reaching it completes the warm-up (°C).
    pub target_min_c: f64,
    /// Upper end of the warm-up target; above it the thermal pause cools the tyre (°C).
    pub target_max_c: f64,
}

impl Default for WarmUpConfig {
    fn default() -> Self {
        Self { target_min_c: 40.0, target_max_c: 45.0 }
    }
}

/// Online Newton-cooling model `T(t) = T_amb_eff + (T0 − T_amb_eff)·exp(−t/τ)`.
///
/// It is fitted by linear least squares on the integral form of the cooling ODE, with Gaussian
/// priors on τ and on the effective ambient taken from the previous pause (the first pause uses
/// `initial_tau_s` and `ambient_c`). See the crate documentation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CoolingConfig {
    /// Prior time constant for the first pause (s). Not given in the thesis; a 255/55R20 tread
    /// surface at zero slip on a flat track cools with τ of the order of tens of seconds.
    pub initial_tau_s: f64,
    /// Prior effective ambient (belt and air) temperature for the first pause (°C).
    pub ambient_c: f64,
    /// Relative 1-σ uncertainty of the τ prior (-) (0.5: τ is known within ±50 %).
    pub tau_prior_rel_sigma: f64,
    /// 1-σ uncertainty of the effective-ambient prior (°C).
    pub ambient_prior_sigma_c: f64,
    /// Temperature noise of the filtered signal, as white noise per second of data (°C).
    pub sensor_noise_c: f64,
    /// Smallest plausible time constant; fits outside `[tau_min_s, tau_max_s]` are clamped (s).
    pub tau_min_s: f64,
    /// Largest plausible time constant (s).
    pub tau_max_s: f64,
    /// Pause data needed before a fit replaces the priors of the next pause (s).
    pub min_fit_data_s: f64,
}

impl Default for CoolingConfig {
    fn default() -> Self {
        Self {
            initial_tau_s: 40.0,
            ambient_c: 25.0,
            tau_prior_rel_sigma: 0.5,
            ambient_prior_sigma_c: 10.0,
            sensor_noise_c: 0.2,
            tau_min_s: 1.0,
            tau_max_s: 3600.0,
            min_fit_data_s: 5.0,
        }
    }
}

/// Configuration of the thermal gate (`[thermal]` in a node's TOML file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThermalConfig {
    /// Release threshold: a sweep may start at or below it (§3.5: 45 °C) (°C).
    pub baseline_c: f64,
    /// Weighting of inner/centre/outer tread temperature.
    pub weights: TempWeights,
    /// Flash-spike filter.
    pub spike_filter: SpikeFilterConfig,
    /// Pause length after which the gate releases anyway, with an alarm (§3.5: 120 s) (s).
    pub timeout_s: f64,
    /// No temperature sample for this long is a fault (s).
    pub stale_after_s: f64,
    /// Stuck-sensor detection.
    pub stuck: StuckConfig,
    /// Readings below this are physically absurd for a tread surface (sensor fault) (°C).
    pub absurd_min_c: f64,
    /// Readings above this are absurd even for a flash temperature (sensor fault) (°C).
    pub absurd_max_c: f64,
    /// After a fault, the sensor must be healthy this long before the gate trusts it again (s).
    pub recovery_s: f64,
    /// Warm-up target range.
    pub warm_up: WarmUpConfig,
    /// Online cooling model.
    pub cooling: CoolingConfig,
}

impl Default for ThermalConfig {
    fn default() -> Self {
        Self {
            baseline_c: 45.0,
            weights: TempWeights::default(),
            spike_filter: SpikeFilterConfig::default(),
            timeout_s: 120.0,
            stale_after_s: 1.0,
            stuck: StuckConfig::default(),
            absurd_min_c: -40.0,
            absurd_max_c: 250.0,
            recovery_s: 1.0,
            warm_up: WarmUpConfig::default(),
            cooling: CoolingConfig::default(),
        }
    }
}

fn check(key: &'static str, value: f64, ok: bool, expected: &'static str) -> Result<(), ConfigError> {
    if ok && value.is_finite() { Ok(()) } else { Err(ConfigError::Invalid { key, value, expected }) }
}

impl ThermalConfig {
    /// Parses a TOML table and validates it.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        let config: Self = toml::from_str(text)?;
        config.validate()?;
        Ok(config)
    }

    /// Checks every value's range and the relations between values.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check(
            "absurd_min_c",
            self.absurd_min_c,
            self.absurd_min_c < self.absurd_max_c,
            "a finite value below absurd_max_c",
        )?;
        check(
            "absurd_max_c",
            self.absurd_max_c,
            self.absurd_max_c > self.absurd_min_c,
            "a finite value above absurd_min_c",
        )?;
        check(
            "baseline_c",
            self.baseline_c,
            self.baseline_c > self.absurd_min_c && self.baseline_c < self.absurd_max_c,
            "a finite temperature between absurd_min_c and absurd_max_c",
        )?;
        let w = self.weights;
        for (key, value) in [("weights.inner", w.inner), ("weights.centre", w.centre), ("weights.outer", w.outer)] {
            check(key, value, value >= 0.0, "a finite, non-negative weight")?;
        }
        let sum = w.inner + w.centre + w.outer;
        check("weights (sum)", sum, sum > 0.0, "at least one positive weight")?;
        let f = self.spike_filter;
        check("spike_filter.window_s", f.window_s, f.window_s >= 0.0, "a window >= 0 s")?;
        check("spike_filter.min_samples", f64::from(f.min_samples), f.min_samples >= 1, "at least 1 sample")?;
        check("timeout_s", self.timeout_s, self.timeout_s > 0.0, "a time-out > 0 s")?;
        check("stale_after_s", self.stale_after_s, self.stale_after_s > 0.0, "a duration > 0 s")?;
        let s = self.stuck;
        check("stuck.after_s", s.after_s, s.after_s > 0.0, "a duration > 0 s")?;
        check("stuck.tolerance_c", s.tolerance_c, s.tolerance_c >= 0.0, "a tolerance >= 0 °C")?;
        check(
            "stuck.min_expected_change_c",
            s.min_expected_change_c,
            s.min_expected_change_c >= 0.0,
            "a change >= 0 °C",
        )?;
        check("recovery_s", self.recovery_s, self.recovery_s >= 0.0, "a duration >= 0 s")?;
        let u = self.warm_up;
        check(
            "warm_up.target_min_c",
            u.target_min_c,
            u.target_min_c <= u.target_max_c,
            "a finite temperature <= warm_up.target_max_c",
        )?;
        check(
            "warm_up.target_max_c",
            u.target_max_c,
            u.target_max_c >= u.target_min_c,
            "a finite temperature >= warm_up.target_min_c",
        )?;
        let c = self.cooling;
        check(
            "cooling.tau_min_s",
            c.tau_min_s,
            c.tau_min_s > 0.0 && c.tau_min_s < c.tau_max_s,
            "a time constant > 0 s and below cooling.tau_max_s",
        )?;
        check("cooling.tau_max_s", c.tau_max_s, c.tau_max_s > c.tau_min_s, "a time constant above cooling.tau_min_s")?;
        check(
            "cooling.initial_tau_s",
            c.initial_tau_s,
            c.initial_tau_s >= c.tau_min_s && c.initial_tau_s <= c.tau_max_s,
            "a time constant within [cooling.tau_min_s, cooling.tau_max_s]",
        )?;
        check(
            "cooling.ambient_c",
            c.ambient_c,
            c.ambient_c > self.absurd_min_c && c.ambient_c < self.absurd_max_c,
            "a finite temperature between absurd_min_c and absurd_max_c",
        )?;
        check(
            "cooling.tau_prior_rel_sigma",
            c.tau_prior_rel_sigma,
            c.tau_prior_rel_sigma > 0.0,
            "a relative uncertainty > 0",
        )?;
        check(
            "cooling.ambient_prior_sigma_c",
            c.ambient_prior_sigma_c,
            c.ambient_prior_sigma_c > 0.0,
            "an uncertainty > 0 °C",
        )?;
        check("cooling.sensor_noise_c", c.sensor_noise_c, c.sensor_noise_c > 0.0, "a noise level > 0 °C")?;
        check("cooling.min_fit_data_s", c.min_fit_data_s, c.min_fit_data_s >= 0.0, "a duration >= 0 s")?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_toml_is_the_thesis_rig() {
        let c = ThermalConfig::from_toml_str("").unwrap();
        assert_eq!(c, ThermalConfig::default());
        assert_eq!(c.baseline_c, 45.0);
        assert_eq!(c.timeout_s, 120.0);
        assert_eq!(c.weights, TempWeights { inner: 0.0, centre: 1.0, outer: 0.0 });
    }

    #[test]
    fn unknown_keys_are_refused() {
        let err = ThermalConfig::from_toml_str("baseline = 45.0").unwrap_err();
        assert!(matches!(err, ConfigError::Toml(_)), "{err}");
        let err = ThermalConfig::from_toml_str("[weights]\nmiddle = 1.0").unwrap_err();
        assert!(matches!(err, ConfigError::Toml(_)), "{err}");
    }

    #[test]
    fn invalid_values_name_their_key() {
        let err = ThermalConfig::from_toml_str("[weights]\ncentre = 0.0").unwrap_err();
        assert!(err.to_string().contains("weights (sum)"), "{err}");
        let err = ThermalConfig::from_toml_str("timeout_s = -1.0").unwrap_err();
        match err {
            ConfigError::Invalid { key, value, .. } => {
                assert_eq!(key, "timeout_s");
                assert_eq!(value, -1.0);
            }
            other => panic!("unexpected {other}"),
        }
        let err = ThermalConfig::from_toml_str("baseline_c = nan").unwrap_err();
        assert!(err.to_string().contains("baseline_c"), "{err}");
    }

    #[test]
    fn partial_tables_keep_defaults() {
        let c = ThermalConfig::from_toml_str("baseline_c = 50.0\n[weights]\ninner = 1.0\ncentre = 2.0\nouter = 1.0")
            .unwrap();
        assert_eq!(c.baseline_c, 50.0);
        assert_eq!(c.weights.centre, 2.0);
        assert_eq!(c.stuck, StuckConfig::default());
    }
}
