//! The virtual rig's configuration: one TOML file describes the tyre, the rig and every effect.
//!
//! `RigConfig::default()` holds the calibrated values; `launch-config/virtual_rig.toml` carries
//! the same values with a comment on how each was found (a test keeps the two equal). Every
//! parameter section is `#[serde(default)]`, so a config file may name only what it changes.

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// Errors from reading or validating a virtual-rig configuration.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The config file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The TOML did not parse or did not match the schema (unknown key, wrong type, bad effect).
    #[error("{source_name}:{line}:{column}: {message}")]
    Parse {
        /// File name or other label of the text.
        source_name: String,
        /// 1-based line of the offending key/value (0 when unknown).
        line: usize,
        /// 1-based column (0 when unknown).
        column: usize,
        /// What was wrong, as toml/serde report it.
        message: String,
    },
    /// A value parsed but is outside its valid range.
    #[error("{source_name}: invalid `{key}`: {reason}")]
    Invalid {
        /// File name or other label.
        source_name: String,
        /// Dotted key, e.g. `thermal.surface_heat_capacity_j_per_k`.
        key: String,
        /// Why it is invalid.
        reason: String,
    },
}

/// An effect name that `Effects::parse` does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown effect `{name}` (known: none, all, {known})", known = Effects::NAMES.join(", "))]
pub struct UnknownEffect {
    /// The name as given.
    pub name: String,
}

/// Which of the virtual rig's switchable effects are on.
///
/// The steady-state MF-Tyre 6.1 model and the rig's actuators (rate limits, envelope, modes) are
/// always on; everything else can be hidden. Parsed from `"none"`, `"all"` or a comma list of
/// [`Effects::NAMES`]; written back in the same form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Effects {
    /// First-order relaxation of slip angle and slip ratio in travelled distance.
    pub transient: bool,
    /// Surface/bulk/flash tread temperatures from sliding power; without it the tyre stays at its
    /// initial temperature.
    pub thermal: bool,
    /// Grip and stiffness depending on tread temperature.
    pub thermal_grip: bool,
    /// Tread loss from sliding energy, and the worn tyre's stiffer, peakier curves.
    pub wear: bool,
    /// A new tyre's grip deficit that disappears over its first severe sweeps.
    pub break_in: bool,
    /// Sensor noise, coupled-drive noise and slip-ratio control roughness.
    pub noise: bool,
    /// Rig vibration at high load and slip once the tyre is worn.
    pub chatter: bool,
    /// The tyre slipping on the rim when the slip ratio changes faster than the bead holds.
    pub rim_slip: bool,
}

impl Effects {
    /// Every effect name, in canonical order.
    pub const NAMES: [&'static str; 8] =
        ["transient", "thermal", "thermal_grip", "wear", "break_in", "noise", "chatter", "rim_slip"];

    /// All effects on.
    pub const ALL: Effects = Effects {
        transient: true,
        thermal: true,
        thermal_grip: true,
        wear: true,
        break_in: true,
        noise: true,
        chatter: true,
        rim_slip: true,
    };

    /// All effects off: the output is the steady-state MF model at the rig's actual inputs.
    pub const NONE: Effects = Effects {
        transient: false,
        thermal: false,
        thermal_grip: false,
        wear: false,
        break_in: false,
        noise: false,
        chatter: false,
        rim_slip: false,
    };

    /// Parses `"none"`, `"all"` or a comma list such as `"transient,thermal"` (spaces ignored).
    pub fn parse(text: &str) -> Result<Effects, UnknownEffect> {
        let t = text.trim();
        if t.eq_ignore_ascii_case("none") || t.is_empty() {
            return Ok(Effects::NONE);
        }
        if t.eq_ignore_ascii_case("all") {
            return Ok(Effects::ALL);
        }
        let mut e = Effects::NONE;
        for name in t.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            *e.flag_mut(name).ok_or_else(|| UnknownEffect { name: name.to_owned() })? = true;
        }
        Ok(e)
    }

    /// The flag of one effect by name.
    pub fn get(&self, name: &str) -> Option<bool> {
        let mut copy = *self;
        copy.flag_mut(name).map(|f| *f)
    }

    /// Mutable flag of one effect by name (`None` for an unknown name).
    pub fn flag_mut(&mut self, name: &str) -> Option<&mut bool> {
        Some(match name {
            "transient" => &mut self.transient,
            "thermal" => &mut self.thermal,
            "thermal_grip" => &mut self.thermal_grip,
            "wear" => &mut self.wear,
            "break_in" => &mut self.break_in,
            "noise" => &mut self.noise,
            "chatter" => &mut self.chatter,
            "rim_slip" => &mut self.rim_slip,
            _ => return None,
        })
    }
}

impl fmt::Display for Effects {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if *self == Effects::ALL {
            return f.write_str("all");
        }
        let on: Vec<&str> = Effects::NAMES.iter().copied().filter(|n| self.get(n) == Some(true)).collect();
        if on.is_empty() { f.write_str("none") } else { f.write_str(&on.join(",")) }
    }
}

impl FromStr for Effects {
    type Err = UnknownEffect;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Effects::parse(s)
    }
}

impl TryFrom<String> for Effects {
    type Error = UnknownEffect;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        Effects::parse(&s)
    }
}

impl From<Effects> for String {
    fn from(e: Effects) -> String {
        e.to_string()
    }
}

impl Default for Effects {
    fn default() -> Self {
        Effects::ALL
    }
}

