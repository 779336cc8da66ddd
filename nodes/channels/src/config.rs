//! Typed configuration of the channels node (TOML, `deny_unknown_fields`, validated).

use serde::{Deserialize, Serialize};

/// Errors from reading or validating a channels configuration.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The TOML did not parse or did not match the schema.
    #[error("channels config: {0}")]
    Parse(String),
    /// A value parsed but is outside its valid range.
    #[error("channels config: `{key}` {reason}")]
    Invalid {
        /// Dotted key.
        key: &'static str,
        /// Why it is invalid.
        reason: &'static str,
    },
}

/// Configuration of [`crate::ChannelsCore`]. Every value has a default taken from the thesis
/// where it gives one, otherwise a chosen value documented here.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ChannelsConfig {
    /// Below this forward speed slip ratios are not computed (NaN): SR divides by VX [m/s].
    /// Chosen: the step-steer rolls at 1 m/s, so 0.5 m/s keeps it.
    pub min_speed_mps: f64,
    /// A zero-slip crossing counts for the mechanical hysteresis only after the slip has been
    /// beyond this since the previous crossing [deg] (chosen: 1°, well above sensor noise).
    pub hysteresis_arm_slip_angle_deg: f64,
    /// The same for slip ratio sweeps [-] (chosen: 1 %).
    pub hysteresis_arm_slip_ratio: f64,
    /// A sweep is longitudinal (force FX vs slip ratio) when its slip-ratio range exceeds this
    /// [-]; otherwise lateral (FYW vs slip angle). Chosen: 2 %, the BrkDrv threshold.
    pub longitudinal_sweep_min_slip_ratio: f64,
    /// A load plateau (on-centre, rolling radius) needs this many seconds [s]. Chosen: 2 s, a
    /// fifth of the procedure's 10 s / 8 s holds.
    pub plateau_min_s: f64,
    /// Samples in the first seconds of a plateau are dropped (load and radius settle) [s].
    pub plateau_settle_s: f64,
    /// Load tolerance of a plateau, as a fraction of its load [-] (chosen: 1.5 %)...
    pub plateau_load_tol_frac: f64,
    /// ...but at least this [N] (chosen: 200 N, 8 σ of the rig's 25 N load noise).
    pub plateau_load_tol_n: f64,
    /// Pressures within this of each other are the same pressure case [Pa] (chosen: 0.1 bar).
    pub pressure_tol_pa: f64,
    /// On-centre / rolling-radius loads within this fraction are the same load case [-].
    pub load_case_tol_frac: f64,
    /// Effective-radius model: free-rolling samples (|SA| below this) teach Re = VX/W [deg].
    pub re_model_max_slip_angle_deg: f64,
    /// Static drag: the stiffness is fitted where |FX| is below this fraction of the drag's
    /// peak |FX| (beyond it the patch slides) [-]. Chosen: 0.5.
    pub static_drag_linear_frac: f64,
    /// Step-steer: the saturated FY is the mean over this final fraction of the distance [-].
    pub step_steer_saturated_frac: f64,
}

impl Default for ChannelsConfig {
    fn default() -> Self {
        Self {
            min_speed_mps: 0.5,
            hysteresis_arm_slip_angle_deg: 1.0,
            hysteresis_arm_slip_ratio: 0.01,
            longitudinal_sweep_min_slip_ratio: 0.02,
            plateau_min_s: 2.0,
            plateau_settle_s: 1.0,
            plateau_load_tol_frac: 0.015,
            plateau_load_tol_n: 200.0,
            pressure_tol_pa: 10_000.0,
            load_case_tol_frac: 0.04,
            re_model_max_slip_angle_deg: 0.5,
            static_drag_linear_frac: 0.5,
            step_steer_saturated_frac: 0.2,
        }
    }
}

impl ChannelsConfig {
    /// Parses TOML and validates it.
    pub fn from_toml(src: &str) -> Result<Self, ConfigError> {
        let c: Self = toml::from_str(src).map_err(|e| ConfigError::Parse(e.to_string()))?;
        c.validate()?;
        Ok(c)
    }

    /// Checks every value's range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let pos = |key: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ConfigError::Invalid { key, reason: "must be finite and > 0" })
            }
        };
        pos("min_speed_mps", self.min_speed_mps)?;
        pos("hysteresis_arm_slip_angle_deg", self.hysteresis_arm_slip_angle_deg)?;
        pos("hysteresis_arm_slip_ratio", self.hysteresis_arm_slip_ratio)?;
        pos("longitudinal_sweep_min_slip_ratio", self.longitudinal_sweep_min_slip_ratio)?;
        pos("plateau_min_s", self.plateau_min_s)?;
        if !(self.plateau_settle_s.is_finite() && self.plateau_settle_s >= 0.0) {
            return Err(ConfigError::Invalid { key: "plateau_settle_s", reason: "must be finite and ≥ 0" });
        }
        pos("plateau_load_tol_frac", self.plateau_load_tol_frac)?;
        pos("plateau_load_tol_n", self.plateau_load_tol_n)?;
        pos("pressure_tol_pa", self.pressure_tol_pa)?;
        pos("load_case_tol_frac", self.load_case_tol_frac)?;
        pos("re_model_max_slip_angle_deg", self.re_model_max_slip_angle_deg)?;
        let frac = |key: &'static str, v: f64| {
            if v > 0.0 && v < 1.0 { Ok(()) } else { Err(ConfigError::Invalid { key, reason: "must be in (0, 1)" }) }
        };
        frac("static_drag_linear_frac", self.static_drag_linear_frac)?;
        frac("step_steer_saturated_frac", self.step_steer_saturated_frac)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_unknown_keys_are_refused() {
        ChannelsConfig::default().validate().unwrap();
        assert!(ChannelsConfig::from_toml("min_speed_mps = 1.0").is_ok());
        assert!(ChannelsConfig::from_toml("nope = 1").is_err());
        assert!(ChannelsConfig::from_toml("min_speed_mps = -1.0").is_err());
    }
}
