//! The virtual flat-track rig: actuators, tyre state, effects and sample generation.

use std::path::Path;

use mftyre::{MfOutput, ScalingFactors, TyreParams};
use tyre_msgs::msg::{RigSample, RigSetpoint};
use tyre_msgs::std_msgs::Header;

use crate::config::{ConfigError, Effects, RigConfig, RigLimits, nominal_load_n};
use crate::noise::Gauss;
use crate::thermal::{ThermalInput, ThermalState};
use crate::tyre::{TyreScaling, TyreState, VirtualTyre};

/// Errors building a virtual rig.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The rig config is unreadable or invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The tyre property file is unreadable or invalid.
    #[error("tyre file {path}: {source}")]
    Tyre {
        /// The `.tir` path.
        path: String,
        /// The reader's error.
        #[source]
        source: mftyre::TirError,
    },
    /// The brush-tyre parameter file is unreadable or invalid.
    #[error(transparent)]
    Brush(#[from] crate::brush::BrushError),
    /// The config does not validate (when built from a value rather than a file).
    #[error("invalid `{key}`: {reason}")]
    Invalid {
        /// Dotted config key.
        key: String,
        /// Why.
        reason: String,
    },
    /// The tyre file's nominal load, radius or pressure is unusable.
    #[error("tyre parameters: {0}")]
    TyreValues(String),
}

/// Why a setpoint was refused. The rig goes to (and holds) its safe state and flags
/// `FAULT_ENVELOPE` until a valid setpoint arrives.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SetpointRefusal {
    /// `mode` is not one of `RigSetpoint::MODE_*`.
    #[error("unknown mode {0}")]
    UnknownMode(u8),
    /// A numeric field is NaN or infinite.
    #[error("`{field}` is not finite ({value})")]
    NotFinite {
        /// The setpoint field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A field is outside the rig's envelope or the tyre's load rating.
    #[error("`{field}` = {value} outside the envelope [{min}, {max}] ({limit})")]
    OutOfEnvelope {
        /// The setpoint field.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Smallest accepted value.
        min: f64,
        /// Largest accepted value.
        max: f64,
        /// Which limit (rig profile or tyre load rating).
        limit: &'static str,
    },
}

/// The hidden true state of the virtual tyre, for tests and for monitors that compare what
/// the rig measures with what really happened.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthState {
    /// Rig time [s].
    pub time_s: f64,
    /// Remaining tread depth [mm].
    pub tread_depth_mm: f64,
    /// Tread lost so far [mm].
    pub tread_worn_mm: f64,
    /// Surface temperatures inner/centre/outer without flash [°C].
    pub surface_temp_c: [f64; 3],
    /// Bulk temperature [°C].
    pub bulk_temp_c: f64,
    /// Flash temperature rise on top of the surface [K].
    pub flash_temp_k: f64,
    /// Grip temperature (surface/bulk mix) [°C].
    pub grip_temp_c: f64,
    /// Product of thermal, break-in grip factors applied to λμx and λμy [-].
    pub grip_factor: f64,
    /// Stiffness factor applied to λKx and λKy (thermal × wear) [-].
    pub stiffness_factor: f64,
    /// Remaining break-in grip deficit [-] (0 when broken in).
    pub break_in_deficit: f64,
    /// Total sliding energy dissipated [J].
    pub sliding_energy_j: f64,
    /// Severe sliding energy counted for break-in [J].
    pub severe_sliding_energy_j: f64,
    /// Present sliding power [W].
    pub sliding_power_w: f64,
    /// Slip angle the tyre's contact patch sees after relaxation [deg].
    pub relaxed_slip_angle_deg: f64,
    /// Slip ratio the contact patch sees after relaxation, rim slip and control wander [-].
    pub relaxed_slip_ratio: f64,
    /// Accumulated rim-slip (tyre turning on the rim) events, in samples with slip [-].
    pub rim_slip_steps: u64,
    /// Whether the tread is below the legal minimum.
    pub below_legal_minimum: bool,
    /// Whether the rig is in its safe state.
    pub safe: bool,
}

/// A rate- and acceleration-limited position servo (slip angle, slip ratio) following a
/// streamed trajectory: velocity feed-forward from the last two setpoints, so a ramp is
/// tracked without lag, and a braking law for steps so a plain step does not overshoot.
#[derive(Debug, Clone, Copy, Default)]
struct Servo {
    pos: f64,
    vel: f64,
    /// Latest commanded position.
    target: f64,
    /// Feed-forward velocity estimated from the setpoint stream [unit/s].
    ff_vel: f64,
    /// Rig time of the latest setpoint [s].
    target_time_s: f64,
    /// Interval between the last two setpoints [s] (how far the target is extrapolated).
    interval_s: f64,
}

/// How far above its rated rate a servo may run to catch up with its trajectory [-].
const SERVO_RATE_HEADROOM: f64 = 1.1;
/// Position-error time constant of the servos [s].
const SERVO_TIME_CONSTANT_S: f64 = 0.01;
/// The filtered slip-ratio rate must exceed the bead's limit by this factor before the tyre
/// slips on the rim (servo ripple at exactly the limit does not count).
const RIM_SLIP_RATE_MARGIN: f64 = 1.15;
/// How much faster than the bead limit the tread's slip ratio rejoins the rim's after slipping.
const RIM_REGRIP_RATE_FACTOR: f64 = 20.0;
/// Setpoints further apart than this are steps, not a streamed trajectory [s].
const STREAM_MAX_INTERVAL_S: f64 = 0.1;