/// Which rig the virtual rig imitates: sets actuator rate limits and the envelope.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RigProfile {
    /// An MTS Flat-Trac class machine (the thesis's SoVaMotion rig): fast slip-angle head.
    #[default]
    MtsFlattrac,
    /// A Calspan TIRF class machine: heavy head, slower slip-angle and camber slews.
    CalspanTirf,
}

/// Actuator rate/acceleration limits and the envelope of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigLimits {
    /// Slip-angle slew rate limit [deg/s].
    pub slip_angle_rate_deg_per_s: f64,
    /// Slip-angle acceleration limit [deg/s²].
    pub slip_angle_accel_deg_per_s2: f64,
    /// Slip-ratio rate limit of the drive (coupled mode) [1/s].
    pub slip_ratio_rate_per_s: f64,
    /// Slip-ratio acceleration limit [1/s²].
    pub slip_ratio_accel_per_s2: f64,
    /// Vertical-load rate limit [N/s].
    pub load_rate_n_per_s: f64,
    /// Camber slew rate limit [deg/s].
    pub camber_rate_deg_per_s: f64,
    /// Belt acceleration limit [m/s²].
    pub belt_accel_mps2: f64,
    /// Time constant of the inflation-pressure regulator [s] (≈ 20 s to settle = 4.6 τ).
    pub pressure_time_constant_s: f64,
    /// Envelope: largest |slip angle| [deg].
    pub max_abs_slip_angle_deg: f64,
    /// Envelope: largest |slip ratio| [-].
    pub max_abs_slip_ratio: f64,
    /// Envelope: largest vertical load of the machine [N].
    pub max_load_n: f64,
    /// Envelope: largest |camber| [deg].
    pub max_abs_camber_deg: f64,
    /// Envelope: largest belt speed [m/s].
    pub max_speed_mps: f64,
    /// Envelope: smallest inflation pressure (gauge) [Pa].
    pub min_pressure_pa: f64,
    /// Envelope: largest inflation pressure (gauge) [Pa].
    pub max_pressure_pa: f64,
    /// Envelope: largest |belt displacement| in static mode [m].
    pub max_abs_belt_displacement_m: f64,
}

impl RigLimits {
    /// Limits of an MTS Flat-Trac class rig. The thesis names 30 °/s as the fastest slip-angle
    /// rate its (SoVaMotion) rig allows; the drive can change slip ratio far faster than the
    /// 60 %/s the tyre's bead holds. Accelerations are those of a hydraulic steer head and a
    /// direct drive (0 → 30 °/s in 30 ms, 0 → 60 %/s in 12 ms: ~4 kN·m on the wheel's inertia,
    /// within the 10 kN·m the thesis's rigs drive with).
    pub const MTS_FLATTRAC: RigLimits = RigLimits {
        slip_angle_rate_deg_per_s: 30.0,
        slip_angle_accel_deg_per_s2: 1000.0,
        slip_ratio_rate_per_s: 2.0,
        slip_ratio_accel_per_s2: 50.0,
        load_rate_n_per_s: 20_000.0,
        camber_rate_deg_per_s: 5.0,
        belt_accel_mps2: 3.0,
        pressure_time_constant_s: 4.3,
        max_abs_slip_angle_deg: 30.0,
        max_abs_slip_ratio: 1.0,
        max_load_n: 22_000.0,
        max_abs_camber_deg: 10.0,
        max_speed_mps: 70.0,
        min_pressure_pa: 100_000.0,
        max_pressure_pa: 450_000.0,
        max_abs_belt_displacement_m: 0.2,
    };

    /// Limits of a Calspan TIRF class rig: heavier steer head (slower, gentler slip angle and
    /// camber), higher load capacity, lower top speed.
    pub const CALSPAN_TIRF: RigLimits = RigLimits {
        slip_angle_rate_deg_per_s: 15.0,
        slip_angle_accel_deg_per_s2: 300.0,
        slip_ratio_rate_per_s: 1.5,
        slip_ratio_accel_per_s2: 20.0,
        load_rate_n_per_s: 15_000.0,
        camber_rate_deg_per_s: 3.0,
        belt_accel_mps2: 2.0,
        pressure_time_constant_s: 4.3,
        max_abs_slip_angle_deg: 30.0,
        max_abs_slip_ratio: 1.0,
        max_load_n: 40_000.0,
        max_abs_camber_deg: 10.0,
        max_speed_mps: 55.0,
        min_pressure_pa: 100_000.0,
        max_pressure_pa: 450_000.0,
        max_abs_belt_displacement_m: 0.2,
    };
}

impl RigProfile {
    /// The built-in limits of this profile.
    pub fn limits(self) -> RigLimits {
        match self {
            RigProfile::MtsFlattrac => RigLimits::MTS_FLATTRAC,
            RigProfile::CalspanTirf => RigLimits::CALSPAN_TIRF,
        }
    }
}

/// The rig: profile, optional limit overrides, slip-ratio control and static mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RigSection {
    /// Which machine to imitate.
    pub profile: RigProfile,
    /// Full replacement of the profile's limits (all keys), when present.
    pub limits: Option<RigLimits>,
    /// Slowest slip-ratio rate the drive controls smoothly [1/s] (thesis: 10 %/s).
    pub smooth_slip_ratio_rate_per_s: f64,
    /// Belt speed while moving the belt in static mode [m/s].
    pub static_belt_speed_mps: f64,
}

