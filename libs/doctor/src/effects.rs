//! The effect catalogue: each candidate effect's physical variable, its parametric extension of
//! MF-Tyre 6.1, and the evaluation of a base model with any set of extensions at the measured
//! operating points.
//!
//! Two families:
//! - **State effects** (`thermal`, `wear`, `break_in`, `speed`, `specimen`, `transient`): what
//!   MF-Tyre 6.1 does not have, driven by a state of the tyre the doctor derives from the log
//!   (grip temperature, sliding energy, severe sliding energy, belt speed, which tyre). All but
//!   `transient` act on the whole tyre through the MF scaling factors ([`crate::state`]);
//!   `transient` relaxes the slips.
//! - **Form errors** (`pressure`, `camber`, `load`, `offset`): operating-point misfits of the
//!   model MF-Tyre 6.1 could describe with its own coefficients; the candidate re-fits those
//!   coefficients (a base model whose pressure terms are zero, or wrong, is repaired where
//!   `tyrerig model eval` applies it directly). They are reported as the model's form error,
//!   never as a missing effect of the tyre's state.

use crate::data::Dataset;
use crate::state;
use mftyre::{MfInput, TyreParams, UseMode, evaluate_scaled};
use serde::Serialize;

/// Channels residuals are computed on.
pub const CHANNELS: [&str; 4] = ["FX", "FYW", "MZW", "DSTWOWHC"];
/// Channel index of FX.
pub const CH_FX: usize = 0;
/// Channel index of FYW.
pub const CH_FY: usize = 1;
/// Channel index of MZW.
pub const CH_MZ: usize = 2;
/// Channel index of DSTWOWHC.
pub const CH_RL: usize = 3;

/// A candidate effect (the vocabulary of `doctor.json`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// Tread temperature: the whole tyre with the (lagged) grip temperature.
    Thermal,
    /// Tread wear: the whole tyre and its loaded radius with sliding energy.
    Wear,
    /// Break-in: a new tyre's difference recovered with severe sliding.
    BreakIn,
    /// Transient relaxation of the slips.
    Transient,
    /// Inflation pressure (MF pressure coefficients).
    Pressure,
    /// Camber (MF camber coefficients).
    Camber,
    /// Belt speed: grip and stiffness.
    Speed,
    /// Load sensitivity (MF load coefficients).
    Load,
    /// Ply-steer / conicity offsets (MF shift coefficients).
    Offset,
    /// The tyre specimen: a later log's tyre differs from the first's (two physical tyres of
    /// one model, as TTC's cornering and drive/brake runs often are).
    Specimen,
    /// Not a candidate: the base's level, load, camber and pressure coefficients refitted
    /// beside a state effect that was fitted with its operating-point share taken out. A base
    /// fitted to the same logs had absorbed that share (a TTC run heats up cell by cell, and
    /// the fit gave the heat's grip loss to camber and load); applied to the whole state on
    /// top of that base, the effect would count it twice (on runs with a grip factor of the
    /// tread temperature hidden, FX χ² 47,786 → 321,564 with thermal added, without this).
    Rebase,
}

impl Effect {
    /// Every effect, catalogue order.
    pub const ALL: [Effect; 10] = [
        Effect::Thermal,
        Effect::Wear,
        Effect::BreakIn,
        Effect::Transient,
        Effect::Pressure,
        Effect::Camber,
        Effect::Speed,
        Effect::Load,
        Effect::Offset,
        Effect::Specimen,
    ];

    /// Name in `doctor.json` and the extension section.
    pub fn name(self) -> &'static str {
        match self {
            Effect::Thermal => "thermal",
            Effect::Wear => "wear",
            Effect::BreakIn => "break_in",
            Effect::Transient => "transient",
            Effect::Pressure => "pressure",
            Effect::Camber => "camber",
            Effect::Speed => "speed",
            Effect::Load => "load",
            Effect::Offset => "offset",
            Effect::Specimen => "specimen",
            Effect::Rebase => "rebase",
        }
    }

    /// Parses a name.
    pub fn parse(s: &str) -> Option<Effect> {
        Effect::ALL.into_iter().chain([Effect::Rebase]).find(|e| e.name() == s)
    }

    /// The variable the effect's signature is plotted against, with its unit.
    pub fn variable(self) -> (&'static str, &'static str) {
        match self {
            Effect::Thermal => ("grip temperature", "°C"),
            Effect::Wear => ("sliding energy on the tyre", "MJ"),
            Effect::BreakIn => ("sliding energy on the tyre", "MJ"),
            Effect::Transient => ("slip-angle rate", "deg/s"),
            Effect::Pressure => ("inflation pressure", "bar"),
            Effect::Camber => ("camber", "deg"),
            Effect::Speed => ("belt speed", "m/s"),
            Effect::Load => ("vertical load", "kN"),
            Effect::Offset => ("slip angle", "deg"),
            Effect::Specimen => ("tyre (log) of the test", "#"),
            Effect::Rebase => ("vertical load", "kN"),
        }
    }

    /// True for effects MF-Tyre 6.1 models with its own coefficients (the candidate refits them).
    pub fn is_refit(self) -> bool {
        matches!(self, Effect::Pressure | Effect::Camber | Effect::Load | Effect::Offset | Effect::Rebase)
    }

    /// The family: a state effect of the tyre, or the model's form error at an operating point.
    pub fn family(self) -> Family {
        if self.is_refit() { Family::FormError } else { Family::State }
    }

    /// The effect's variable at series sample `i`.
    pub fn variable_value(self, ds: &Dataset, i: usize) -> f64 {
        let s = &ds.series;
        match self {
            Effect::Thermal => s.temp_grip_c[i],
            Effect::Wear | Effect::BreakIn => s.sliding_energy_j[i] * 1e-6,
            Effect::Transient => s.alpha_rate_dps[i],
            Effect::Pressure => s.p_pa[i] * 1e-5,
            Effect::Camber => s.gamma_deg[i],
            Effect::Speed => s.v_mps[i],
            Effect::Load => s.fz_n[i] * 1e-3,
            Effect::Offset => s.alpha_deg[i],
            Effect::Specimen => s.tyre[i] as f64,
            Effect::Rebase => s.fz_n[i] * 1e-3,
        }
    }
}