impl Servo {
    /// A new commanded position at rig time `now_s`.
    fn command(&mut self, target: f64, now_s: f64, rate: f64) {
        let dt = now_s - self.target_time_s;
        if dt > 0.0 && dt <= STREAM_MAX_INTERVAL_S {
            self.ff_vel = ((target - self.target) / dt).clamp(-rate, rate);
            self.interval_s = dt;
        } else if dt > 0.0 {
            self.ff_vel = 0.0;
            self.interval_s = 0.0;
        }
        self.target = target;
        self.target_time_s = now_s;
    }

    /// Holds a fixed position (no feed-forward): safe state, held axes, mode changes.
    fn hold(&mut self, target: f64, now_s: f64) {
        self.target = target;
        self.ff_vel = 0.0;
        self.interval_s = 0.0;
        self.target_time_s = now_s;
    }

    /// One step of `dt` at rig time `now_s`.
    fn track(&mut self, now_s: f64, rate: f64, accel: f64, dt: f64) {
        // Extrapolate the streamed target by at most one setpoint interval.
        let age = (now_s - self.target_time_s).clamp(0.0, self.interval_s);
        let target = self.target + self.ff_vel * age;
        let ff = if now_s - self.target_time_s <= self.interval_s { self.ff_vel } else { 0.0 };
        let e = target - self.pos;
        // Close the error no faster than the acceleration limit can still brake to the target
        // trajectory (time-optimal approach), so rate changes and reversals do not ring.
        let close = (e.abs() / SERVO_TIME_CONSTANT_S).min((2.0 * accel * e.abs()).sqrt());
        // The servo may exceed the rated rate by a small headroom to catch up a lag (e.g. after
        // accelerating onto a ramp at the rated rate), so it tracks the trajectory, not a
        // constant delay behind it.
        let max = rate * SERVO_RATE_HEADROOM;
        let want = (ff + e.signum() * close).clamp(-max, max);
        let dv = (want - self.vel).clamp(-accel * dt, accel * dt);
        self.vel += dv;
        let step = self.vel * dt;
        if ff == 0.0 && ((e >= 0.0 && step > e) || (e <= 0.0 && step < e)) {
            self.pos = target;
            self.vel = 0.0;
        } else {
            self.pos += step;
        }
    }
}

/// Moves `x` towards `target` by at most `rate`·dt.
fn slew(x: f64, target: f64, rate: f64, dt: f64) -> f64 {
    x + (target - x).clamp(-rate * dt, rate * dt)
}

/// What the rig is trying to do (validated targets).
#[derive(Debug, Clone, Copy)]
struct Targets {
    mode: u8,
    slip_angle_deg: f64,
    slip_ratio: f64,
    fz_n: f64,
    camber_deg: f64,
    pressure_pa: f64,
    speed_mps: f64,
    belt_displacement_m: f64,
}

/// The latest tyre-model evaluation and what the sample needs from it.
#[derive(Debug, Clone, Copy, Default)]
struct ModelOut {
    mf: MfOutput,
    fx_n: f64,
    valid: bool,
}

/// The virtual flat-track rig. Pure: no I/O, no clock; time advances by [`VirtualRig::step`].
/// Cloning forks the whole state, noise stream included (e.g. one preconditioned tyre, several
/// experiments).
#[derive(Debug, Clone)]
pub struct VirtualRig {
    cfg: RigConfig,
    tyre: VirtualTyre,
    base_scaling: ScalingFactors,
    limits: RigLimits,
    effects: Effects,
    fz0_n: f64,
    max_load_n: f64,
    dt_s: f64,
    publish_every: u64,
    model_every: u64,
    step_index: u64,
    seq: u64,
    noise: Gauss,

    targets: Targets,
    refused: bool,

    slip_angle: Servo,
    slip_ratio: Servo,
    fz_n: f64,
    camber_deg: f64,
    pressure_pa: f64,
    speed_mps: f64,
    belt_disp_m: f64,
    /// Belt velocity in static mode (d belt displacement / dt of the last step) [m/s].
    belt_vel_mps: f64,
    /// Position-encoder error of the last static sample [m] (see [`VirtualRig::sample`]).
    belt_encoder_err_m: f64,
    static_elastic_m: f64,
    commanded_slip_ratio_rate: f64,

    alpha_relaxed_deg: f64,
    kappa_relaxed: f64,
    /// (Fz/Fz0)^load_exponent of the relaxation lengths, refreshed at the model rate (a powf per
    /// internal step would cost more than the rest of the step).
    sigma_load_scale: f64,
    kappa_tread: f64,
    control_wander: f64,
    rim_slip_steps: u64,

    thermal: ThermalState,
    tread_worn_mm: f64,
    sliding_energy_j: f64,
    severe_energy_j: f64,
    sliding_power_w: f64,
    grip_temp_c: f64,
    grip_factor: f64,
    stiffness_factor: f64,
    break_in_deficit: f64,