impl Default for RigSection {
    fn default() -> Self {
        Self {
            profile: RigProfile::MtsFlattrac,
            limits: None,
            smooth_slip_ratio_rate_per_s: 0.10,
            static_belt_speed_mps: 0.02,
        }
    }
}

/// Which tyre model `tyre_file` holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TyreModel {
    /// An MF-Tyre 6.1 property file (`.tir`).
    #[default]
    Mf61,
    /// A physical brush tyre's parameter file (TOML; `crate::brush`, `docs/brush-tyre.md`).
    Brush,
}

/// The tyre specimen: model, tread and load rating.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TyreSection {
    /// What `tyre_file` is: `"mf61"` (default) or `"brush"`.
    pub model: TyreModel,
    /// Tread depth of a new tyre [mm] (thesis tyre: 5.6 mm).
    pub new_tread_depth_mm: f64,
    /// Tread depth at the start of the run [mm].
    pub initial_tread_depth_mm: f64,
    /// Legal minimum tread depth [mm]; below it samples keep coming but `truth()` flags it.
    pub legal_min_tread_depth_mm: f64,
    /// ETRTO load index entered at the rig; loads above `max_load_factor` × Fz0 (Fz0 = 0.65 ×
    /// capacity × 9.81) are refused. A wrong index is the thesis's over-load failure case.
    pub load_index: u32,
    /// Largest load accepted, as a factor of Fz0 (model valid range 0–3 × Fz0).
    pub max_load_factor: f64,
    /// Multiplies the wear rate (a test needs ×5 to wear a tyre out quickly).
    pub wear_rate_multiplier: f64,
}

impl Default for TyreSection {
    fn default() -> Self {
        Self {
            model: TyreModel::Mf61,
            new_tread_depth_mm: 5.6,
            initial_tread_depth_mm: 5.6,
            legal_min_tread_depth_mm: 1.6,
            load_index: 110,
            max_load_factor: 3.0,
            wear_rate_multiplier: 1.0,
        }
    }
}

/// The room and the belt.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvironmentSection {
    /// Air temperature around the rig [°C] (the thesis's room: ~20 °C).
    pub ambient_temp_c: f64,
    /// Belt surface temperature, held by the water/air bearing under it [°C].
    pub belt_temp_c: f64,
    /// Initial tyre temperature, all nodes [°C].
    pub initial_tyre_temp_c: f64,
}

impl Default for EnvironmentSection {
    fn default() -> Self {
        Self { ambient_temp_c: 20.0, belt_temp_c: 22.0, initial_tyre_temp_c: 20.0 }
    }
}

/// `transient`: first-order relaxation in travelled distance with slip-dependent length
/// σ(s) = σ_min + (σ0 − σ_min) / (1 + (|s| / s_half)²), σ0 scaled by (Fz/Fz0)^load_exponent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransientParams {
    /// Lateral relaxation length at zero slip and Fz0 [m] (Rill: ≈0.6 m).
    pub sigma_y0_m: f64,
    /// Slip angle at which the lateral length has fallen most of the way [deg]
    /// (2.31° puts σ at 0.15 m at 4° for σ0 = 0.6 m, as Rill's tyre).
    pub sigma_y_half_slip_deg: f64,
    /// Shortest lateral relaxation length [m].
    pub sigma_y_min_m: f64,
    /// Longitudinal relaxation length at zero slip and Fz0 [m].
    pub sigma_x0_m: f64,
    /// Slip ratio at which the longitudinal length has fallen most of the way [-].
    pub sigma_x_half_slip: f64,
    /// Shortest longitudinal relaxation length [m].
    pub sigma_x_min_m: f64,
    /// Exponent of the load dependence of σ0 [-].
    pub load_exponent: f64,
}

impl Default for TransientParams {
    fn default() -> Self {
        Self {
            sigma_y0_m: 0.7,
            sigma_y_half_slip_deg: 2.31,
            sigma_y_min_m: 0.03,
            sigma_x0_m: 0.43,
            sigma_x_half_slip: 0.02,
            sigma_x_min_m: 0.03,
            load_exponent: 0.3,
        }
    }
}

/// `thermal`: a two-node tread (three surface zones over one bulk node) plus flash temperature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThermalParams {
    /// Heat capacity of the tread surface layer, all three zones together [J/K].
    pub surface_heat_capacity_j_per_k: f64,
    /// Heat capacity of the bulk (tread base, belt package) [J/K].
    pub bulk_heat_capacity_j_per_k: f64,
    /// Conductance surface ↔ bulk [W/K].
    pub surface_bulk_conductance_w_per_k: f64,
    /// Convective conductance of the surface to air at standstill [W/K].
    pub convection_w_per_k: f64,
    /// Extra convective conductance per (m/s)^0.8 of belt speed [W/K].
    pub convection_speed_w_per_k: f64,
    /// Conductance of the surface to the belt (cooled by its bearing) at Fz0 [W/K].
    pub belt_contact_w_per_k: f64,
    /// Conductance of the bulk to air (sidewall, rim) [W/K].
    pub bulk_to_air_w_per_k: f64,
    /// Fraction of lateral sliding power (PY) deposited in the surface layer [-].
    pub surface_fraction_lateral: f64,
    /// Fraction of longitudinal sliding power (PX) deposited in the surface layer [-].
    pub surface_fraction_longitudinal: f64,
    /// Fraction of lateral sliding power deposited in the bulk [-]; what neither the surface
    /// nor the bulk takes goes into the belt (steel under sandpaper, cooled by its bearing).
    pub bulk_fraction_lateral: f64,
    /// Fraction of longitudinal sliding power deposited in the bulk [-].
    pub bulk_fraction_longitudinal: f64,
    /// Rolling-loss power into the bulk per N of load per m/s [W/(N·m/s)] (a rolling
    /// resistance coefficient).
    pub rolling_loss_coefficient: f64,
    /// Flash temperature rise per kW of lateral sliding power, steady [K/kW].
    pub flash_lateral_k_per_kw: f64,
    /// Flash temperature rise per kW of longitudinal sliding power, steady [K/kW]: sliding in
    /// the rolling direction concentrates in the rear of the patch, under the centre laser.
    pub flash_longitudinal_k_per_kw: f64,
    /// Time constant of the lateral flash temperature [s] ("cools in moments").
    pub flash_time_constant_s: f64,
    /// Time constant of the longitudinal flash temperature [s].
    pub flash_longitudinal_time_constant_s: f64,
    /// Heat share of the inner/outer shoulder per degree of camber [1/deg]; negative camber
    /// loads the inner shoulder of a right-side tyre.
    pub camber_zone_share_per_deg: f64,
}

