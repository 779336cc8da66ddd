//! The setpoint a trajectory yields, and the rig envelope it must stay inside.

use serde::{Deserialize, Serialize};

/// Rig mode (mirrors `RigSetpoint.MODE_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RigMode {
    /// Drive un-coupled: the tyre rolls freely.
    #[default]
    FreeRolling,
    /// Drive coupled: slip ratio controlled.
    Coupled,
    /// Wheel locked (or rolling at creep speed), belt moved: static longitudinal, step-steer.
    Static,
    /// Safe state: slip to zero, load off, belt stopped.
    Safe,
}

impl RigMode {
    /// The `RigSetpoint.MODE_*` value.
    pub fn as_msg_mode(self) -> u8 {
        match self {
            Self::FreeRolling => 0,
            Self::Coupled => 1,
            Self::Static => 2,
            Self::Safe => 3,
        }
    }
}

/// One setpoint of every controlled axis (ISO-W, right-side tyre), as a trajectory yields it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Setpoint {
    /// Rig mode.
    pub mode: RigMode,
    /// Slip angle \[deg\].
    pub slip_angle_deg: f64,
    /// Slip ratio \[-\] (coupled mode).
    pub slip_ratio: f64,
    /// Vertical load \[N\].
    pub fz_n: f64,
    /// Camber (inclination) \[deg\].
    pub camber_deg: f64,
    /// Inflation pressure (gauge) \[bar\].
    pub pressure_bar: f64,
    /// Belt speed \[m/s\].
    pub speed_mps: f64,
    /// Static mode: belt displacement from the lock point \[m\].
    pub belt_displacement_m: f64,
}

impl Setpoint {
    /// The same setpoint with slip angle and slip ratio at zero (thermal pause, pause hold).
    pub fn zero_slip(mut self) -> Self {
        self.slip_angle_deg = 0.0;
        self.slip_ratio = 0.0;
        self.belt_displacement_m = 0.0;
        self
    }

    /// Linear blend `a + (b − a)·f` of the continuous axes; the mode is `a`'s until `f` = 1.
    pub fn lerp(a: &Self, b: &Self, f: f64) -> Self {
        let l = |x: f64, y: f64| x + (y - x) * f;
        Self {
            mode: if f >= 1.0 { b.mode } else { a.mode },
            slip_angle_deg: l(a.slip_angle_deg, b.slip_angle_deg),
            slip_ratio: l(a.slip_ratio, b.slip_ratio),
            fz_n: l(a.fz_n, b.fz_n),
            camber_deg: l(a.camber_deg, b.camber_deg),
            pressure_bar: l(a.pressure_bar, b.pressure_bar),
            speed_mps: l(a.speed_mps, b.speed_mps),
            belt_displacement_m: l(a.belt_displacement_m, b.belt_displacement_m),
        }
    }
}

/// Bar → pascal.
pub const PA_PER_BAR: f64 = 1e5;

/// The rig's envelope (what it may be asked for) and its profile limits (how fast it moves).
///
/// Defaults describe a Calspan/MTS-class flat-track machine as the thesis used them: the model's
/// validity range (SA ±25°, SR ±0.5, camber ±6°), loads to 3 × Fz0 of a large SUV tyre, the
/// fastest slip rates the thesis ran (30 °/s, 60 %/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RigLimits {
    /// Largest |slip angle| \[deg\].
    pub max_slip_angle_deg: f64,
    /// Largest |slip ratio| \[-\].
    pub max_slip_ratio: f64,
    /// Largest vertical load \[N\].
    pub max_fz_n: f64,
    /// Smallest vertical load while the tyre is loaded \[N\] (safe state may go below).
    pub min_fz_n: f64,
    /// Largest |camber| \[deg\].
    pub max_camber_deg: f64,
    /// Largest belt speed \[m/s\].
    pub max_speed_mps: f64,
    /// Lowest inflation pressure \[bar\].
    pub min_pressure_bar: f64,
    /// Highest inflation pressure \[bar\].
    pub max_pressure_bar: f64,
    /// Largest |belt displacement| in static mode \[m\].
    pub max_belt_displacement_m: f64,
    /// Fastest slip-angle slew \[deg/s\] (the thesis's "fastest the rig allows": 30 °/s).
    pub max_slip_angle_rate_dps: f64,
    /// Fastest slip-ratio slew \[1/s\] (60 %/s: faster makes the tyre slip on the rim).
    pub max_slip_ratio_rate_ps: f64,
    /// Load slew used for settles and vertical-load sweeps \[N/s\].
    pub load_rate_nps: f64,
    /// Camber slew used for settles \[deg/s\].
    pub camber_rate_dps: f64,
    /// Belt acceleration used for settles \[m/s²\].
    pub speed_accel_mps2: f64,
    /// Time to change inflation pressure \[s\] (the thesis: "around 20 s").
    pub pressure_change_s: f64,
    /// Dwell added to every settle so the load case is steady before data \[s\].
    pub settle_dwell_s: f64,
}