    model: ModelOut,
}

impl VirtualRig {
    /// A rig at rest (belt stopped, load off, safe mode) with the tyre at
    /// `environment.initial_tyre_temp_c`. `seed` overrides `cfg.seed` for the noise stream.
    /// `tyre`: MF parameters ([`TyreParams`]) or any [`VirtualTyre`].
    pub fn new(cfg: RigConfig, tyre: impl Into<VirtualTyre>, seed: u64) -> Result<VirtualRig, RigError> {
        let tyre: VirtualTyre = tyre.into();
        cfg.validate().map_err(|(key, reason)| RigError::Invalid { key, reason })?;
        let fz0_n = tyre.fnomin_n();
        let r0 = tyre.unloaded_radius_m();
        let p0 = tyre.nominal_pressure_pa();
        if !(fz0_n.is_finite() && fz0_n > 0.0 && r0.is_finite() && r0 > 0.0 && p0.is_finite() && p0 > 0.0) {
            return Err(RigError::TyreValues(format!(
                "FNOMIN {fz0_n}, UNLOADED_RADIUS {r0}, NOMPRES {p0} must be > 0"
            )));
        }
        let limits = cfg.limits();
        // The rating entered at the rig caps the load, not the tyre file's FNOMIN: a wrong index
        // lets the rig overload the tyre exactly as in the thesis's failure case.
        // A brush tyre carries its own rating (race tyres have no ETRTO index).
        let rated_fz0 = match &tyre {
            VirtualTyre::Brush(_) => fz0_n,
            VirtualTyre::Mf(_) => nominal_load_n(cfg.tyre.load_index).unwrap_or(fz0_n),
        };
        let max_load_n = limits.max_load_n.min(cfg.tyre.max_load_factor * rated_fz0);
        let internal = u64::from(cfg.internal_rate_hz);
        let t0 = cfg.environment.initial_tyre_temp_c;
        let break_in_deficit = if cfg.effects.break_in { cfg.break_in.initial_grip_deficit } else { 0.0 };
        let mut rig = VirtualRig {
            base_scaling: tyre.base_scaling(),
            effects: cfg.effects,
            fz0_n,
            max_load_n,
            dt_s: cfg.dt_s(),
            publish_every: internal / u64::from(cfg.publish_rate_hz),
            model_every: internal / u64::from(cfg.model_rate_hz),
            step_index: 0,
            seq: 0,
            noise: Gauss::new(seed),
            targets: Targets {
                mode: RigSetpoint::MODE_SAFE,
                slip_angle_deg: 0.0,
                slip_ratio: 0.0,
                fz_n: 0.0,
                camber_deg: 0.0,
                pressure_pa: p0,
                speed_mps: 0.0,
                belt_displacement_m: 0.0,
            },
            refused: false,
            slip_angle: Servo::default(),
            slip_ratio: Servo::default(),
            fz_n: 0.0,
            camber_deg: 0.0,
            pressure_pa: p0,
            speed_mps: 0.0,
            belt_disp_m: 0.0,
            belt_vel_mps: 0.0,
            belt_encoder_err_m: 0.0,
            static_elastic_m: 0.0,
            commanded_slip_ratio_rate: 0.0,
            alpha_relaxed_deg: 0.0,
            kappa_relaxed: 0.0,
            sigma_load_scale: 1.0,
            kappa_tread: 0.0,
            control_wander: 0.0,
            rim_slip_steps: 0,
            thermal: ThermalState::uniform(t0),
            tread_worn_mm: cfg.tyre.new_tread_depth_mm - cfg.tyre.initial_tread_depth_mm,
            sliding_energy_j: 0.0,
            severe_energy_j: 0.0,
            sliding_power_w: 0.0,
            grip_temp_c: t0,
            grip_factor: 1.0,
            stiffness_factor: 1.0,
            break_in_deficit,
            model: ModelOut::default(),
            limits,
            tyre,
            cfg,
        };
        rig.update_model(0.0);
        Ok(rig)
    }

    /// Reads `path` (a `virtual_rig.toml`), its tyre file (`.tir` or brush file, per
    /// `[tyre] model`), and builds the rig with the config's seed.
    pub fn from_config_file(path: &Path) -> Result<VirtualRig, RigError> {
        let cfg = RigConfig::load(path)?;
        VirtualRig::from_config(cfg)
    }

    /// Builds the rig from a loaded config (tyre file path already resolved), with its seed.
    pub fn from_config(cfg: RigConfig) -> Result<VirtualRig, RigError> {
        let tyre = VirtualTyre::load(&cfg)?;
        let seed = cfg.seed;
        VirtualRig::new(cfg, tyre, seed)
    }

    /// The configuration in use.
    pub fn config(&self) -> &RigConfig {
        &self.cfg
    }

    /// The tyre model parameters in use.
    pub fn params(&self) -> Option<&TyreParams> {
        self.tyre.mf_params()
    }

    /// The tyre in use (MF or brush).
    pub fn tyre(&self) -> &VirtualTyre {
        &self.tyre
    }