impl Default for ThermalParams {
    fn default() -> Self {
        Self {
            surface_heat_capacity_j_per_k: 6000.0,
            bulk_heat_capacity_j_per_k: 11760.0,
            surface_bulk_conductance_w_per_k: 43.73,
            convection_w_per_k: 8.632,
            convection_speed_w_per_k: 1.223,
            belt_contact_w_per_k: 64.22,
            bulk_to_air_w_per_k: 41.0,
            surface_fraction_lateral: 0.5263,
            // The four longitudinal values: `tune_thermal 120 longitudinal` (see virtual_rig.toml).
            surface_fraction_longitudinal: 0.1666,
            bulk_fraction_lateral: 0.3088,
            bulk_fraction_longitudinal: 0.1355,
            rolling_loss_coefficient: 0.02543,
            flash_lateral_k_per_kw: 0.9575,
            flash_longitudinal_k_per_kw: 2.454,
            flash_time_constant_s: 0.7736,
            flash_longitudinal_time_constant_s: 2.026,
            camber_zone_share_per_deg: 0.05,
        }
    }
}

/// `thermal_grip`: friction and stiffness scale with the grip temperature (surface/bulk mix,
/// no flash): μ factor = max(min, 1 − c·(T − T_opt)²), stiffness factor = 1 − k·(T − T_opt).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThermalGripParams {
    /// Temperature of best grip [°C].
    pub optimum_temp_c: f64,
    /// Quadratic grip loss per K² away from the optimum [1/K²].
    pub grip_loss_per_k2: f64,
    /// Smallest grip factor [-].
    pub min_grip_factor: f64,
    /// Stiffness loss per K above the optimum (gain below) [1/K].
    pub stiffness_per_k: f64,
    /// Weight of the surface temperature in the grip temperature (rest: bulk) [-].
    pub surface_weight: f64,
}

impl Default for ThermalGripParams {
    fn default() -> Self {
        Self {
            optimum_temp_c: 50.0,
            grip_loss_per_k2: 8.0e-5,
            min_grip_factor: 0.7,
            stiffness_per_k: 0.002,
            surface_weight: 0.7,
        }
    }
}

/// `wear`: tread loss ∝ sliding energy; the worn tyre is stiffer and drops off more after the
/// peak (MF scaling λK and λC).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WearParams {
    /// Tread lost per MJ of sliding energy [mm/MJ] (× `tyre.wear_rate_multiplier`).
    pub wear_mm_per_mj: f64,
    /// Cornering/slip stiffness gain per mm of tread lost [1/mm].
    pub stiffness_gain_per_mm: f64,
    /// Shape-factor (λC: drop-off after the peak) gain per mm of tread lost [1/mm].
    pub shape_gain_per_mm: f64,
}

impl Default for WearParams {
    fn default() -> Self {
        Self { wear_mm_per_mj: 0.208, stiffness_gain_per_mm: 0.04, shape_gain_per_mm: 0.02 }
    }
}

/// `break_in`: grip deficit d0·exp(−E/E0) where E is the sliding energy above a power
/// threshold (full sliding, not the gentle warm-up sweeps).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BreakInParams {
    /// Grip deficit of a new tyre [-] (thesis: 5,650 → 6,450 N peak FX, 1 − 5650/6450).
    pub initial_grip_deficit: f64,
    /// Severe sliding energy that reduces the deficit by 1/e [kJ].
    pub energy_scale_kj: f64,
    /// Sliding power above which energy counts as severe [kW].
    pub power_threshold_kw: f64,
}

impl Default for BreakInParams {
    fn default() -> Self {
        Self { initial_grip_deficit: 0.124, energy_scale_kj: 150.0, power_threshold_kw: 10.0 }
    }
}

