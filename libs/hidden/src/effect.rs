//! The hidden effects and how their forms are drawn.
//!
//! Every effect is a state of the tyre (a temperature, a tread depth, a break-in history) acting
//! on the whole tyre through MF scaling factors and the loaded radius. The forms are chosen to
//! be *other* than the doctor's candidate forms (docs/doctor.md §3) and wider: an asymmetric
//! friction optimum on a lagged bulk temperature, stiffness with its own optimum, wear that
//! changes grip (either sign, non-linearly), break-in that recovers by a power law or in two
//! stages and changes shape and stiffness as well as grip.
//!
//! Parameters that only mean something against a log (a temperature optimum, a wear rate, a
//! power threshold) are drawn *relative* to the logs injected together — a quantile of their
//! temperatures, a depth lost by the most-sliding tyre — and resolved to absolute values
//! by [`crate::resolve`]; the report gives both.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The kinds of hidden effect the generator knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    /// Grip, stiffness and radius follow a lagged tread temperature.
    Thermal,
    /// Tread loss with sliding energy: radius, grip, stiffness, shape.
    Wear,
    /// A new tyre's grip, shape and stiffness recovering with severe sliding.
    BreakIn,
}

impl EffectKind {
    /// Every kind, in the order the bench reports them.
    pub const ALL: [EffectKind; 3] = [EffectKind::Thermal, EffectKind::Wear, EffectKind::BreakIn];

    /// The name the CLI, the truth JSON and the doctor use (`thermal`, `wear`, `break_in`).
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::Thermal => "thermal",
            EffectKind::Wear => "wear",
            EffectKind::BreakIn => "break_in",
        }
    }

    /// The kind of a name (`break-in` is accepted for `break_in`).
    pub fn parse(name: &str) -> Option<EffectKind> {
        let n = name.trim().replace('-', "_");
        EffectKind::ALL.into_iter().find(|k| k.name() == n)
    }
}

impl std::fmt::Display for EffectKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Shape of the friction-temperature curve around its optimum.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GripCurve {
    /// loss = L·x² on each side, x the distance from the optimum as a share of that side's
    /// temperature range (each side its own L: a different curvature below and above).
    AsymmetricQuadratic,
    /// loss = L·(1 − exp(−x²/(2·w²)))/(1 − exp(−1/(2·w²))): flat near the optimum, saturating
    /// far from it (a plateau), L at the end of each side.
    AsymmetricGaussian {
        /// Width w as a share of the side's range [-].
        width: f64,
    },
}

/// `thermal`: grip, stiffness and radius as functions of the generator's own bulk temperature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalEffect {
    /// Multiplies every change (0 = no effect).
    pub strength: f64,
    /// The bulk temperature is a first-order lag of the measured mean tread temperature
    /// (TRDTEMPI/C/O) with this time constant [s]; 0 = the surface reading itself.
    pub bulk_lag_s: f64,
    /// Share of the surface reading mixed into the grip temperature (the rest is the lagged
    /// bulk) [-].
    pub surface_weight: f64,
    /// Shape of μ(T).
    pub grip_curve: GripCurve,
    /// Where grip peaks: a quantile of the logs' grip temperatures [-].
    pub grip_optimum_quantile: f64,
    /// Lateral grip lost at the coldest grip temperature of the logs [-].
    pub grip_loss_cold: f64,
    /// Lateral grip lost at the hottest grip temperature of the logs [-].
    pub grip_loss_hot: f64,
    /// Longitudinal grip loss as a share of the lateral [-].
    pub grip_x_ratio: f64,
    /// Where stiffness is referenced: a quantile of the grip temperatures, apart from the grip
    /// optimum [-].
    pub stiffness_reference_quantile: f64,
    /// Stiffness falls by this share per temperature range above its reference (rises below) [-].
    pub stiffness_slope: f64,
    /// Stiffness curvature around its reference, per range squared [-] (≥ 0: an optimum).
    pub stiffness_curvature: f64,
    /// Loaded radius growth with temperature (the inflation pressure rising) [mm/K].
    pub radius_mm_per_k: f64,
}

