//! The planner's settings (the sequencer config's `[adaptive]` table).

use serde::{Deserialize, Serialize};

/// How the adaptive planner chooses and when it stops.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdaptiveConfig {
    /// A slot stops when its predicted held-out error (% of peak, RMS over the slot's target
    /// channels) is at most `target_ratio` × the error predicted for running every remaining
    /// candidate of the slot, i.e. the full procedure's content. 1.0 would run until nothing
    /// is left to learn; the default accepts a predicted error 15 % above the full run's.
    pub target_ratio: f64,
    /// An absolute target instead (% of peak): a slot also stops when its predicted error is
    /// at most this. `None`: only the ratio.
    pub target_error_pct: Option<f64>,
    /// A slot stops only when its target is met at this many decisions in a row (a sweep runs
    /// between them): the predicted error jumps between updates, and one low reading is no
    /// reason to stop (`docs/adaptive-plan.md`, Limits). 1 stops at the first.
    pub target_confirmations: u32,
    /// At most this fraction of the full procedure's predicted cost of a slot's candidates is
    /// spent on the slot (the rig-time budget); 1.0 = no limit beyond the full content.
    pub budget_fraction: f64,
    /// Planned points per candidate sweep in the linearisation (spread evenly over its time).
    /// Points along one sweep are correlated, so a few tens stand for a whole sweep.
    pub points_per_sweep: usize,
    /// Prior standard deviation of a coefficient the fit holds for want of data (a pressure or
    /// camber level not tested yet): MF coefficients are O(0.1–1), so 0.3 says "unknown".
    pub held_prior_std: f64,
    /// A candidate is worth running only if it lowers the slot's predicted error by at least
    /// this fraction (relative).
    pub min_relative_gain: f64,
    /// Severe sweeps (run last): peak slip angle at least this \[deg\] …
    pub severe_slip_angle_deg: f64,
    /// … or a load at least this factor of Fz0.
    pub severe_load_factor: f64,
    /// A slot's first choices (until every target channel has a covariance) go by coverage:
    /// the cheapest candidate that informs an unfitted channel.
    pub bootstrap_by_cost: bool,
    /// Before a slot closes, run the candidates that take its data beyond where the sweeps run
    /// so far reached (load, slip, camber; `adaptive::extent`), so the model's tested range is
    /// the procedure's. Off by default: on GS2MF it adds only BrkDrv's extreme sweeps, for 0.5–3 %
    /// more rig time and no better model on the virtual rig (docs/adaptive-plan.md).
    pub cover_envelope: bool,
    /// Tread a sweep wears counts in its cost: the tyre is worn out sooner, and a fresh one
    /// costs `tyre_change_s` per `usable_tread_mm`. A candidate's wear is its sliding energy
    /// along its sweep as the live model predicts it, × this rate \[mm/MJ\]. The default,
    /// 0.208, is the rate at which the thesis's 32-sweep FreeRolling investigation wore the
    /// 1.4 mm it measured (§3.6.2); the monitor fits a tyre's own rate from its rolling radius
    /// (the k of `docs/monitoring.md`, *wear*), and once it has, that rate is weighed against
    /// this one (`wear_rate_log_sd`). 0 leaves wear out of the cost.
    pub wear_mm_per_mj: f64,
    /// How far the tyre's own wear rate may be from `wear_mm_per_mj`: the 1 σ spread of the
    /// rate's logarithm (1.0: a factor of e ≈ 2.7 either way; compounds differ by more than
    /// that). The monitor's measured rate, with its own spread, is weighed against the
    /// configured one in log space (inverse-variance), so a rate measured to ±10 % all but
    /// replaces it and a rough early one moves it a little. 0 keeps the configured rate
    /// whatever the monitor measures.
    pub wear_rate_log_sd: f64,
    /// Tread a specimen may lose before it is changed \[mm\] (thesis: 5.6 mm new, 1.6 mm legal
    /// minimum).
    pub usable_tread_mm: f64,
    /// Rig time of a tyre change \[s\] (the thesis's 900 s).
    pub tyre_change_s: f64,
}

impl Default for AdaptiveConfig {
    fn default() -> Self {
        Self {
            target_ratio: 1.15,
            target_error_pct: None,
            target_confirmations: 2,
            budget_fraction: 1.0,
            points_per_sweep: 24,
            held_prior_std: 0.3,
            min_relative_gain: 0.005,
            severe_slip_angle_deg: 18.0,
            severe_load_factor: 1.75,
            bootstrap_by_cost: true,
            cover_envelope: false,
            wear_mm_per_mj: 0.208,
            wear_rate_log_sd: 1.0,
            usable_tread_mm: 4.0,
            tyre_change_s: 900.0,
        }
    }
}

impl AdaptiveConfig {
    /// Rig time a millimetre of tread costs \[s/mm\]: a tyre change per usable tread.
    pub fn wear_cost_s_per_mm(&self) -> f64 {
        self.tyre_change_s / self.usable_tread_mm
    }

    /// Checks ranges; the error names the key.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let pos = [
            ("target_ratio", self.target_ratio),
            ("budget_fraction", self.budget_fraction),
            ("held_prior_std", self.held_prior_std),
            ("severe_slip_angle_deg", self.severe_slip_angle_deg),
            ("severe_load_factor", self.severe_load_factor),
            ("usable_tread_mm", self.usable_tread_mm),
        ];
        for (k, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                return Err((k, format!("expected a positive number, got {v}")));
            }
        }
        if self.target_ratio < 1.0 {
            return Err((
                "target_ratio",
                format!("expected ≥ 1 (the full run's predicted error is the floor), got {}", self.target_ratio),
            ));
        }
        if let Some(t) = self.target_error_pct
            && !(t.is_finite() && t > 0.0)
        {
            return Err(("target_error_pct", format!("expected a positive percentage, got {t}")));
        }
        if !(self.min_relative_gain.is_finite() && (0.0..1.0).contains(&self.min_relative_gain)) {
            return Err(("min_relative_gain", format!("expected 0 ≤ x < 1, got {}", self.min_relative_gain)));
        }
        for (k, v) in [
            ("wear_mm_per_mj", self.wear_mm_per_mj),
            ("wear_rate_log_sd", self.wear_rate_log_sd),
            ("tyre_change_s", self.tyre_change_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err((k, format!("expected a number ≥ 0, got {v}")));
            }
        }
        if self.target_confirmations < 1 {
            return Err(("target_confirmations", "expected at least 1".into()));
        }
        if self.points_per_sweep < 2 {
            return Err(("points_per_sweep", format!("expected at least 2, got {}", self.points_per_sweep)));
        }
        Ok(())
    }
}