/// `noise`: white Gaussian noise per channel (1σ), the coupled drive's extra noise, and the
/// slip-ratio controller's roughness below its smooth rate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NoiseParams {
    /// FX [N].
    pub fx_n: f64,
    /// FYW [N].
    pub fy_n: f64,
    /// FZW [N].
    pub fz_n: f64,
    /// MXW [N·m].
    pub mx_nm: f64,
    /// MYW [N·m].
    pub my_nm: f64,
    /// MZW [N·m].
    pub mz_nm: f64,
    /// SLIPANGL [deg].
    pub slip_angle_deg: f64,
    /// LONGSLIP [-].
    pub slip_ratio: f64,
    /// INCLANGL [deg].
    pub camber_deg: f64,
    /// INFLPRES [Pa].
    pub pressure_pa: f64,
    /// TRAJVELW [m/s].
    pub speed_mps: f64,
    /// DSTWOWHC before the 0.1 mm quantisation [m].
    pub radius_m: f64,
    /// TRDTEMP* [°C].
    pub temp_c: f64,
    /// Noise gain on FX when the drive is coupled [-].
    pub coupled_fx_gain: f64,
    /// Noise gain on MXW when the drive is coupled (thesis: MX unusable in BrkDrv) [-].
    pub coupled_mx_gain: f64,
    /// Noise gain on MYW/MZW when the drive is coupled [-].
    pub coupled_moment_gain: f64,
    /// Slip-ratio wander (1σ) of the controller when changing slip slower than its smooth rate,
    /// at zero rate [-]; fades linearly to 0 at the smooth rate.
    pub slow_control_slip_ratio: f64,
    /// Slip-ratio wander (1σ) of the coupled drive at any rate [-].
    pub coupled_slip_ratio: f64,
    /// Correlation time of the controller wander [s].
    pub control_time_constant_s: f64,
}

impl Default for NoiseParams {
    fn default() -> Self {
        Self {
            fx_n: 30.0,
            fy_n: 40.0,
            fz_n: 25.0,
            mx_nm: 3.0,
            my_nm: 2.0,
            mz_nm: 3.0,
            slip_angle_deg: 0.01,
            slip_ratio: 0.0003,
            camber_deg: 0.01,
            pressure_pa: 200.0,
            speed_mps: 0.01,
            radius_m: 0.00003,
            temp_c: 0.3,
            coupled_fx_gain: 2.0,
            coupled_mx_gain: 25.0,
            coupled_moment_gain: 3.0,
            slow_control_slip_ratio: 0.002,
            coupled_slip_ratio: 0.0003,
            control_time_constant_s: 0.05,
        }
    }
}

/// `chatter`: rig vibration at high load and slip once the tyre is worn. Amplitude =
/// gain × (wear − onset) × (Fz/Fz0 − onset) × slip severity, at a fixed frequency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ChatterParams {
    /// Tread lost before chatter can appear [mm].
    pub onset_wear_mm: f64,
    /// Load factor of Fz0 above which chatter can appear [-].
    pub onset_load_factor: f64,
    /// Slip angle beyond which chatter grows [deg] (slip ratio: this / 100 rad-equivalent).
    pub onset_slip_angle_deg: f64,
    /// Slip ratio beyond which chatter grows [-].
    pub onset_slip_ratio: f64,
    /// Force amplitude per mm of excess wear per unit of excess load factor at full severity [N].
    pub amplitude_n: f64,
    /// Vibration frequency [Hz].
    pub frequency_hz: f64,
}

impl Default for ChatterParams {
    fn default() -> Self {
        Self {
            onset_wear_mm: 1.5,
            onset_load_factor: 1.2,
            onset_slip_angle_deg: 8.0,
            onset_slip_ratio: 0.12,
            amplitude_n: 1500.0,
            frequency_hz: 23.0,
        }
    }
}

/// `rim_slip`: above this slip-ratio rate the tyre turns on the rim, so the rim's (measured)
/// slip ratio runs ahead of the tread's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RimSlipParams {
    /// Largest slip-ratio rate the bead holds [1/s] (thesis: 60 %/s).
    pub max_slip_ratio_rate_per_s: f64,
    /// Longitudinal force below which the bead never slips [N].
    pub min_force_n: f64,
}

impl Default for RimSlipParams {
    fn default() -> Self {
        Self { max_slip_ratio_rate_per_s: 0.60, min_force_n: 1500.0 }
    }
}

/// The whole virtual-rig configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigConfig {
    /// The tyre's file, relative to the config file (or absolute): an MF-Tyre 6.1 `.tir`, or a
    /// brush-tyre TOML file when `[tyre] model = "brush"`.
    pub tyre_file: PathBuf,
    /// Seed of the noise generator (ChaCha8); the same config and seed give identical samples.
    #[serde(default)]
    pub seed: u64,
    /// Internal integration rate [Hz] (≥ 1,000).
    #[serde(default = "default_internal_rate")]
    pub internal_rate_hz: u32,
    /// Sample publish rate [Hz] (≤ internal rate and dividing it; 100 default, up to 1,000).
    #[serde(default = "default_publish_rate")]
    pub publish_rate_hz: u32,
    /// The tyre model, thermal and wear update rate [Hz] (dividing the internal rate); actuators
    /// and relaxation run at the internal rate. Samples always see a fresh model evaluation.
    #[serde(default = "default_model_rate")]
    pub model_rate_hz: u32,
    /// Effects switched on: `"all"`, `"none"` or a comma list.
    #[serde(default)]
    pub effects: Effects,
    /// The rig.
    #[serde(default)]
    pub rig: RigSection,
    /// The tyre specimen.
    #[serde(default)]
    pub tyre: TyreSection,
    /// Room and belt.
    #[serde(default)]
    pub environment: EnvironmentSection,
    /// `transient` parameters.
    #[serde(default)]
    pub transient: TransientParams,
    /// `thermal` parameters.
    #[serde(default)]
    pub thermal: ThermalParams,
    /// `thermal_grip` parameters.
    #[serde(default)]
    pub thermal_grip: ThermalGripParams,
    /// `wear` parameters.
    #[serde(default)]
    pub wear: WearParams,
    /// `break_in` parameters.
    #[serde(default)]
    pub break_in: BreakInParams,
    /// `noise` parameters.
    #[serde(default)]
    pub noise: NoiseParams,
    /// `chatter` parameters.
    #[serde(default)]
    pub chatter: ChatterParams,
    /// `rim_slip` parameters.
    #[serde(default)]
    pub rim_slip: RimSlipParams,
}