/// `wear`: tread lost with the generator's own sliding energy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WearEffect {
    /// Multiplies the tread depth lost (0 = no effect).
    pub strength: f64,
    /// Tread lost by the most-sliding tyre of the logs at strength 1 [mm]; sets the rate.
    pub depth_at_end_mm: f64,
    /// Grip change per mm^exponent of tread lost (either sign) [-].
    pub grip_per_mm: f64,
    /// Exponent of the grip change in the depth lost [-].
    pub grip_exponent: f64,
    /// Stiffness gain per mm (less tread shuffle) [1/mm].
    pub stiffness_per_mm: f64,
    /// Shape factor λC gain per mm (more drop-off after the peak) [1/mm].
    pub shape_per_mm: f64,
    /// Pneumatic trail change per mm (a thinner tread, a shorter trail) [1/mm].
    pub trail_per_mm: f64,
}

/// How a break-in deficit recovers with severe sliding energy E.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Recovery {
    /// r = (1 + E/E0)^(−n).
    PowerLaw {
        /// n [-].
        exponent: f64,
    },
    /// r = a·exp(−E/E0) + (1 − a)·exp(−E/(m·E0)): a quick first stage, then a slow one.
    TwoStage {
        /// a [-].
        fast_share: f64,
        /// m [-].
        slow_ratio: f64,
    },
}

/// `break_in`: a new tyre's deficit, recovered with severe sliding energy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BreakInEffect {
    /// Multiplies every deficit (0 = no effect).
    pub strength: f64,
    /// The recovery's form.
    pub recovery: Recovery,
    /// Sliding power threshold of "severe": a quantile of the logs' in-sweep sliding power [-].
    pub threshold_quantile: f64,
    /// E0 as a share of the severe energy of the most-sliding tyre [-].
    pub energy_scale_share: f64,
    /// Grip deficit of the new tyre [-].
    pub grip_deficit: f64,
    /// Stiffness deficit of the new tyre [-] (either sign).
    pub stiffness_deficit: f64,
    /// Shape factor λC deficit of the new tyre [-] (either sign).
    pub shape_deficit: f64,
}

/// One hidden effect with its drawn form.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum HiddenEffect {
    /// See [`ThermalEffect`].
    Thermal(ThermalEffect),
    /// See [`WearEffect`].
    Wear(WearEffect),
    /// See [`BreakInEffect`].
    BreakIn(BreakInEffect),
}

impl HiddenEffect {
    /// Draws an effect of `kind` from the family (same `seed`, same form) at `strength`
    /// (1 = a typical effect, 0 = none; it multiplies the effect's size, not its form).
    pub fn draw(kind: EffectKind, seed: u64, strength: f64) -> HiddenEffect {
        // Each kind its own stream, so `thermal` and `wear` of one seed are unrelated.
        let salt = match kind {
            EffectKind::Thermal => 0x7468_6572,
            EffectKind::Wear => 0x7765_6172,
            EffectKind::BreakIn => 0x6272_6b69,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (salt << 20));
        match kind {
            EffectKind::Thermal => HiddenEffect::Thermal(draw_thermal(&mut rng, strength)),
            EffectKind::Wear => HiddenEffect::Wear(draw_wear(&mut rng, strength)),
            EffectKind::BreakIn => HiddenEffect::BreakIn(draw_break_in(&mut rng, strength)),
        }
    }

    /// Its kind.
    pub fn kind(&self) -> EffectKind {
        match self {
            HiddenEffect::Thermal(_) => EffectKind::Thermal,
            HiddenEffect::Wear(_) => EffectKind::Wear,
            HiddenEffect::BreakIn(_) => EffectKind::BreakIn,
        }
    }

    /// Its strength.
    pub fn strength(&self) -> f64 {
        match self {
            HiddenEffect::Thermal(t) => t.strength,
            HiddenEffect::Wear(w) => w.strength,
            HiddenEffect::BreakIn(b) => b.strength,
        }
    }
}

