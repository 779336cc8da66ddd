//! Tread temperature model: three surface zones (inner, centre, outer) over one bulk node, plus
//! a flash temperature on the surface.
//!
//! ```text
//!   sliding power P = √(PX² + PY²)          rolling loss
//!        │ f_s·P (by zone share)  f_b·P          │   (rest of P: into the belt)
//!        ▼                          ▼            ▼
//!   [surface i/c/o] ──G_sb── [bulk] ──G_b,air── air
//!     │ conv(V)   │ belt contact (cooled by the belt's bearing)
//!     ▼           ▼
//!    air         belt
//! ```
//! Measured TRDTEMP* = surface zone + flash × zone weight. The flash follows P with a short time
//! constant: the laser sees spikes that "cool in moments" (thesis §3.5) and grip ignores them.

use crate::config::ThermalParams;

/// Inputs of one thermal step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ThermalInput {
    pub lateral_power_w: f64,
    pub longitudinal_power_w: f64,
    pub rolling_loss_w: f64,
    pub speed_mps: f64,
    pub load_factor: f64,
    pub camber_deg: f64,
    pub ambient_c: f64,
    pub belt_c: f64,
}

/// The thermal state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ThermalState {
    /// Surface zones inner/centre/outer [°C].
    pub surface_c: [f64; 3],
    /// Bulk [°C].
    pub bulk_c: f64,
    /// Flash temperature rise from lateral sliding [K].
    pub flash_k: f64,
    /// Flash temperature rise from longitudinal sliding [K].
    pub flash_long_k: f64,
}

/// Heat share of the inner, centre and outer zones at camber `camber_deg`. Negative camber
/// (top of a right-side tyre leaning towards the car) loads the inner shoulder.
pub(crate) fn zone_shares(p: &ThermalParams, camber_deg: f64) -> [f64; 3] {
    let c = (p.camber_zone_share_per_deg * camber_deg).clamp(-0.9, 0.9);
    [(1.0 - c) / 3.0, 1.0 / 3.0, (1.0 + c) / 3.0]
}

impl ThermalState {
    pub(crate) fn uniform(temp_c: f64) -> Self {
        Self { surface_c: [temp_c; 3], bulk_c: temp_c, flash_k: 0.0, flash_long_k: 0.0 }
    }

    /// Both flash components [K].
    pub(crate) fn flash_total_k(&self) -> f64 {
        self.flash_k + self.flash_long_k
    }

    pub(crate) fn surface_mean_c(&self) -> f64 {
        (self.surface_c[0] + self.surface_c[1] + self.surface_c[2]) / 3.0
    }

    /// What the three lasers read (before sensor noise).
    pub(crate) fn measured_c(&self, p: &ThermalParams, camber_deg: f64) -> [f64; 3] {
        let w = zone_shares(p, camber_deg);
        let f = self.flash_total_k();
        [self.surface_c[0] + f * 3.0 * w[0], self.surface_c[1] + f * 3.0 * w[1], self.surface_c[2] + f * 3.0 * w[2]]
    }

    /// Advances by `dt_s` (explicit Euler; the smallest time constant with the calibrated
    /// values is seconds, the step is at most 10 ms; the flash uses its exact decay).
    pub(crate) fn advance(&mut self, p: &ThermalParams, u: &ThermalInput, dt_s: f64) {
        let w = zone_shares(p, u.camber_deg);
        let surface_power =
            p.surface_fraction_lateral * u.lateral_power_w + p.surface_fraction_longitudinal * u.longitudinal_power_w;
        let bulk_power = p.bulk_fraction_lateral * u.lateral_power_w
            + p.bulk_fraction_longitudinal * u.longitudinal_power_w
            + u.rolling_loss_w;
        let conv = p.convection_w_per_k + p.convection_speed_w_per_k * u.speed_mps.max(0.0).powf(0.8);
        // The contact area (so the belt's cooling) grows roughly with √load.
        let belt = if u.load_factor > 0.0 { p.belt_contact_w_per_k * u.load_factor.sqrt() } else { 0.0 };
        let cs = p.surface_heat_capacity_j_per_k / 3.0;
        let gsb = p.surface_bulk_conductance_w_per_k / 3.0;
        let mut to_bulk = 0.0;
        for (z, ts) in self.surface_c.iter_mut().enumerate() {
            let q_sb = gsb * (*ts - self.bulk_c);
            let q = surface_power * w[z] - q_sb - conv / 3.0 * (*ts - u.ambient_c) - belt / 3.0 * (*ts - u.belt_c);
            *ts += q / cs * dt_s;
            to_bulk += q_sb;
        }
        let qb = bulk_power + to_bulk - p.bulk_to_air_w_per_k * (self.bulk_c - u.ambient_c);
        self.bulk_c += qb / p.bulk_heat_capacity_j_per_k * dt_s;
        let a = 1.0 - (-dt_s / p.flash_time_constant_s).exp();
        self.flash_k += (p.flash_lateral_k_per_kw * u.lateral_power_w * 1e-3 - self.flash_k) * a;
        let a = 1.0 - (-dt_s / p.flash_longitudinal_time_constant_s).exp();
        self.flash_long_k += (p.flash_longitudinal_k_per_kw * u.longitudinal_power_w * 1e-3 - self.flash_long_k) * a;
    }
}