fn default_internal_rate() -> u32 {
    1000
}
fn default_publish_rate() -> u32 {
    100
}
fn default_model_rate() -> u32 {
    100
}

/// The default virtual tyre, relative to `launch-config/`.
pub const DEFAULT_TYRE_FILE: &str = "tyres/MagicFormula61_Paramerters.tir";

impl Default for RigConfig {
    fn default() -> Self {
        Self {
            tyre_file: PathBuf::from(DEFAULT_TYRE_FILE),
            seed: 0,
            internal_rate_hz: default_internal_rate(),
            publish_rate_hz: default_publish_rate(),
            model_rate_hz: default_model_rate(),
            effects: Effects::ALL,
            rig: RigSection::default(),
            tyre: TyreSection::default(),
            environment: EnvironmentSection::default(),
            transient: TransientParams::default(),
            thermal: ThermalParams::default(),
            thermal_grip: ThermalGripParams::default(),
            wear: WearParams::default(),
            break_in: BreakInParams::default(),
            noise: NoiseParams::default(),
            chatter: ChatterParams::default(),
            rim_slip: RimSlipParams::default(),
        }
    }
}

/// ETRTO load capacity [kg] for load indices 60–130 (reference §4).
const LOAD_CAPACITY_KG: [u32; 71] = [
    250, 257, 265, 272, 280, 290, 300, 307, 315, 325, 335, 345, 355, 365, 375, 387, 400, 412, 425, 437, 450, 462, 475,
    487, 500, 515, 530, 545, 560, 580, 600, 615, 630, 650, 670, 690, 710, 730, 750, 775, 800, 825, 850, 875, 900, 925,
    950, 975, 1000, 1030, 1060, 1090, 1120, 1150, 1180, 1215, 1250, 1285, 1320, 1360, 1400, 1450, 1500, 1550, 1600,
    1650, 1700, 1750, 1800, 1850, 1900,
];

/// ETRTO load capacity [kg] of a load index, if in the 60–130 table.
pub fn load_capacity_kg(load_index: u32) -> Option<f64> {
    let i = load_index.checked_sub(60)? as usize;
    LOAD_CAPACITY_KG.get(i).map(|&kg| f64::from(kg))
}

/// Nominal load Fz0 = 0.65 × capacity × 9.81 [N] of a load index (110 → 6,752 N).
pub fn nominal_load_n(load_index: u32) -> Option<f64> {
    load_capacity_kg(load_index).map(|kg| 0.65 * kg * 9.81)
}