fn draw_thermal(rng: &mut ChaCha8Rng, strength: f64) -> ThermalEffect {
    // One case in six grips on the surface reading itself (laser flash and all).
    let bulk_lag_s = if rng.random::<f64>() < 1.0 / 6.0 { 0.0 } else { rng.random_range(5.0..120.0) };
    let surface_weight = if bulk_lag_s == 0.0 { 1.0 } else { rng.random_range(0.0..0.5) };
    let grip_curve = if rng.random::<bool>() {
        GripCurve::AsymmetricQuadratic
    } else {
        GripCurve::AsymmetricGaussian { width: rng.random_range(0.3..0.8) }
    };
    let grip_optimum_quantile: f64 = rng.random_range(0.25..0.75);
    // Asymmetry: the two sides' losses differ by a factor of up to 3 either way.
    let hot = rng.random_range(0.04..0.12);
    let ratio = (rng.random_range(-1.1..1.1_f64)).exp();
    let cold = (hot * ratio).min(0.16);
    // The stiffness reference sits at least 0.2 of the quantile range away from the grip optimum.
    let mut stiffness_reference_quantile: f64 = rng.random_range(0.1..0.9);
    while (stiffness_reference_quantile - grip_optimum_quantile).abs() < 0.2 {
        stiffness_reference_quantile = rng.random_range(0.1..0.9);
    }
    // Mostly softening when hot; sometimes stiffening.
    let slope_sign = if rng.random::<f64>() < 0.8 { 1.0 } else { -1.0 };
    ThermalEffect {
        strength,
        bulk_lag_s,
        surface_weight,
        grip_curve,
        grip_optimum_quantile,
        grip_loss_cold: cold,
        grip_loss_hot: hot,
        grip_x_ratio: rng.random_range(0.6..1.2),
        stiffness_reference_quantile,
        stiffness_slope: slope_sign * rng.random_range(0.03..0.10),
        stiffness_curvature: rng.random_range(0.0..0.05),
        radius_mm_per_k: rng.random_range(0.003..0.015),
    }
}

fn draw_wear(rng: &mut ChaCha8Rng, strength: f64) -> WearEffect {
    // Worn tyres mostly lose grip; some compounds gain a little as the skin wears off.
    let grip_sign = if rng.random::<f64>() < 0.7 { -1.0 } else { 1.0 };
    WearEffect {
        strength,
        depth_at_end_mm: rng.random_range(0.4..1.2),
        grip_per_mm: grip_sign * rng.random_range(0.02..0.08),
        grip_exponent: rng.random_range(0.6..1.6),
        stiffness_per_mm: rng.random_range(0.03..0.12),
        shape_per_mm: rng.random_range(0.02..0.08),
        trail_per_mm: -rng.random_range(0.0..0.06),
    }
}

fn draw_break_in(rng: &mut ChaCha8Rng, strength: f64) -> BreakInEffect {
    let recovery = if rng.random::<bool>() {
        Recovery::PowerLaw { exponent: rng.random_range(0.7..2.5) }
    } else {
        Recovery::TwoStage { fast_share: rng.random_range(0.3..0.8), slow_ratio: rng.random_range(5.0..20.0) }
    };
    BreakInEffect {
        strength,
        recovery,
        threshold_quantile: rng.random_range(0.0..0.6),
        energy_scale_share: rng.random_range(0.03..0.2),
        grip_deficit: rng.random_range(0.05..0.14),
        stiffness_deficit: rng.random_range(-0.04..0.08),
        shape_deficit: rng.random_range(-0.06..0.08),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_are_reproducible_and_differ_by_seed_and_kind() {
        let a = HiddenEffect::draw(EffectKind::Thermal, 3, 1.0);
        assert_eq!(a, HiddenEffect::draw(EffectKind::Thermal, 3, 1.0));
        assert_ne!(a, HiddenEffect::draw(EffectKind::Thermal, 4, 1.0));
        assert_eq!(a.kind(), EffectKind::Thermal);
        assert_eq!(HiddenEffect::draw(EffectKind::BreakIn, 3, 0.5).strength(), 0.5);
    }

    #[test]
    fn names_round_trip() {
        for k in EffectKind::ALL {
            assert_eq!(EffectKind::parse(k.name()), Some(k));
        }
        assert_eq!(EffectKind::parse("break-in"), Some(EffectKind::BreakIn));
        assert_eq!(EffectKind::parse("pressure"), None);
    }

    #[test]
    fn effects_serialise_with_their_kind() {
        let e = HiddenEffect::draw(EffectKind::Wear, 1, 2.0);
        let v = serde_json::to_value(&e).expect("serialises");
        assert_eq!(v["kind"], "wear");
        let back: HiddenEffect = serde_json::from_value(v).expect("reads back");
        assert_eq!(back, e);
    }
}