/// The two families of what the doctor can add.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// A state of the tyre MF-Tyre 6.1 lacks (named as a missing effect).
    State,
    /// An operating-point misfit MF-Tyre 6.1's own coefficients can mend (reported as form error).
    FormError,
}

/// One parameter of an effect.
#[derive(Debug, Clone, Serialize)]
pub struct ParamSpec {
    /// Key in the extension section or the `.tir` coefficient key (refits).
    pub key: String,
    /// Starting value.
    pub init: f64,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
}

fn ps(key: &str, init: f64, lower: f64, upper: f64) -> ParamSpec {
    ParamSpec { key: key.to_owned(), init, lower, upper }
}

/// Why an effect cannot be tested on a dataset.
pub fn untestable_reason(effect: Effect, ds: &Dataset) -> Option<String> {
    let s = &ds.series;
    match effect {
        Effect::Thermal => {
            let r = ds.point_range(&s.temp_grip_c);
            (r < 3.0).then(|| format!("grip temperature spans only {r:.1} K"))
        }
        Effect::Pressure => {
            let r = ds.point_range(&s.p_pa) * 1e-5;
            (r < 0.15).then(|| format!("one inflation pressure only (range {r:.2} bar)"))
        }
        Effect::Camber => {
            let r = ds.point_range(&s.gamma_deg);
            (r < 1.0).then(|| format!("camber spans only {r:.2}°"))
        }
        Effect::Speed => {
            let r = ds.point_range(&s.v_mps);
            (r < 3.0).then(|| format!("speed spans only {r:.1} m/s"))
        }
        Effect::Load => {
            let r = ds.point_range(&s.fz_n);
            (r < 1000.0).then(|| format!("load spans only {r:.0} N"))
        }
        Effect::Wear | Effect::BreakIn => {
            let r = ds.point_range(&s.sliding_energy_j) * 1e-6;
            (r < 0.01).then(|| format!("sliding energy spans only {r:.3} MJ"))
        }
        Effect::Specimen => {
            let n = ds.points.iter().map(|&i| s.tyre[i]).max().map_or(0, |m| m + 1);
            (n < 2).then(|| "one tyre (log) only".to_owned())
        }
        Effect::Transient | Effect::Offset | Effect::Rebase => None,
    }
}

/// The parameters of `effect` on `ds` with base model `base`.
pub fn param_specs(effect: Effect, ds: &Dataset, base: &TyreParams) -> Vec<ParamSpec> {
    let lat = ds.has_lateral() || !ds.has_longitudinal();
    let lon = ds.has_longitudinal();
    let refit = |keys: &[&str], slack: f64| -> Vec<ParamSpec> {
        keys.iter()
            .filter_map(|k| base.get(k).map(|v| (k, v)))
            .map(|(k, v)| {
                let w = 2.0 * (v.abs() + slack);
                ps(k, v, v - w, v + w)
            })
            .collect()
    };
    match effect {
        // Fitted by linear least squares through the scaling factors' sensitivities
        // ([`crate::linfit`]), not by Levenberg–Marquardt.
        Effect::Thermal | Effect::Wear | Effect::BreakIn | Effect::Speed | Effect::Specimen => vec![],
        Effect::Transient => {
            let mut v = Vec::new();
            if lat {
                v.push(ps("TRANSIENT_SIGMA_Y0_M", 0.3, 0.002, 3.0));
                v.push(ps("TRANSIENT_ALPHA_HALF_DEG", 3.0, 0.2, 30.0));
            }
            if lon {
                v.push(ps("TRANSIENT_SIGMA_X0_M", 0.2, 0.002, 3.0));
                v.push(ps("TRANSIENT_KAPPA_HALF", 0.03, 0.002, 0.5));
            }
            v
        }
        Effect::Pressure => {
            let mut keys = vec!["PFZ1"];
            if lat {
                keys.extend(["PPY1", "PPY2", "PPY3", "PPY4", "PPZ1", "PPZ2"]);
            }
            if lon {
                keys.extend(["PPX1", "PPX2", "PPX3", "PPX4"]);
            }
            refit(&keys, 1.0)
        }
        Effect::Camber => {
            let mut keys = vec![];
            if lat {
                keys.extend(["PKY6", "PDY3", "PVY3", "QHZ3"]);
            }
            if lon {
                keys.push("PDX3");
            }
            refit(&keys, 1.0)
        }
        Effect::Load => {
            let mut keys = vec![];
            if lat {
                keys.extend(["PDY2", "PKY2", "QBZ2"]);
            }
            if lon {
                keys.extend(["PDX2", "PKX2"]);
            }
            refit(&keys, 1.0)
        }
        Effect::Offset => {
            let mut keys = vec![];
            if lat {
                keys.extend(["PHY1", "PVY1", "QHZ1"]);
            }
            if lon {
                keys.extend(["PHX1", "PVX1"]);
            }
            refit(&keys, 0.02)
        }
        // The levels, and the operating-point terms the data span, of both forces.
        Effect::Rebase => {
            let mut out = Vec::new();
            let mut levels = vec![];
            if lat {
                levels.extend(["PDY1", "PKY1", "PCY1", "PEY1", "PEY2", "QDZ1", "QBZ1", "QCZ1"]);
            }
            if lon {
                levels.extend(["PDX1", "PKX1", "PCX1", "PEX1", "PEX2", "PKX3"]);
            }
            if lat && lon {
                levels.extend(["RBX1", "RBX2", "RCX1", "RBY1", "RBY2", "RCY1"]);
            }
            out.extend(refit(&levels, 1.0));
            for e in [Effect::Load, Effect::Camber, Effect::Pressure] {
                if untestable_reason(e, ds).is_none() {
                    out.extend(param_specs(e, ds, base));
                }
            }
            out
        }
    }
}