    /// The effects in use.
    pub fn effects(&self) -> Effects {
        self.effects
    }

    /// Rig time [s]: internal steps × step length (exact multiples, no accumulated rounding).
    pub fn time_s(&self) -> f64 {
        self.step_index as f64 * self.dt_s
    }

    /// Internal step [s].
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Conditions the tyre as a soak at `temp_c` would: every thermal node at `temp_c`, no
    /// flash. For tests and for the calibration's "start at the 45 °C baseline".
    pub fn soak(&mut self, temp_c: f64) {
        if temp_c.is_finite() {
            self.thermal = ThermalState::uniform(temp_c);
            self.update_model(0.0);
        }
    }

    /// Marks the tyre as broken in (no grip deficit), as after the first severe sweeps.
    pub fn complete_break_in(&mut self) {
        self.break_in_deficit = 0.0;
        self.update_model(0.0);
    }

    /// Validates `sp` and makes it the rig's target. A refused setpoint sends the rig to its
    /// safe state (slip to zero, load off, belt stopped) with `FAULT_ENVELOPE` set until a valid
    /// setpoint is applied. `MODE_SAFE` is always accepted, whatever its other fields hold.
    pub fn apply_setpoint(&mut self, sp: &RigSetpoint) -> Result<(), SetpointRefusal> {
        match self.check_setpoint(sp) {
            Ok(t) => {
                let now = self.time_s();
                let l = self.limits;
                let was_safe = self.effective_mode() == RigSetpoint::MODE_SAFE;
                self.targets = t;
                self.refused = false;
                let (sa, sr) = self.servo_targets(t.mode);
                if t.mode == RigSetpoint::MODE_SAFE || was_safe || sp.hold_slip_angle {
                    self.slip_angle.hold(sa, now);
                } else {
                    self.slip_angle.command(sa, now, l.slip_angle_rate_deg_per_s);
                }
                if t.mode != RigSetpoint::MODE_COUPLED || was_safe || sp.hold_slip_ratio {
                    self.slip_ratio.hold(sr, now);
                } else {
                    self.slip_ratio.command(sr, now, l.slip_ratio_rate_per_s);
                }
                Ok(())
            }
            Err(r) => {
                let now = self.time_s();
                self.refused = true;
                self.targets.mode = RigSetpoint::MODE_SAFE;
                self.slip_angle.hold(0.0, now);
                self.slip_ratio.hold(0.0, now);
                Err(r)
            }
        }
    }

