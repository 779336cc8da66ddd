//! rigsim: the virtual flat-track rig's simulation core (pure, deterministic, time as data).
//!
//! [`VirtualRig`] takes `tyre_msgs::msg::RigSetpoint`s ([`VirtualRig::apply_setpoint`]),
//! integrates at a fixed internal step (`internal_rate_hz`, ≥ 1 kHz) and returns
//! `tyre_msgs::msg::RigSample`s at the publish rate (100 Hz default, up to 1 kHz) from
//! [`VirtualRig::step`] / [`VirtualRig::run_until`]. It reads no clock and does no I/O: a wrapper
//! decides whether simulated time runs in real time or accelerated. The same config and seed
//! give a byte-identical sample stream. One TOML file ([`RigConfig`],
//! `launch-config/virtual_rig.toml`) describes the tyre, the rig and every effect.
//!
//! # Physics
//! Always on:
//! - **Steady state**: MF-Tyre 6.1 (`mftyre`, use mode 111) forces and moments, loaded radius
//!   (DSTWOWHC, quantised to the rig's 0.1 mm) and effective rolling radius (wheel speed).
//!   Or, with `[tyre] model = "brush"`, the physical [`brush`] tyre ([`VirtualTyre`]): a brush
//!   with a parabolic pressure q(x) = 3Fz/(4a)·(1 − x²/a²) over a patch of half-length
//!   a = q_a·√(2·R0·ρ) from the nonlinear vertical deflection ρ; adhesion up to the static
//!   friction ellipse at λ = |(Cx·σx/μx, Cy·σy/μy)|/(3Fz), sliding behind it at a kinetic
//!   friction μk = μs·(r + (1 − r)/(1 + Vs/Vμ)) that falls with the sliding speed; static
//!   friction μs = μ0·(Fz/Fz0)^(−n) (power law) × the rig's grip factor; closed forms
//!   F = C·σ·(1 − λ)² + μk·Fz·λ²(3 − 2λ)·ŝ and MZ = −(a/3)·Cy·σy·(1 − λ)²(1 − 4λ) −
//!   3·μk,y·Fz·a·λ²(1 − λ)²·ŝy; carcass compliance in series (αe = α − MZ/cψ,
//!   κe = κ − FX/EA, patch shift FY/ccy giving MZ −= FX·FY/ccy and MX = Fz·FY/ccy − …); camber
//!   as an equivalent slip; pressure in the vertical, bristle and friction terms. Derivations,
//!   parameters and what the Magic Formula cannot reproduce of it: `docs/brush-tyre.md`.
//! - **Rig**: rate/acceleration-limited servos for slip angle and slip ratio, rate limits for
//!   load, camber and belt speed (profiles `mts_flattrac`, `calspan_tirf`), a first-order
//!   pressure regulator (~20 s to settle), the envelope (refused setpoints send the rig safe),
//!   free-rolling (un-coupled) vs coupled drive, static mode (wheel locked, belt moved: FX =
//!   −Cx·displacement up to the friction limit) and standstill steering (no rolling, so the
//!   relaxed slip does not move until the belt runs again: a step-steer).
//!
//! Switchable effects ([`Effects`], names as in the config and `--effects`):
//! - `transient`: first-order lateral and longitudinal relaxation in travelled distance,
//!   dα'/ds = (α − α')/σy(α'), with σ falling with slip from σ0 (0.6 m) to 0.15 m at 4°
//!   (Rill's tyre, thesis Fig. 3.6.2-G). Fast sweeps show mechanical hysteresis at zero slip.
//! - `thermal`: three surface zones (TRDTEMPI/C/O, shares shifted by camber) over a bulk node,
//!   heated by the sliding powers PY = FY·VX·sin(SA) and PX = FX·SR·VX·cos(SA) (reference §3;
//!   separate surface/bulk shares for each, the rest heats the belt) and by rolling loss, cooled
//!   by speed-dependent convection, by contact with the belt (held near ambient by its bearing)
//!   and from the bulk to air, plus lateral and longitudinal flash temperatures (sub-second time
//!   constants) that only the lasers see.
//! - `thermal_grip`: λμ = 1 − c·(T − T_opt)² and λK = 1 − k·(T − T_opt) at the grip temperature
//!   (surface/bulk mix): an overheated tyre loses grip.
//! - `wear`: tread loss ∝ sliding energy; DSTWOWHC falls with it; the worn tyre gets a higher
//!   λK (less tread shuffle) and λC (more drop-off after the peak).
//! - `break_in`: a new tyre lacks ~12 % grip, recovered exponentially with severe sliding
//!   energy (thesis: +14.2 % peak FX over the first five BrkDrv sweeps).
//! - `noise`: Gaussian sensor noise per channel, extra FX/MXW/MYW/MZW noise with the drive
//!   coupled, and slip-ratio controller wander that grows below the smooth rate (10 %/s).
//! - `chatter`: a rig vibration on the forces at high load and slip once the tyre is worn.
//! - `rim_slip`: above 60 %/s of slip-ratio change the tyre turns on the rim: the tread's slip
//!   ratio lags the rim's (measured) one.
//!
//! With every effect off the samples equal the steady-state tyre model (MF or brush) at the
//! rig's actual (actuator-limited) inputs.
//!
//! [`calibration`] runs the thesis's comparison sweeps (Tables 3.6.2-H and 3.6.2-I) and the
//! warm-up and wear checks on the default tyre; `tyrerig rig calibrate` prints them.
//!
//! # Speed
//! Actuators and relaxation run every internal step; the tyre model (the costly part, ~1 µs),
//! temperatures and wear run at `model_rate_hz` (100 Hz) and whenever a sample is due, so at
//! the default 1 kHz step and 100 Hz publish rate one internal step costs a fraction of a
//! microsecond (`cargo bench -p rigsim --bench step`). Publishing at 1 kHz evaluates the model
//! every step.

pub mod brush;
pub mod calibration;
mod config;
mod noise;
mod rig;
mod thermal;
mod tyre;

pub use brush::{BrushError, BrushInput, BrushParams};
pub use config::{
    BreakInParams, ChatterParams, ConfigError, DEFAULT_TYRE_FILE, Effects, EnvironmentSection, NoiseParams, RigConfig,
    RigLimits, RigProfile, RigSection, RimSlipParams, ThermalGripParams, ThermalParams, TransientParams, TyreModel,
    TyreSection, UnknownEffect, WearParams, load_capacity_kg, nominal_load_n,
};
pub use rig::{RigError, SetpointRefusal, TruthState, VirtualRig};
pub use tyre::VirtualTyre;

/// Re-exported so users of the core need not depend on `tyre_msgs` / `mftyre` for the basics.
pub use mftyre::TyreParams;
pub use tyre_msgs::msg::{RigSample, RigSetpoint};