/// One effect with parameter values (a state effect's terms and choice of knobs, a refit's MF
/// coefficients, the transient's relaxation lengths).
#[derive(Debug, Clone, Serialize)]
pub struct EffectParams {
    /// The effect.
    pub effect: Effect,
    /// Parameter keys.
    pub keys: Vec<String>,
    /// Values, as `keys`.
    pub values: Vec<f64>,
}

impl EffectParams {
    /// A value by key (0 when absent).
    pub fn get(&self, key: &str) -> f64 {
        self.keys.iter().position(|k| k == key).map_or(0.0, |i| self.values[i])
    }

    /// A state effect's coefficients, parsed for evaluation.
    pub fn parsed(&self) -> state::Parsed {
        state::Parsed::from_entries(self.effect, self.keys.iter().map(String::as_str).zip(self.values.iter().copied()))
    }
}

/// Evaluates a base model with extensions at a dataset's points. Precomputes the state
/// variables that do not depend on parameters.
#[derive(Debug)]
pub struct Evaluator<'a> {
    /// The data.
    pub ds: &'a Dataset,
    /// The base model.
    pub base: &'a TyreParams,
    /// Reference temperature of the thermal extension (median grip temperature) [°C].
    pub t_ref_c: f64,
    /// Reference speed of the speed extension: LONGVL for a given model, the points' median
    /// speed for a base fitted to them [m/s].
    pub v_ref_mps: f64,
    /// Severe sliding energy per [`state::BREAK_IN_THRESHOLDS_W`] [J].
    severe: std::sync::Arc<Vec<Vec<f64>>>,
    /// Each of [`state::THERMAL_TEMPERATURES`] over the series [°C].
    lagged_temp: std::sync::Arc<Vec<Vec<f64>>>,
    /// The last relaxed slip series by transient parameters: a named transient held fixed is
    /// evaluated again with every prediction, and its recursion runs over every full-rate
    /// sample.
    relaxed_cache: std::sync::Arc<std::sync::Mutex<Vec<RelaxedEntry>>>,
    /// A state effect whose state acts with the operating point's share taken out
    /// ([`crate::form::PartialOut`]): its basis values are z − E[z | x] at every point.
    partial_out: Option<(Effect, std::sync::Arc<crate::form::PartialOut>)>,
}

type RelaxedEntry = (Vec<f64>, std::sync::Arc<(Vec<f64>, Vec<f64>)>);
/// Relaxed series kept (a few: candidates are scored on parallel workers).
const RELAXED_CACHE: usize = 4;

/// A perturbation of one scaling factor's logarithm (for sensitivities).
#[derive(Debug, Clone, Copy)]
pub struct Perturb {
    /// Index into [`state::SCALING`].
    pub factor: usize,
    /// Added to the factor's logarithm.
    pub log_step: f64,
}

impl<'a> Evaluator<'a> {
    /// Prepares the evaluator.
    pub fn new(ds: &'a Dataset, base: &'a TyreParams) -> Self {
        let mut temps: Vec<f64> =
            ds.points.iter().map(|&i| ds.series.temp_grip_c[i]).filter(|v| v.is_finite()).collect();
        temps.sort_by(f64::total_cmp);
        let t_ref_c = if temps.is_empty() { 25.0 } else { temps[temps.len() / 2] };
        let severe = state::BREAK_IN_THRESHOLDS_W.iter().map(|&th| ds.series.severe_energy_j(th)).collect();
        let s = &ds.series;
        let lagged_temp = state::THERMAL_TEMPERATURES
            .iter()
            .map(|&(source, tau)| state::lagged(&s.t_s, Self::temp_source(ds, source), &s.new_tyre, tau))
            .collect();
        let v_ref_mps = if base.longvl_mps() > 0.0 { base.longvl_mps() } else { 16.6 };
        Self {
            ds,
            base,
            t_ref_c,
            v_ref_mps,
            severe: std::sync::Arc::new(severe),
            lagged_temp: std::sync::Arc::new(lagged_temp),
            relaxed_cache: Default::default(),
            partial_out: None,
        }
    }

    /// The same evaluator with `effect`'s state partialled out of the operating point
    /// ([`crate::form::PartialOut`]); the precomputed series are shared, not copied.
    pub fn partialled_out(&self, effect: Effect, weights: std::sync::Arc<crate::form::PartialOut>) -> Self {
        Self {
            ds: self.ds,
            base: self.base,
            t_ref_c: self.t_ref_c,
            v_ref_mps: self.v_ref_mps,
            severe: self.severe.clone(),
            lagged_temp: self.lagged_temp.clone(),
            relaxed_cache: self.relaxed_cache.clone(),
            partial_out: Some((effect, weights)),
        }
    }