impl RigConfig {
    /// Parses a config from TOML text; `source_name` labels errors (usually the file path).
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<RigConfig, ConfigError> {
        let cfg: RigConfig = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map(|s| line_col(text, s.start)).unwrap_or((0, 0));
            ConfigError::Parse { source_name: source_name.to_owned(), line, column, message: e.message().to_owned() }
        })?;
        cfg.validate().map_err(|(key, reason)| ConfigError::Invalid {
            source_name: source_name.to_owned(),
            key,
            reason,
        })?;
        Ok(cfg)
    }

    /// Reads and validates a config file; `tyre_file` is resolved relative to it.
    pub fn load(path: &Path) -> Result<RigConfig, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io { path: path.to_owned(), source })?;
        let mut cfg = RigConfig::from_toml_str(&text, &path.display().to_string())?;
        if cfg.tyre_file.is_relative() {
            let dir = path.parent().unwrap_or_else(|| Path::new("."));
            cfg.tyre_file = dir.join(&cfg.tyre_file);
        }
        Ok(cfg)
    }

    /// The active rig limits (profile, or the override table).
    pub fn limits(&self) -> RigLimits {
        self.rig.limits.unwrap_or_else(|| self.rig.profile.limits())
    }

    /// Internal step [s].
    pub fn dt_s(&self) -> f64 {
        1.0 / f64::from(self.internal_rate_hz)
    }

    /// Checks ranges and rate divisibility; on failure returns (dotted key, reason).
    pub fn validate(&self) -> Result<(), (String, String)> {
        fn bad(key: &str, reason: impl Into<String>) -> Result<(), (String, String)> {
            Err((key.to_owned(), reason.into()))
        }
        if self.internal_rate_hz < 1000 || self.internal_rate_hz > 100_000 {
            return bad("internal_rate_hz", "must be 1000..=100000 Hz");
        }
        if self.publish_rate_hz == 0
            || self.publish_rate_hz > 1000
            || !self.internal_rate_hz.is_multiple_of(self.publish_rate_hz)
        {
            return bad("publish_rate_hz", "must be 1..=1000 Hz and divide internal_rate_hz");
        }
        if self.model_rate_hz == 0
            || self.model_rate_hz > self.internal_rate_hz
            || !self.internal_rate_hz.is_multiple_of(self.model_rate_hz)
        {
            return bad("model_rate_hz", "must divide internal_rate_hz");
        }
        let t = &self.tyre;
        if nominal_load_n(t.load_index).is_none() {
            return bad("tyre.load_index", "must be an ETRTO load index 60..=130");
        }
        if !(t.new_tread_depth_mm > 0.0 && t.new_tread_depth_mm < 30.0) {
            return bad("tyre.new_tread_depth_mm", "must be in (0, 30) mm");
        }
        if !(t.initial_tread_depth_mm >= 0.0 && t.initial_tread_depth_mm <= t.new_tread_depth_mm) {
            return bad("tyre.initial_tread_depth_mm", "must be in [0, new_tread_depth_mm]");
        }
        if !(t.legal_min_tread_depth_mm >= 0.0 && t.legal_min_tread_depth_mm < t.new_tread_depth_mm) {
            return bad("tyre.legal_min_tread_depth_mm", "must be in [0, new_tread_depth_mm)");
        }
        if !(t.max_load_factor > 0.0 && t.max_load_factor <= 5.0) {
            return bad("tyre.max_load_factor", "must be in (0, 5]");
        }
        if !(t.wear_rate_multiplier >= 0.0 && t.wear_rate_multiplier.is_finite()) {
            return bad("tyre.wear_rate_multiplier", "must be finite and ≥ 0");
        }
        let e = &self.environment;
        for (k, v) in [
            ("environment.ambient_temp_c", e.ambient_temp_c),
            ("environment.belt_temp_c", e.belt_temp_c),
            ("environment.initial_tyre_temp_c", e.initial_tyre_temp_c),
        ] {
            if !(-40.0..=80.0).contains(&v) {
                return bad(k, "must be in −40..=80 °C");
            }
        }
        let l = self.limits();
        for (k, v) in [
            ("rig.limits.slip_angle_rate_deg_per_s", l.slip_angle_rate_deg_per_s),
            ("rig.limits.slip_angle_accel_deg_per_s2", l.slip_angle_accel_deg_per_s2),
            ("rig.limits.slip_ratio_rate_per_s", l.slip_ratio_rate_per_s),
            ("rig.limits.slip_ratio_accel_per_s2", l.slip_ratio_accel_per_s2),
            ("rig.limits.load_rate_n_per_s", l.load_rate_n_per_s),
            ("rig.limits.camber_rate_deg_per_s", l.camber_rate_deg_per_s),
            ("rig.limits.belt_accel_mps2", l.belt_accel_mps2),
            ("rig.limits.pressure_time_constant_s", l.pressure_time_constant_s),
            ("rig.limits.max_abs_slip_angle_deg", l.max_abs_slip_angle_deg),
            ("rig.limits.max_abs_slip_ratio", l.max_abs_slip_ratio),
            ("rig.limits.max_load_n", l.max_load_n),
            ("rig.limits.max_abs_camber_deg", l.max_abs_camber_deg),
            ("rig.limits.max_speed_mps", l.max_speed_mps),
            ("rig.limits.min_pressure_pa", l.min_pressure_pa),
            ("rig.limits.max_pressure_pa", l.max_pressure_pa),
            ("rig.limits.max_abs_belt_displacement_m", l.max_abs_belt_displacement_m),
            ("rig.smooth_slip_ratio_rate_per_s", self.rig.smooth_slip_ratio_rate_per_s),
            ("rig.static_belt_speed_mps", self.rig.static_belt_speed_mps),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, "must be finite and > 0");
            }
        }
        let tr = &self.transient;
        for (k, v) in [
            ("transient.sigma_y0_m", tr.sigma_y0_m),
            ("transient.sigma_y_half_slip_deg", tr.sigma_y_half_slip_deg),
            ("transient.sigma_y_min_m", tr.sigma_y_min_m),
            ("transient.sigma_x0_m", tr.sigma_x0_m),
            ("transient.sigma_x_half_slip", tr.sigma_x_half_slip),
            ("transient.sigma_x_min_m", tr.sigma_x_min_m),
        ] {
            if !(v.is_finite() && v > 0.0 && v < 10.0) {
                return bad(k, "must be in (0, 10)");
            }
        }
        if !(0.0..=2.0).contains(&tr.load_exponent) {
            return bad("transient.load_exponent", "must be in 0..=2");
        }
        let th = &self.thermal;
        for (k, v) in [
            ("thermal.surface_heat_capacity_j_per_k", th.surface_heat_capacity_j_per_k),
            ("thermal.bulk_heat_capacity_j_per_k", th.bulk_heat_capacity_j_per_k),
            ("thermal.flash_time_constant_s", th.flash_time_constant_s),
            ("thermal.flash_longitudinal_time_constant_s", th.flash_longitudinal_time_constant_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, "must be finite and > 0");
            }
        }
        for (k, v) in [
            ("thermal.surface_bulk_conductance_w_per_k", th.surface_bulk_conductance_w_per_k),
            ("thermal.convection_w_per_k", th.convection_w_per_k),
            ("thermal.convection_speed_w_per_k", th.convection_speed_w_per_k),
            ("thermal.belt_contact_w_per_k", th.belt_contact_w_per_k),
            ("thermal.bulk_to_air_w_per_k", th.bulk_to_air_w_per_k),
            ("thermal.rolling_loss_coefficient", th.rolling_loss_coefficient),
            ("thermal.flash_lateral_k_per_kw", th.flash_lateral_k_per_kw),
            ("thermal.flash_longitudinal_k_per_kw", th.flash_longitudinal_k_per_kw),
            ("thermal_grip.grip_loss_per_k2", self.thermal_grip.grip_loss_per_k2),
            ("thermal_grip.stiffness_per_k", self.thermal_grip.stiffness_per_k.abs()),
            ("wear.wear_mm_per_mj", self.wear.wear_mm_per_mj),
            ("wear.stiffness_gain_per_mm", self.wear.stiffness_gain_per_mm.abs()),
            ("wear.shape_gain_per_mm", self.wear.shape_gain_per_mm.abs()),
            ("break_in.power_threshold_kw", self.break_in.power_threshold_kw),
            ("chatter.amplitude_n", self.chatter.amplitude_n),
            ("rim_slip.min_force_n", self.rim_slip.min_force_n),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, "must be finite and ≥ 0");
            }
        }
        for (k, v) in [
            ("thermal.surface_fraction_lateral", th.surface_fraction_lateral),
            ("thermal.surface_fraction_longitudinal", th.surface_fraction_longitudinal),
            ("thermal_grip.surface_weight", self.thermal_grip.surface_weight),
            ("thermal_grip.min_grip_factor", self.thermal_grip.min_grip_factor),
            ("break_in.initial_grip_deficit", self.break_in.initial_grip_deficit),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(k, "must be in 0..=1");
            }
        }
        for (k, v) in [
            ("thermal.bulk_fraction_lateral", th.surface_fraction_lateral + th.bulk_fraction_lateral),
            ("thermal.bulk_fraction_longitudinal", th.surface_fraction_longitudinal + th.bulk_fraction_longitudinal),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(k, "must be ≥ 0 and, with the surface fraction, ≤ 1");
            }
        }
        if !(0.0..=0.3).contains(&th.camber_zone_share_per_deg) {
            return bad("thermal.camber_zone_share_per_deg", "must be in 0..=0.3");
        }
        if !(self.break_in.energy_scale_kj.is_finite() && self.break_in.energy_scale_kj > 0.0) {
            return bad("break_in.energy_scale_kj", "must be finite and > 0");
        }
        if !(self.chatter.frequency_hz > 0.0 && self.chatter.frequency_hz < f64::from(self.internal_rate_hz) / 2.0) {
            return bad("chatter.frequency_hz", "must be in (0, internal_rate_hz / 2)");
        }
        if !(self.rim_slip.max_slip_ratio_rate_per_s > 0.0 && self.rim_slip.max_slip_ratio_rate_per_s.is_finite()) {
            return bad("rim_slip.max_slip_ratio_rate_per_s", "must be finite and > 0");
        }
        let n = &self.noise;
        for (k, v) in [
            ("noise.fx_n", n.fx_n),
            ("noise.fy_n", n.fy_n),
            ("noise.fz_n", n.fz_n),
            ("noise.mx_nm", n.mx_nm),
            ("noise.my_nm", n.my_nm),
            ("noise.mz_nm", n.mz_nm),
            ("noise.slip_angle_deg", n.slip_angle_deg),
            ("noise.slip_ratio", n.slip_ratio),
            ("noise.camber_deg", n.camber_deg),
            ("noise.pressure_pa", n.pressure_pa),
            ("noise.speed_mps", n.speed_mps),
            ("noise.radius_m", n.radius_m),
            ("noise.temp_c", n.temp_c),
            ("noise.coupled_fx_gain", n.coupled_fx_gain),
            ("noise.coupled_mx_gain", n.coupled_mx_gain),
            ("noise.coupled_moment_gain", n.coupled_moment_gain),
            ("noise.slow_control_slip_ratio", n.slow_control_slip_ratio),
            ("noise.coupled_slip_ratio", n.coupled_slip_ratio),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, "must be finite and ≥ 0");
            }
        }
        if !(n.control_time_constant_s.is_finite() && n.control_time_constant_s > 0.0) {
            return bad("noise.control_time_constant_s", "must be finite and > 0");
        }
        Ok(())
    }
}