impl Default for RigLimits {
    fn default() -> Self {
        Self {
            max_slip_angle_deg: 30.0,
            max_slip_ratio: 0.5,
            max_fz_n: 25_000.0,
            min_fz_n: 200.0,
            max_camber_deg: 10.0,
            max_speed_mps: 60.0,
            min_pressure_bar: 1.0,
            max_pressure_bar: 4.5,
            max_belt_displacement_m: 0.5,
            max_slip_angle_rate_dps: 30.0,
            max_slip_ratio_rate_ps: 0.6,
            load_rate_nps: 10_000.0,
            camber_rate_dps: 5.0,
            speed_accel_mps2: 4.0,
            pressure_change_s: 20.0,
            settle_dwell_s: 1.0,
        }
    }
}

/// A setpoint outside the rig envelope: which axis, its value and the limit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{axis} = {value} is outside the rig envelope (limit {limit})")]
pub struct EnvelopeViolation {
    /// Axis name with unit, e.g. `fz_n`.
    pub axis: &'static str,
    /// The requested value.
    pub value: f64,
    /// The limit it broke.
    pub limit: f64,
}

impl RigLimits {
    /// Check a setpoint against the envelope. The safe state is always allowed.
    pub fn check(&self, sp: &Setpoint) -> Result<(), EnvelopeViolation> {
        if sp.mode == RigMode::Safe {
            return Ok(());
        }
        let checks: [(&'static str, f64, f64, f64); 7] = [
            ("slip_angle_deg", sp.slip_angle_deg, -self.max_slip_angle_deg, self.max_slip_angle_deg),
            ("slip_ratio", sp.slip_ratio, -self.max_slip_ratio, self.max_slip_ratio),
            ("fz_n", sp.fz_n, self.min_fz_n, self.max_fz_n),
            ("camber_deg", sp.camber_deg, -self.max_camber_deg, self.max_camber_deg),
            ("speed_mps", sp.speed_mps, 0.0, self.max_speed_mps),
            ("pressure_bar", sp.pressure_bar, self.min_pressure_bar, self.max_pressure_bar),
            (
                "belt_displacement_m",
                sp.belt_displacement_m,
                -self.max_belt_displacement_m,
                self.max_belt_displacement_m,
            ),
        ];
        for (axis, value, lo, hi) in checks {
            // NaN fails both comparisons' negation, so it is refused too.
            if !(value >= lo && value <= hi) {
                let limit = if value.is_nan() || value < lo { lo } else { hi };
                return Err(EnvelopeViolation { axis, value, limit });
            }
        }
        Ok(())
    }

    /// Check the limits themselves (positive rates, ordered ranges).
    pub fn validate(&self) -> Result<(), String> {
        let pos = [
            ("max_slip_angle_deg", self.max_slip_angle_deg),
            ("max_slip_ratio", self.max_slip_ratio),
            ("max_fz_n", self.max_fz_n),
            ("max_camber_deg", self.max_camber_deg),
            ("max_speed_mps", self.max_speed_mps),
            ("max_pressure_bar", self.max_pressure_bar),
            ("max_slip_angle_rate_dps", self.max_slip_angle_rate_dps),
            ("max_slip_ratio_rate_ps", self.max_slip_ratio_rate_ps),
            ("load_rate_nps", self.load_rate_nps),
            ("camber_rate_dps", self.camber_rate_dps),
            ("speed_accel_mps2", self.speed_accel_mps2),
        ];
        for (k, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{k} must be a positive number, got {v}"));
            }
        }
        let nonneg = [
            ("min_fz_n", self.min_fz_n),
            ("min_pressure_bar", self.min_pressure_bar),
            ("max_belt_displacement_m", self.max_belt_displacement_m),
            ("pressure_change_s", self.pressure_change_s),
            ("settle_dwell_s", self.settle_dwell_s),
        ];
        for (k, v) in nonneg {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{k} must be a non-negative number, got {v}"));
            }
        }
        if self.min_fz_n >= self.max_fz_n {
            return Err("min_fz_n must be below max_fz_n".into());
        }
        if self.min_pressure_bar >= self.max_pressure_bar {
            return Err("min_pressure_bar must be below max_pressure_bar".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_refuses_each_axis_and_nan() {
        let lim = RigLimits::default();
        let ok = Setpoint { fz_n: 5000.0, pressure_bar: 2.6, speed_mps: 16.6, ..Setpoint::default() };
        assert!(lim.check(&ok).is_ok());
        let e = lim.check(&Setpoint { fz_n: 30_000.0, ..ok }).unwrap_err();
        assert_eq!(e.axis, "fz_n");
        assert_eq!(e.limit, 25_000.0);
        let e = lim.check(&Setpoint { slip_angle_deg: -31.0, ..ok }).unwrap_err();
        assert_eq!(e.axis, "slip_angle_deg");
        let e = lim.check(&Setpoint { camber_deg: f64::NAN, ..ok }).unwrap_err();
        assert_eq!(e.axis, "camber_deg");
        // Safe state always passes: it is what the rig falls back to.
        assert!(lim.check(&Setpoint { mode: RigMode::Safe, fz_n: 0.0, ..ok }).is_ok());
        assert!(lim.validate().is_ok());
    }
}