    /// Whether `effect`'s state is partialled out here.
    pub fn partialled(&self, effect: Effect) -> bool {
        self.partial_out_of(effect).is_some()
    }

    /// The weights of `effect` if its state is partialled out here.
    fn partial_out_of(&self, effect: Effect) -> Option<&crate::form::PartialOut> {
        self.partial_out.as_ref().filter(|(e, _)| *e == effect).map(|(_, w)| w.as_ref())
    }

    /// The references of the state variables.
    pub fn references(&self) -> state::References {
        state::References { t_ref_c: self.t_ref_c, v_ref_mps: self.v_ref_mps }
    }

    fn temp_source(ds: &Dataset, source: state::TempSource) -> &[f64] {
        match source {
            state::TempSource::Grip => &ds.series.temp_grip_c,
            state::TempSource::Laser => &ds.series.temp_laser_c,
        }
    }

    /// The choices tried for `effect`; thermal's with their reference and range from the data
    /// (the median and the 2 %/98 % quantiles of the temperature over the points); `centred`:
    /// every basis measured from its mean over the points (a base fitted to these logs, see
    /// [`state::Choice::neutral`]).
    pub fn choice_grid(&self, effect: Effect, centred: bool) -> Vec<state::Choice> {
        let mut grid = state::Choice::grid(effect);
        if effect == Effect::Thermal {
            for c in &mut grid {
                let (temp, _) = self.choice_series(c);
                let mut v: Vec<f64> = self.ds.points.iter().map(|&i| temp[i]).filter(|t| t.is_finite()).collect();
                if v.is_empty() {
                    continue;
                }
                v.sort_by(f64::total_cmp);
                let at = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
                c.t_ref_c = at(0.5);
                c.t_range_c = [at(state::THERMAL_RANGE_QUANTILES[0]), at(state::THERMAL_RANGE_QUANTILES[1])];
            }
        }
        let centred_bases = match effect {
            _ if !centred => 0..0,
            Effect::Wear | Effect::BreakIn => 0..state::SHAPE_BASES,
            // x⁰ is the level, which a fitted base has already.
            Effect::Thermal => 1..state::THERMAL_BASES,
            _ => 0..0,
        };
        for c in &mut grid {
            for b in centred_bases.clone() {
                let values = self.basis_at_points(effect, b as u8, c);
                let valid: Vec<f64> = values.into_iter().filter(|v| v.is_finite()).collect();
                if !valid.is_empty() {
                    c.neutral[b] = valid.iter().sum::<f64>() / valid.len() as f64;
                }
            }
        }
        grid
    }

    /// Relaxed slip angle and slip ratio series for the transient extension:
    /// dα'/ds = (α − α')/σ(α'), σ(α') = σ0 / (1 + (α'/α½)²), likewise for κ.
    pub fn relaxed(&self, e: &EffectParams) -> (Vec<f64>, Vec<f64>) {
        let s = &self.ds.series;
        let sy0 = e.get("TRANSIENT_SIGMA_Y0_M");
        let ah = e.get("TRANSIENT_ALPHA_HALF_DEG").max(1e-3);
        let sx0 = e.get("TRANSIENT_SIGMA_X0_M");
        let kh = e.get("TRANSIENT_KAPPA_HALF").max(1e-5);
        let n = s.len();
        let mut a = s.alpha_deg.clone();
        let mut k = s.kappa.clone();
        for i in 1..n {
            let dt = s.t_s[i] - s.t_s[i - 1];
            if !(0.0..=0.5).contains(&dt) {
                continue;
            }
            let ds_m = s.v_mps[i].max(0.0) * dt;
            if sy0 > 0.0 {
                let sig = sy0 / (1.0 + (a[i - 1] / ah).powi(2));
                let g = 1.0 - (-ds_m / sig.max(1e-4)).exp();
                a[i] = a[i - 1] + g * (s.alpha_deg[i] - a[i - 1]);
            }
            if sx0 > 0.0 {
                let sig = sx0 / (1.0 + (k[i - 1] / kh).powi(2));
                let g = 1.0 - (-ds_m / sig.max(1e-4)).exp();
                k[i] = k[i - 1] + g * (s.kappa[i] - k[i - 1]);
            }
        }
        (a, k)
    }

    /// [`Self::relaxed`], remembered for the last few parameter sets.
    fn relaxed_cached(&self, e: &EffectParams) -> std::sync::Arc<(Vec<f64>, Vec<f64>)> {
        let key = e.values.clone();
        if let Ok(c) = self.relaxed_cache.lock()
            && let Some((_, v)) = c.iter().find(|(k, _)| *k == key)
        {
            return v.clone();
        }
        let v = std::sync::Arc::new(self.relaxed(e));
        if let Ok(mut c) = self.relaxed_cache.lock() {
            if c.len() >= RELAXED_CACHE {
                c.remove(0);
            }
            c.push((key, v.clone()));
        }
        v
    }

    /// The state series a state effect's choice reads: lagged temperature and severe energy
    /// (from the precomputed grids, or computed when the choice is not on them).
    fn choice_series(&self, c: &state::Choice) -> (std::borrow::Cow<'_, [f64]>, std::borrow::Cow<'_, [f64]>) {
        use std::borrow::Cow;
        let s = &self.ds.series;
        let lagged =
            |lag_s: f64| match state::THERMAL_TEMPERATURES.iter().position(|&(src, l)| src == c.source && l == lag_s) {
                Some(i) => Cow::Borrowed(self.lagged_temp[i].as_slice()),
                None => Cow::Owned(state::lagged(&s.t_s, Self::temp_source(self.ds, c.source), &s.new_tyre, lag_s)),
            };
        let temp = if c.surface_weight > 0.0 {
            let (surface, bulk) = (lagged(0.0), lagged(c.lag_s));
            let w = c.surface_weight;
            Cow::Owned(surface.iter().zip(bulk.iter()).map(|(a, b)| w * a + (1.0 - w) * b).collect())
        } else {
            lagged(c.lag_s)
        };
        let severe = match state::BREAK_IN_THRESHOLDS_W.iter().position(|&t| t == c.threshold_w) {
            Some(i) => Cow::Borrowed(self.severe[i].as_slice()),
            None => Cow::Owned(s.severe_energy_j(c.threshold_w)),
        };
        (temp, severe)
    }