/// 1-based (line, column) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effects_parse_and_print() {
        assert_eq!(Effects::parse("all").unwrap(), Effects::ALL);
        assert_eq!(Effects::parse("none").unwrap(), Effects::NONE);
        let e = Effects::parse("transient, thermal").unwrap();
        assert!(e.transient && e.thermal && !e.wear);
        assert_eq!(e.to_string(), "transient,thermal");
        let err = Effects::parse("transient,thermol").unwrap_err();
        assert_eq!(err.name, "thermol");
        assert!(err.to_string().contains("thermol"));
    }

    #[test]
    fn load_index_110_is_6752_n() {
        assert!((nominal_load_n(110).unwrap() - 6759.09).abs() < 0.1);
        assert!(nominal_load_n(59).is_none());
        assert!(nominal_load_n(131).is_none());
    }

    #[test]
    fn unknown_key_names_line() {
        let text = "tyre_file = \"x.tir\"\n[thermal]\nflash_time_constant_s = 0.5\nbogus = 1\n";
        let err = RigConfig::from_toml_str(text, "t.toml").unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with("t.toml:4:"), "{msg}");
        assert!(msg.contains("bogus"), "{msg}");
    }

    #[test]
    fn bad_effect_in_file_is_named() {
        let err =
            RigConfig::from_toml_str("tyre_file = \"x.tir\"\neffects = \"thermal,warp\"\n", "t.toml").unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("warp") && msg.contains("t.toml:2"), "{msg}");
    }

    #[test]
    fn invalid_value_names_key() {
        let err = RigConfig::from_toml_str("tyre_file = \"x.tir\"\npublish_rate_hz = 333\n", "t.toml").unwrap_err();
        assert!(err.to_string().contains("publish_rate_hz"), "{err}");
    }
}