    fn check_setpoint(&self, sp: &RigSetpoint) -> Result<Targets, SetpointRefusal> {
        let l = &self.limits;
        if sp.mode > RigSetpoint::MODE_SAFE {
            return Err(SetpointRefusal::UnknownMode(sp.mode));
        }
        let mut t = self.targets;
        t.mode = sp.mode;
        if sp.mode == RigSetpoint::MODE_SAFE {
            return Ok(t);
        }
        let fields: [(&'static str, f64); 7] = [
            ("slip_angle_deg", sp.slip_angle_deg),
            ("slip_ratio", sp.slip_ratio),
            ("fz_n", sp.fz_n),
            ("camber_deg", sp.camber_deg),
            ("pressure_pa", sp.pressure_pa),
            ("speed_mps", sp.speed_mps),
            ("belt_displacement_m", sp.belt_displacement_m),
        ];
        for (field, value) in fields {
            if !value.is_finite() {
                return Err(SetpointRefusal::NotFinite { field, value });
            }
        }
        let check = |field: &'static str, value: f64, min: f64, max: f64, limit: &'static str| {
            if value < min || value > max {
                Err(SetpointRefusal::OutOfEnvelope { field, value, min, max, limit })
            } else {
                Ok(())
            }
        };
        let a = l.max_abs_slip_angle_deg;
        check("slip_angle_deg", sp.slip_angle_deg, -a, a, "rig slip-angle range")?;
        let s = l.max_abs_slip_ratio;
        check("slip_ratio", sp.slip_ratio, -s, s, "rig slip-ratio range")?;
        let load_limit = if self.max_load_n < l.max_load_n { "tyre load rating" } else { "rig load capacity" };
        check("fz_n", sp.fz_n, 0.0, self.max_load_n, load_limit)?;
        let c = l.max_abs_camber_deg;
        check("camber_deg", sp.camber_deg, -c, c, "rig camber range")?;
        check("pressure_pa", sp.pressure_pa, l.min_pressure_pa, l.max_pressure_pa, "rig pressure range")?;
        check("speed_mps", sp.speed_mps, 0.0, l.max_speed_mps, "rig belt speed range")?;
        let d = l.max_abs_belt_displacement_m;
        check("belt_displacement_m", sp.belt_displacement_m, -d, d, "rig belt displacement range")?;
        if !sp.hold_slip_angle {
            t.slip_angle_deg = sp.slip_angle_deg;
        } else {
            t.slip_angle_deg = self.slip_angle.pos;
        }
        if !sp.hold_slip_ratio {
            t.slip_ratio = sp.slip_ratio;
        } else {
            t.slip_ratio = self.slip_ratio.pos;
        }
        t.fz_n = if sp.hold_load { self.fz_n } else { sp.fz_n };
        t.camber_deg = if sp.hold_camber { self.camber_deg } else { sp.camber_deg };
        t.pressure_pa = sp.pressure_pa;
        t.speed_mps = sp.speed_mps;
        t.belt_displacement_m = sp.belt_displacement_m;
        Ok(t)
    }

    /// Runs until rig time reaches `t_s`, handing every published sample to `out`.
    pub fn run_until(&mut self, t_s: f64, out: &mut impl FnMut(&RigSample)) {
        if !t_s.is_finite() {
            return;
        }
        // Compare in whole steps so the loop ends exactly where `time_s()` says it does.
        let end_step = (t_s / self.dt_s - 1e-9).ceil().max(0.0) as u64;
        while self.step_index < end_step {
            if let Some(s) = self.step() {
                out(&s);
            }
        }
    }

    /// The hidden true state.
    pub fn truth(&self) -> TruthState {
        let ts = self.thermal.surface_c;
        TruthState {
            time_s: self.time_s(),
            tread_depth_mm: self.cfg.tyre.new_tread_depth_mm - self.tread_worn_mm,
            tread_worn_mm: self.tread_worn_mm,
            surface_temp_c: ts,
            bulk_temp_c: self.thermal.bulk_c,
            flash_temp_k: self.thermal.flash_total_k(),
            grip_temp_c: self.grip_temp_c,
            grip_factor: self.grip_factor,
            stiffness_factor: self.stiffness_factor,
            break_in_deficit: self.break_in_deficit,
            sliding_energy_j: self.sliding_energy_j,
            severe_sliding_energy_j: self.severe_energy_j,
            sliding_power_w: self.sliding_power_w,
            relaxed_slip_angle_deg: self.alpha_relaxed_deg,
            relaxed_slip_ratio: self.tyre_kappa(),
            rim_slip_steps: self.rim_slip_steps,
            below_legal_minimum: self.cfg.tyre.new_tread_depth_mm - self.tread_worn_mm
                < self.cfg.tyre.legal_min_tread_depth_mm,
            safe: self.effective_mode() == RigSetpoint::MODE_SAFE,
        }
    }

    /// Slip-angle and slip-ratio servo targets in `mode`: safe → zero; free rolling and static
    /// → the drive does not hold a slip ratio (free rolling: zero; static: wheel locked).
    fn servo_targets(&self, mode: u8) -> (f64, f64) {
        match mode {
            RigSetpoint::MODE_SAFE => (0.0, 0.0),
            RigSetpoint::MODE_COUPLED => (self.targets.slip_angle_deg, self.targets.slip_ratio),
            _ => (self.targets.slip_angle_deg, 0.0),
        }
    }

    fn effective_mode(&self) -> u8 {
        if self.refused { RigSetpoint::MODE_SAFE } else { self.targets.mode }
    }

    /// The slip ratio the contact patch works at: relaxed tread slip plus controller wander.
    fn tyre_kappa(&self) -> f64 {
        self.kappa_relaxed
    }

    /// Advances one internal step; returns a sample when one is due at the publish rate.
    pub fn step(&mut self) -> Option<RigSample> {
        let dt = self.dt_s;
        self.step_index += 1;
        let mode = self.effective_mode();
        let l = self.limits;

        // --- actuators ---
        let now = self.time_s();
        let (fz_target, speed_target) = match mode {
            RigSetpoint::MODE_SAFE => (0.0, 0.0),
            RigSetpoint::MODE_STATIC => (self.targets.fz_n, 0.0),
            _ => (self.targets.fz_n, self.targets.speed_mps),
        };
        self.slip_angle.track(now, l.slip_angle_rate_deg_per_s, l.slip_angle_accel_deg_per_s2, dt);
        let sr_before = self.slip_ratio.pos;
        self.slip_ratio.track(now, l.slip_ratio_rate_per_s, l.slip_ratio_accel_per_s2, dt);
        let sr_rate = (self.slip_ratio.pos - sr_before) / dt;
        // A low-pass of the slip rate tells the controller model how slowly it is being asked to
        // move (the thesis: below ~10 %/s the regulation gets rough).
        let k = (dt / 0.05).min(1.0);
        self.commanded_slip_ratio_rate += k * (sr_rate.abs() - self.commanded_slip_ratio_rate);
        self.fz_n = slew(self.fz_n, fz_target, l.load_rate_n_per_s, dt);
        if mode != RigSetpoint::MODE_SAFE {
            self.camber_deg = slew(self.camber_deg, self.targets.camber_deg, l.camber_rate_deg_per_s, dt);
            self.pressure_pa +=
                (self.targets.pressure_pa - self.pressure_pa) * (dt / l.pressure_time_constant_s).min(1.0);
        }
        self.speed_mps = slew(self.speed_mps, speed_target, l.belt_accel_mps2, dt);
        let statik = mode == RigSetpoint::MODE_STATIC;
        if statik {
            let before = self.belt_disp_m;
            self.belt_disp_m =
                slew(self.belt_disp_m, self.targets.belt_displacement_m, self.cfg.rig.static_belt_speed_mps, dt);
            self.static_elastic_m += self.belt_disp_m - before;
            self.belt_vel_mps = (self.belt_disp_m - before) / dt;
        } else {
            self.belt_disp_m = 0.0;
            self.belt_vel_mps = 0.0;
            self.static_elastic_m = 0.0;
        }

        // --- rim slip: while the slip ratio changes faster than the bead holds (50 ms mean of the
        // rate above the limit), the tyre turns on the rim and its slip ratio lags the rim's; once
        // the rate falls the bead grips again and the two turn together (a slip ratio is a speed
        // ratio, so no offset remains).
        let rim_kappa = self.slip_ratio.pos;
        let max_rate = self.cfg.rim_slip.max_slip_ratio_rate_per_s;
        let slipping = self.effects.rim_slip
            && mode == RigSetpoint::MODE_COUPLED
            && self.model.fx_n.abs() >= self.cfg.rim_slip.min_force_n
            && self.commanded_slip_ratio_rate > max_rate * RIM_SLIP_RATE_MARGIN;
        if slipping {
            self.kappa_tread = slew(self.kappa_tread, rim_kappa, max_rate, dt);
            self.rim_slip_steps += 1;
        } else {
            self.kappa_tread = slew(self.kappa_tread, rim_kappa, max_rate * RIM_REGRIP_RATE_FACTOR, dt);
        }
        let kappa_in = self.kappa_tread + self.control_wander;

        // --- transient: first-order relaxation in travelled distance (implicit Euler) ---
        let rolling_speed = if statik { 0.0 } else { self.speed_mps };
        if self.effects.transient {
            let ds = rolling_speed * dt;
            let tr = &self.cfg.transient;
            let load_scale = self.sigma_load_scale;
            let ry = self.alpha_relaxed_deg / tr.sigma_y_half_slip_deg;
            let sigma_y = tr.sigma_y_min_m + (tr.sigma_y0_m * load_scale - tr.sigma_y_min_m).max(0.0) / (1.0 + ry * ry);
            self.alpha_relaxed_deg += (self.slip_angle.pos - self.alpha_relaxed_deg) * ds / (sigma_y + ds);
            let rx = self.kappa_relaxed / tr.sigma_x_half_slip;
            let sigma_x = tr.sigma_x_min_m + (tr.sigma_x0_m * load_scale - tr.sigma_x_min_m).max(0.0) / (1.0 + rx * rx);
            self.kappa_relaxed += (kappa_in - self.kappa_relaxed) * ds / (sigma_x + ds);
        } else {
            self.alpha_relaxed_deg = self.slip_angle.pos;
            self.kappa_relaxed = kappa_in;
        }

        // --- tyre model, thermal, wear at the model rate and whenever a sample is due ---
        let publish = self.step_index.is_multiple_of(self.publish_every);
        if self.step_index.is_multiple_of(self.model_every) {
            self.update_model(dt * self.model_every as f64);
        } else if publish {
            self.update_model(0.0);
        }
        publish.then(|| self.sample(mode))
    }

    /// Evaluates the tyre model at the present state; when `dt_s` > 0 also advances the slow
    /// states (controller wander, temperatures, wear, break-in) by `dt_s`.
    fn update_model(&mut self, dt_s: f64) {
        let statik = self.effective_mode() == RigSetpoint::MODE_STATIC;
        let vx = if statik { 0.0 } else { self.speed_mps };
        let tg = &self.cfg.thermal_grip;
        let wear = &self.cfg.wear;
        // Grip temperature: the surface/bulk mix without flash (the thesis: flash spikes have
        // little effect on grip).
        self.grip_temp_c =
            tg.surface_weight * self.thermal.surface_mean_c() + (1.0 - tg.surface_weight) * self.thermal.bulk_c;
        let (g_t, k_t) = if self.effects.thermal_grip {
            let d = self.grip_temp_c - tg.optimum_temp_c;
            (
                (1.0 - tg.grip_loss_per_k2 * d * d).max(tg.min_grip_factor),
                (1.0 - tg.stiffness_per_k * d).clamp(0.5, 1.5),
            )
        } else {
            (1.0, 1.0)
        };
        let worn = if self.effects.wear { self.tread_worn_mm.max(0.0) } else { 0.0 };
        self.grip_factor = g_t * (1.0 - self.break_in_deficit);
        self.stiffness_factor = k_t * (1.0 + wear.stiffness_gain_per_mm * worn);
        let shape = 1.0 + wear.shape_gain_per_mm * worn;
        let scaling = TyreScaling { grip: self.grip_factor, stiffness: self.stiffness_factor, shape };

        self.sigma_load_scale =
            (self.fz_n.max(0.0) / self.fz0_n).powf(self.cfg.transient.load_exponent).clamp(0.2, 2.0);
        let kappa = self.tyre_kappa();
        let re_prev = if self.model.valid && self.model.mf.re_m > 0.0 {
            self.model.mf.re_m
        } else {
            self.tyre.unloaded_radius_m()
        };
        let state = TyreState {
            fz_n: self.fz_n.max(0.0),
            kappa,
            alpha_rad: self.alpha_relaxed_deg.to_radians(),
            gamma_rad: self.camber_deg.to_radians(),
            vx_mps: vx,
            p_pa: self.pressure_pa,
            omega_radps: if vx > 0.0 { vx * (1.0 + kappa) / re_prev } else { 0.0 },
        };
        let mf = self.tyre.evaluate(&self.base_scaling, scaling, &state);
        let finite = [mf.fx_n, mf.fy_n, mf.mx_nm, mf.my_nm, mf.mz_nm, mf.rl_m, mf.re_m].iter().all(|v| v.is_finite());
        let mut fx = mf.fx_n;
        if statik {
            // Locked wheel, belt moved: the carcass acts as a spring up to the friction limit;
            // a belt displacement along its running direction drags the patch rearwards.
            let cx = if mf.cx_npm.is_finite() && mf.cx_npm > 0.0 { mf.cx_npm } else { 4.0e5 };
            let limit = self.tyre.static_friction(&mf, self.grip_factor) * self.fz_n.max(0.0);
            let max_elastic = limit / cx;
            self.static_elastic_m = self.static_elastic_m.clamp(-max_elastic, max_elastic);
            fx = -cx * self.static_elastic_m;
        }
        self.model = ModelOut { mf, fx_n: if finite { fx } else { 0.0 }, valid: finite };
        if dt_s <= 0.0 {
            return;
        }

        // Controller wander of the coupled drive (Ornstein–Uhlenbeck), rough below the smooth rate.
        let coupled = self.effective_mode() == RigSetpoint::MODE_COUPLED;
        if self.effects.noise && coupled {
            let n = &self.cfg.noise;
            let smooth = self.cfg.rig.smooth_slip_ratio_rate_per_s;
            let rate = self.commanded_slip_ratio_rate;
            let slow =
                if rate > 1e-4 && rate < smooth { n.slow_control_slip_ratio * (1.0 - rate / smooth) } else { 0.0 };
            let sigma = (n.coupled_slip_ratio.powi(2) + slow * slow).sqrt();
            let a = (dt_s / n.control_time_constant_s).min(1.0);
            self.control_wander += -a * self.control_wander + sigma * (2.0 * a).sqrt() * self.noise.normal();
        } else {
            self.control_wander = 0.0;
        }

        // Sliding power (reference §3): PY = FY·VX·sin(SA), PX = FX·SR·VX·cos(SA), at the
        // contact patch's (relaxed) slips so stored carcass energy is not counted as heat.
        let (sa, ca) = self.alpha_relaxed_deg.to_radians().sin_cos();
        let (py, px) = if finite && !statik { (mf.fy_n * vx * sa, fx * kappa * vx * ca) } else { (0.0, 0.0) };
        let p = (px * px + py * py).sqrt();
        self.sliding_power_w = p;
        let e = p * dt_s;
        self.sliding_energy_j += e;
        let bi = &self.cfg.break_in;
        let severe = (p - bi.power_threshold_kw * 1e3).max(0.0) * dt_s;
        self.severe_energy_j += severe;
        if self.effects.break_in {
            self.break_in_deficit *= (-severe / (bi.energy_scale_kj * 1e3)).exp();
        }
        if self.effects.wear {
            self.tread_worn_mm += self.cfg.wear.wear_mm_per_mj * self.cfg.tyre.wear_rate_multiplier * e * 1e-6;
            self.tread_worn_mm = self.tread_worn_mm.min(self.cfg.tyre.new_tread_depth_mm);
        }
        if self.effects.thermal {
            let rolling_loss_w = self.cfg.thermal.rolling_loss_coefficient * self.fz_n.max(0.0) * vx;
            self.thermal.advance(
                &self.cfg.thermal,
                &ThermalInput {
                    lateral_power_w: py.abs(),
                    longitudinal_power_w: px.abs(),
                    rolling_loss_w,
                    speed_mps: vx,
                    load_factor: self.fz_n.max(0.0) / self.fz0_n,
                    camber_deg: self.camber_deg,
                    ambient_c: self.cfg.environment.ambient_temp_c,
                    belt_c: self.cfg.environment.belt_temp_c,
                },
                dt_s,
            );
        }
    }

    /// Builds the published sample from the present state, with noise and chatter.
    fn sample(&mut self, mode: u8) -> RigSample {
        let t = self.time_s();
        let m = self.model;
        let on = self.effects.noise;
        let coupled = mode == RigSetpoint::MODE_COUPLED;
        let n = self.cfg.noise.clone();
        let mut nz = |sigma: f64| if on && sigma > 0.0 { sigma * self.noise.normal() } else { 0.0 };
        let (gx, gm, gmx) =
            if coupled { (n.coupled_fx_gain, n.coupled_moment_gain, n.coupled_mx_gain) } else { (1.0, 1.0, 1.0) };
        let fx_noise = nz(n.fx_n * gx);
        let fy_noise = nz(n.fy_n);
        let fz_noise = nz(n.fz_n);
        let mx_noise = nz(n.mx_nm * gmx);
        let my_noise = nz(n.my_nm * gm);
        let mz_noise = nz(n.mz_nm * gm);
        let sa_noise = nz(n.slip_angle_deg);
        let sr_noise = nz(n.slip_ratio);
        let ca_noise = nz(n.camber_deg);
        let p_noise = nz(n.pressure_pa);
        let v_noise = nz(n.speed_mps);
        let r_noise = nz(n.radius_m);
        let ti_noise = nz(n.temp_c);
        let tc_noise = nz(n.temp_c);
        let to_noise = nz(n.temp_c);

        let chatter = self.chatter_n(t);
        let statik = mode == RigSetpoint::MODE_STATIC;
        // TRAJVELW. Rolling: the belt speed plus white sensor noise. Static (wheel locked, belt
        // crawling under it): the belt's signed velocity d(displacement)/dt as the rig's belt
        // position encoder gives it, differenced between samples, so its noise is the difference
        // of two position errors (same 1σ per sample as rolling: position error σ =
        // speed noise × sample interval / √2) and TRAJVELW integrates back to the belt's
        // displacement (LONGDISP) without a random walk.
        let trajvelw = if statik {
            let dt_pub = self.dt_s * self.publish_every as f64;
            let err = v_noise * dt_pub / std::f64::consts::SQRT_2;
            let v = self.belt_vel_mps + (err - self.belt_encoder_err_m) / dt_pub;
            self.belt_encoder_err_m = err;
            v
        } else {
            self.belt_encoder_err_m = 0.0;
            self.speed_mps + v_noise
        };
        let worn_m = if self.effects.wear { self.tread_worn_mm * 1e-3 } else { 0.0 };
        let rl = if m.valid { m.mf.rl_m - worn_m } else { self.tyre.unloaded_radius_m() - worn_m };
        // DSTWOWHC at the rig's 0.1 mm resolution.
        let dst = ((rl + r_noise) / 1e-4).round() * 1e-4;
        let re = if m.valid && m.mf.re_m > 0.0 { m.mf.re_m - worn_m } else { rl };
        let vx = if statik { 0.0 } else { self.speed_mps };
        let rim_kappa = self.slip_ratio.pos + self.control_wander;
        let omega = if statik || re <= 0.0 { 0.0 } else { vx * (1.0 + rim_kappa) / re };
        let temps = self.thermal.measured_c(&self.cfg.thermal, self.camber_deg);
        let mut fault = 0;
        if !m.valid {
            fault |= RigSample::FAULT_FORCE;
        }
        if self.refused {
            fault |= RigSample::FAULT_ENVELOPE;
        }
        // FAULT_ESTOP means a hardware e-stop tripped (RigSample.msg). Being in the safe state
        // (power-up, between procedures, after an abort) is not one; the virtual rig has no
        // e-stop chain of its own, so it never raises the flag.
        let (fx, fy, mx, my, mz) =
            if m.valid { (m.fx_n, m.mf.fy_n, m.mf.mx_nm, m.mf.my_nm, m.mf.mz_nm) } else { (0.0, 0.0, 0.0, 0.0, 0.0) };
        let seq = self.seq;
        self.seq += 1;
        RigSample {
            header: Header::iso_w(t),
            seq,
            runtime_s: t,
            fx_n: fx + fx_noise + chatter.0,
            fyw_n: fy + fy_noise + chatter.1,
            fzw_n: self.fz_n.max(0.0) + fz_noise + chatter.2,
            mxw_nm: mx + mx_noise,
            myw_nm: my + my_noise,
            mzw_nm: mz + mz_noise,
            slipangl_deg: self.slip_angle.pos + sa_noise,
            longslip: if coupled { rim_kappa + sr_noise } else { self.slip_ratio.pos + sr_noise },
            inclangl_deg: self.camber_deg + ca_noise,
            inflpres_pa: self.pressure_pa + p_noise,
            trajvelw_mps: trajvelw,
            wheel_speed_radps: omega,
            dstwowhc_m: dst,
            trdtempi_c: temps[0] + ti_noise,
            trdtempc_c: temps[1] + tc_noise,
            trdtempo_c: temps[2] + to_noise,
            rig_mode: mode,
            fault_flags: fault,
        }
    }

    /// Chatter force (FX, FYW, FZW) at time `t`: zero unless worn, loaded high and sliding.
    fn chatter_n(&self, t: f64) -> (f64, f64, f64) {
        if !self.effects.chatter {
            return (0.0, 0.0, 0.0);
        }
        let c = &self.cfg.chatter;
        let wear = (self.tread_worn_mm - c.onset_wear_mm).max(0.0);
        let load = (self.fz_n / self.fz0_n - c.onset_load_factor).max(0.0);
        let slip_a = ((self.slip_angle.pos.abs() - c.onset_slip_angle_deg) / c.onset_slip_angle_deg).clamp(0.0, 1.0);
        let slip_k = ((self.slip_ratio.pos.abs() - c.onset_slip_ratio) / c.onset_slip_ratio).clamp(0.0, 1.0);
        let severity = slip_a.max(slip_k);
        let amp = c.amplitude_n * wear * load * severity;
        if amp <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let w = (std::f64::consts::TAU * c.frequency_hz * t).sin();
        (amp * w * slip_k.max(0.3), amp * w * slip_a.max(0.3), 0.5 * amp * w)
    }
}