    /// The state at series sample `i` as a state effect with choice series `(temp, severe)`
    /// reads it.
    pub fn state_at(&self, temp: &[f64], severe: &[f64], i: usize) -> state::StateAt {
        let s = &self.ds.series;
        state::StateAt {
            temp_c: temp[i],
            energy_mj: s.sliding_energy_j[i] * 1e-6,
            severe_kj: severe[i] * 1e-3,
            speed_mps: s.v_mps[i],
            tyre: s.tyre[i],
        }
    }

    /// Basis function values of `effect`'s `basis` at every point, for `choice`.
    /// (With the operating point's share taken out where this evaluator partials `effect` out.)
    pub fn basis_at_points(&self, effect: Effect, basis: u8, choice: &state::Choice) -> Vec<f64> {
        let raw = self.raw_basis_at_points(effect, basis, choice);
        match self.partial_out_of(effect) {
            Some(w) => w.residualized(&raw),
            None => raw,
        }
    }

    /// Basis function values as the state gives them, never partialled out (for the size of a
    /// coefficient's prior: the state's own range).
    pub fn raw_basis_at_points(&self, effect: Effect, basis: u8, choice: &state::Choice) -> Vec<f64> {
        let (temp, severe) = self.choice_series(choice);
        let refs = self.references();
        self.ds
            .points
            .iter()
            .map(|&i| state::basis(effect, basis, &self.state_at(&temp, &severe, i), choice, &refs))
            .collect()
    }

    /// Predictions [FX, FYW, MZW, DSTWOWHC] at the point ordinals `which` with `effects`.
    pub fn predict(&self, effects: &[EffectParams], which: &[usize]) -> Vec<[f64; 4]> {
        self.predict_perturbed(effects, which, None)
    }

    /// As [`Self::predict`], with one scaling factor's logarithm moved by `perturb`.
    pub fn predict_perturbed(
        &self,
        effects: &[EffectParams],
        which: &[usize],
        perturb: Option<Perturb>,
    ) -> Vec<[f64; 4]> {
        let s = &self.ds.series;
        let mut params = self.base.clone();
        for e in effects.iter().filter(|e| e.effect.is_refit()) {
            for (k, v) in e.keys.iter().zip(&e.values) {
                // Keys come from `param_specs`, which only lists keys the base has.
                if params.set(k, *v).is_err() {
                    continue;
                }
            }
        }
        let relaxed = effects.iter().find(|e| e.effect == Effect::Transient).map(|e| self.relaxed_cached(e));
        let states: Vec<_> = effects
            .iter()
            .filter(|e| state::is_state_scaling(e.effect))
            .map(|e| {
                let p = e.parsed();
                let series = self.choice_series(&p.choice);
                (p, series)
            })
            .collect();
        let refs = self.references();
        // A partialled-out state effect: its contribution (eight log-factors and the radius) at
        // every point, for the operating point's share of it.
        let partialled: Option<(usize, &crate::form::PartialOut, Vec<[f64; 9]>)> =
            states.iter().enumerate().find_map(|(si, (p, (temp, severe)))| {
                let w = self.partial_out_of(p.effect)?;
                let contrib = self
                    .ds
                    .points
                    .iter()
                    .map(|&i| {
                        let (mut log_f, mut drl_m) = ([0.0; 8], 0.0);
                        p.accumulate(&self.state_at(temp, severe, i), &refs, &mut log_f, &mut drl_m);
                        std::array::from_fn(|m| if m < 8 { log_f[m] } else { drl_m })
                    })
                    .collect();
                Some((si, w, contrib))
            });
        which
            .iter()
            .map(|&kpt| {
                let i = self.ds.points[kpt];
                let mut log_f = [0.0; 8];
                let mut drl_m = 0.0;
                for (si, (p, (temp, severe))) in states.iter().enumerate() {
                    match &partialled {
                        Some((pi, w, contrib)) if *pi == si => {
                            let left = w.residual_at(contrib, kpt);
                            for m in 0..8 {
                                log_f[m] += left[m];
                            }
                            drl_m += left[8];
                        }
                        _ => p.accumulate(&self.state_at(temp, severe, i), &refs, &mut log_f, &mut drl_m),
                    }
                }
                if let Some(pt) = perturb
                    && let Some(l) = log_f.get_mut(pt.factor)
                {
                    *l += pt.log_step;
                }
                let mut sc = params.scaling;
                state::apply(&mut sc, &log_f);
                let (alpha_deg, kappa) = match relaxed.as_deref() {
                    Some((a, k)) => (a[i], k[i]),
                    None => (s.alpha_deg[i], s.kappa[i]),
                };
                let input = MfInput {
                    fz_n: s.fz_n[i].max(0.0),
                    kappa,
                    alpha_rad: alpha_deg.to_radians(),
                    gamma_rad: s.gamma_deg[i].to_radians(),
                    phit_per_m: 0.0,
                    vx_mps: s.v_mps[i],
                    p_pa: s.p_pa[i],
                    omega_radps: s.omega_radps[i].max(0.0),
                };
                let o = evaluate_scaled(&params, &sc, UseMode::M111, &input);
                [o.fx_n, o.fy_n, o.mz_nm, o.rl_m + drl_m]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    //! Each extension's fit recovers its parameters from synthetic data made with them.
    use super::*;
    use crate::data::{Series, SweepInfo};
    use crate::fit::{FitOptions, FitSpec, fit_effects, measured};

    fn base() -> TyreParams {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../launch-config/tyres/MagicFormula61_Paramerters.tir");
        TyreParams::read_tir(&p).expect("tyre file")
    }

    /// Eight slip-angle sweeps 0 → −10° → +10° → 0 at 5 °/s, 100 Hz, points at 10 Hz; loads,
    /// pressures and speeds cycle between sweeps; the grip temperature rises with sliding and
    /// falls between sweeps; sliding energy accumulates.
    fn synthetic() -> Dataset {
        let mut s = Series::default();
        let mut ds = Dataset::default();
        let (mut t, mut e) = (0.0, 0.0);
        let dt = 0.01;
        for sw in 0..8usize {
            ds.sweeps.push(SweepInfo {
                name: format!("sw{sw}"),
                index_in_log: sw as u32,
                log: "synthetic".into(),
                ordinal: sw,
                coupled: false,
            });
            let fz = [3000.0, 5000.0, 7000.0][sw % 3];
            let p = [2.2e5, 2.6e5, 3.0e5, 2.6e5][sw % 4];
            let v = [16.6, 10.0, 25.0][sw % 3];
            let mut temp = 30.0 + 8.0 * sw as f64 % 40.0;
            let n = (40.0 / 5.0 / dt) as usize;
            for j in 0..n {
                let u = j as f64 * dt * 5.0;
                let a = if u < 10.0 {
                    -u
                } else if u < 30.0 {
                    -10.0 + (u - 10.0)
                } else {
                    10.0 - (u - 30.0)
                };
                let power = 2000.0 * a.abs();
                e += power * dt;
                temp += power * dt / 4000.0 - (temp - 25.0) * dt / 200.0;
                let i = s.t_s.len();
                s.t_s.push(t);
                s.sweep.push(sw);
                s.new_tyre.push(i == 0);
                s.tyre.push(0);
                s.alpha_deg.push(a);
                s.kappa.push(0.0);
                s.fz_n.push(fz);
                s.gamma_deg.push(0.0);
                s.p_pa.push(p);
                s.v_mps.push(v);
                s.omega_radps.push(v / 0.31);
                s.fx_n.push(0.0);
                s.fy_n.push(0.0);
                s.mz_nm.push(0.0);
                s.rl_m.push(0.0);
                s.temp_laser_c.push(temp);
                s.sliding_power_w.push(power);
                s.sliding_energy_j.push(e);
                s.temp_grip_c.push(temp);
                s.alpha_rate_dps.push(0.0);
                s.kappa_rate_ps.push(0.0);
                if j % 10 == 0 {
                    ds.points.push(i);
                }
                t += dt;
            }
            t += 5.0;
        }
        ds.series = s;
        ds
    }

    /// Writes `pred` into the dataset's measured channels.
    fn set_measured(ds: &mut Dataset, pred: &[[f64; 4]]) {
        for (k, p) in pred.iter().enumerate() {
            let i = ds.points[k];
            ds.series.fx_n[i] = p[0];
            ds.series.fy_n[i] = p[1];
            ds.series.mz_nm[i] = p[2];
            ds.series.rl_m[i] = p[3];
        }
    }

    /// Makes the "measurements" with a state effect of the given terms and choice, then fits its
    /// terms back through the sensitivities; returns the fitted values in `truth`'s order.
    fn recover_state(effect: Effect, choice: state::Choice, truth: &[(state::Term, f64)]) -> Vec<f64> {
        let b = base();
        let mut ds = synthetic();
        let entries = choice.entries(effect);
        let truth_p = EffectParams {
            effect,
            keys: entries
                .iter()
                .map(|e| e.0.clone())
                .chain(truth.iter().map(|(t, _)| state::term_key(effect, *t)))
                .collect(),
            values: entries.iter().map(|e| e.1).chain(truth.iter().map(|(_, v)| *v)).collect(),
        };
        let all: Vec<usize> = (0..ds.len()).collect();
        let pred = Evaluator::new(&ds, &b).predict(std::slice::from_ref(&truth_p), &all);
        set_measured(&mut ds, &pred);
        let ev = Evaluator::new(&ds, &b);
        let meas = measured(&ev);
        let terms: Vec<state::Term> = truth.iter().map(|(t, _)| *t).collect();
        let design = crate::linfit::with_candidate(&ev, &[], &[], effect, choice, terms);
        let lin0 = crate::linfit::linearize(&ev, &[]);
        let sigma = [10.0, 10.0, 1.0, 1e-4];
        let fitted = crate::linfit::fit_all(&ev, design, &lin0, &[], &|k| meas[k], &sigma);
        let got = &fitted.effects[0];
        truth.iter().map(|(t, _)| got.get(&state::term_key(effect, *t))).collect()
    }

    fn close(got: &[f64], want: &[f64], tol: f64) {
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= tol * w.abs().max(1e-3), "got {got:?}, want {want:?}");
        }
    }

    use crate::state::{Factor, Term};

    /// A specimen term whose factor acts only on one tyre's sweeps (λμx where only the second
    /// tyre was driven and braked to 8 % slip, as a TTC pair's drive/brake run on its own specimen is) has
    /// no state variation to fit with the operating point's share taken out: it is dropped,
    /// where the lateral terms, which both tyres' sweeps show, are kept. (Fitted on the
    /// kernel's leftovers, such a λμx came out at e^191 on real-like TTC runs.)
    #[test]
    fn a_term_that_acts_on_one_tyre_only_is_not_fitted_partialled() {
        let mut ds = synthetic();
        for i in 0..ds.series.len() {
            let second = ds.series.sweep[i] >= 4;
            ds.series.tyre[i] = usize::from(second);
            ds.series.new_tyre[i] = i == 0 || (second && ds.series.sweep[i - 1] < 4);
            // Only the second tyre is driven (its last two sweeps); its first two are lateral
            // sweeps like the first tyre's.
            if ds.series.sweep[i] >= 6 {
                ds.series.kappa[i] = 0.08;
            }
        }
        let b = base();
        let ev = Evaluator::new(&ds, &b);
        let po = std::sync::Arc::new(crate::form::PartialOut::new(&ds, &crate::form::Bandwidths::from_data(&ds)));
        let evp = ev.partialled_out(Effect::Specimen, po);
        let lin = crate::linfit::linearize(&ev, &[]);
        let cov = state::Coverage { lateral: true, longitudinal: true, radius: false, tyres: 2, levels: false };
        let design = crate::linfit::with_candidate(
            &evp,
            &[],
            &[],
            Effect::Specimen,
            state::Choice::default(),
            state::terms(Effect::Specimen, cov),
        );
        let sigma = [20.0, 20.0, 2.0, 1e-4];
        let largest =
            crate::linfit::largest_partialled_share(&evp, &design, &lin, &sigma, 0).expect("partialled").share;
        let kept: Vec<Factor> =
            crate::linfit::without_aliased(&evp, design, &lin, &sigma, 0).cols.iter().map(|c| c.term.factor).collect();
        assert!(!kept.contains(&Factor::MuX), "kept {kept:?}");
        assert!(kept.contains(&Factor::MuY) && kept.contains(&Factor::Ky), "kept {kept:?}");
        assert!(largest >= crate::linfit::MIN_PARTIALLED_SHARE, "{largest}");
        // With the λμx term alone, nothing is left to fit: the largest share says how nearly the
        // plan ties the state to the operating point (what the report then tells the user).
        let mux_only: Vec<Term> =
            state::terms(Effect::Specimen, cov).into_iter().filter(|t| t.factor == Factor::MuX).collect();
        assert!(!mux_only.is_empty());
        let design =
            crate::linfit::with_candidate(&evp, &[], &[], Effect::Specimen, state::Choice::default(), mux_only);
        let largest =
            crate::linfit::largest_partialled_share(&evp, &design, &lin, &sigma, 0).expect("partialled").share;
        assert!(largest < crate::linfit::MIN_PARTIALLED_SHARE, "{largest}");
        assert!(crate::linfit::without_aliased(&evp, design, &lin, &sigma, 0).cols.is_empty());
        // Where the effect is not partialled out, there is no screen and no share.
        let design = crate::linfit::with_candidate(
            &ev,
            &[],
            &[],
            Effect::Specimen,
            state::Choice::default(),
            state::terms(Effect::Specimen, cov),
        );
        assert_eq!(crate::linfit::largest_partialled_share(&ev, &design, &lin, &sigma, 0), None);
    }

    #[test]
    fn the_force_level_moves_grip_and_stiffness_of_both_forces_alike() {
        let p = state::Parsed {
            effect: Effect::Thermal,
            choice: state::Choice { t_ref_c: 40.0, ..state::Choice::default() },
            terms: vec![(Term { factor: Factor::Force, basis: 1 }, -0.1)],
        };
        let (mut log_f, mut drl) = ([0.0; 8], 0.0);
        let refs = state::References { t_ref_c: 40.0, v_ref_mps: 16.6 };
        p.accumulate(&state::StateAt { temp_c: 60.0, ..Default::default() }, &refs, &mut log_f, &mut drl);
        // x = (60 − 40) / 10 = 2: every force factor's logarithm −0.2, nothing else.
        assert_eq!(log_f, [-0.2, -0.2, -0.2, -0.2, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(drl, 0.0);
        let key = state::term_key(Effect::Thermal, Term { factor: Factor::Force, basis: 2 });
        assert_eq!(key, "THERMAL_FORCE_2");
        assert_eq!(state::parse_term(Effect::Thermal, &key), Some(Term { factor: Factor::Force, basis: 2 }));
    }
    fn t(factor: Factor, basis: u8) -> Term {
        Term { factor, basis }
    }

    #[test]
    fn thermal_extension_recovers_grip_stiffness_and_trail_terms() {
        // A quarter of the grip at the extremes: the Gauss–Newton step makes it exact.
        let truth = [
            (t(Factor::MuY, 0), -0.01),
            (t(Factor::MuY, 1), -0.05),
            (t(Factor::MuY, 2), -0.04),
            (t(Factor::Ky, 1), -0.03),
            (t(Factor::Trail, 1), 0.05),
        ];
        let want: Vec<f64> = truth.iter().map(|x| x.1).collect();
        let choice = state::Choice { lag_s: 30.0, t_ref_c: 40.0, ..state::Choice::default() };
        close(&recover_state(Effect::Thermal, choice, &truth), &want, 0.05);
    }

    /// A worn tyre's radius only shrinks: wear's radius term is fitted where it does, and held
    /// at zero where the data would have it grow with sliding energy, while its grip term is
    /// still fitted.
    #[test]
    fn wear_radius_shrinks_with_sliding_or_is_held_at_zero() {
        let shrinks = [(t(Factor::MuY, 0), -0.08), (t(Factor::Radius, 0), -2.5)];
        close(&recover_state(Effect::Wear, state::Choice::default(), &shrinks), &[-0.08, -2.5], 0.05);
        let grows = [(t(Factor::MuY, 0), -0.08), (t(Factor::Radius, 0), 2.5)];
        let got = recover_state(Effect::Wear, state::Choice::default(), &grows);
        assert_eq!(got[1], 0.0, "radius slope {got:?}");
        assert!((got[0] + 0.08).abs() < 0.01, "grip slope {got:?}");
    }

    #[test]
    fn wear_extension_recovers_grip_stiffness_and_radius() {
        let truth = [(t(Factor::MuY, 0), -0.08), (t(Factor::Ky, 0), 0.1), (t(Factor::Radius, 0), -2.5)];
        let want: Vec<f64> = truth.iter().map(|x| x.1).collect();
        close(&recover_state(Effect::Wear, state::Choice::default(), &truth), &want, 0.05);
    }

    #[test]
    fn break_in_extension_recovers_its_deficit() {
        let choice = state::Choice { energy_kj: 100.0, threshold_w: 5_000.0, ..state::Choice::default() };
        let truth = [(t(Factor::MuY, 0), -0.12), (t(Factor::Cy, 0), 0.05)];
        let want: Vec<f64> = truth.iter().map(|x| x.1).collect();
        close(&recover_state(Effect::BreakIn, choice, &truth), &want, 0.05);
    }

    /// A new tyre never grips more than a broken-in one: break-in's grip term is fitted where
    /// the new tyre's grip is lower, and held at zero where the data would have it higher (grip
    /// falling as the tyre slides is wear's or heat's, not a break-in's), while its shape term is
    /// still fitted (there it takes what it can of the surplus).
    #[test]
    fn break_in_grip_only_lowers_a_new_tyres_grip() {
        let choice = state::Choice { energy_kj: 100.0, threshold_w: 5_000.0, ..state::Choice::default() };
        let deficit = [(t(Factor::MuY, 0), -0.12), (t(Factor::Cy, 0), 0.05)];
        close(&recover_state(Effect::BreakIn, choice, &deficit), &[-0.12, 0.05], 0.05);
        let surplus = [(t(Factor::MuY, 0), 0.12), (t(Factor::Cy, 0), 0.05)];
        let got = recover_state(Effect::BreakIn, choice, &surplus);
        assert_eq!(got[0], 0.0, "grip {got:?}");
        assert!(got[1] != 0.0, "shape {got:?}");
    }

    #[test]
    fn speed_extension_recovers_its_coefficients() {
        let truth = [(t(Factor::MuY, 0), -0.05), (t(Factor::Ky, 0), 0.04)];
        let want: Vec<f64> = truth.iter().map(|x| x.1).collect();
        close(&recover_state(Effect::Speed, state::Choice::default(), &truth), &want, 0.05);
    }

    /// Makes the "measurements" from `truth` with `base_truth`, then fits `effect` (transient
    /// or a refit) on `base_fit` by Levenberg–Marquardt.
    fn recover(effect: Effect, truth: &[f64], base_truth: &TyreParams, base_fit: &TyreParams) -> Vec<f64> {
        let mut ds = synthetic();
        let specs = param_specs(effect, &ds, base_fit);
        let truth_p =
            EffectParams { effect, keys: specs.iter().map(|p| p.key.clone()).collect(), values: truth.to_vec() };
        let all: Vec<usize> = (0..ds.len()).collect();
        let pred = {
            let ev = Evaluator::new(&ds, base_truth);
            let fx: Vec<EffectParams> = if effect.is_refit() { vec![] } else { vec![truth_p.clone()] };
            ev.predict(&fx, &all)
        };
        set_measured(&mut ds, &pred);
        let ev = Evaluator::new(&ds, base_fit);
        let meas = measured(&ev);
        let (fitted, cost) = fit_effects(
            &ev,
            &[FitSpec { effect, params: specs }],
            &[],
            &all,
            &meas,
            [10.0, 10.0, 1.0, 1e-4],
            FitOptions { max_iterations: 60 },
        );
        assert!(cost < 1.0, "{}: cost {cost} after the fit", effect.name());
        fitted[0].values.clone()
    }

    #[test]
    fn transient_extension_recovers_relaxation_length() {
        let b = base();
        let truth = [0.6, 2.5];
        close(&recover(Effect::Transient, &truth, &b, &b), &truth, 0.05);
    }

    #[test]
    fn pressure_refit_restores_zeroed_pressure_terms() {
        let truth_model = base();
        // Zero the lateral pressure terms the candidate refits (a lateral-only dataset does not
        // determine PPX1–4, which still move FX at κ = 0 through Bx·SHx).
        let mut zeroed = truth_model.clone();
        for k in ["PPY1", "PPY2", "PPY3", "PPY4", "PPZ1", "PPZ2"] {
            zeroed.set(k, 0.0).expect("key");
        }
        let got = recover(Effect::Pressure, &[], &truth_model, &zeroed);
        // PFZ1, PPY1, PPY2, PPY3, PPY4, PPZ1: the cornering-stiffness and trail terms are
        // well determined by ±10° sweeps at three pressures.
        let want_ppy1 = truth_model.get("PPY1").expect("PPY1");
        assert!((got[1] - want_ppy1).abs() < 0.05 * want_ppy1.abs() + 0.02, "PPY1 {} vs {want_ppy1}", got[1]);
    }
}
