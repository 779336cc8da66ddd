//! The extended model file: the base `.tir` with refitted MF coefficients written into their
//! own sections, plus a `[TYRERIG_EXTENSIONS]` section for the terms MF-Tyre 6.1 lacks.
//!
//! ```text
//! [TYRERIG_EXTENSIONS]
//! $ Added by `tyrerig doctor` (docs/doctor.md). MF-Tyre 6.1 readers ignore this section.
//! FORMAT_VERSION            = 5
//! EFFECTS                   = 'thermal,wear'
//! THERMAL_SOURCE            = 0       $ 0: grip temperature (quiet, flash fitted out); 1: laser mean
//! THERMAL_LAG_S             = 30      $ its first-order lag
//! THERMAL_SURFACE_WEIGHT    = 0.3     $ T = w·T_read + (1 − w)·T_lagged (0: lagged alone)
//! THERMAL_TREF_C            = 52.3    $ x = (T_lagged − TREF)/10 K
//! THERMAL_TMIN_C, THERMAL_TMAX_C    $ T_lagged clamped to this range (2 %/98 % of the data)
//! THERMAL_NEUTRAL_1, _2             $ N1, N2: x and x² measured from them (0 for a given model)
//! THERMAL_MUY_0, _1, _2 …           $ λμy ×= exp(c0 + c1·(x − N1) + c2·(x² − N2)); likewise MUX, KX, KY (c0, c1),
//!                                   $ TRAIL, MRES, RL_MM (Rl += c0 + c1·x mm); no c0 for a base
//!                                   $ fitted to the same logs
//! THERMAL_FORCE_0, _1, _2           $ the force-level form instead: λμx, λμy, λKx, λKy ×= one factor
//! WEAR_MUY, WEAR_KY, WEAR_CY, …     $ λ ×= exp(c·(E − N1) + c2·(E² − N2)), E = sliding energy [MJ];
//! WEAR_MUY_S1, WEAR_MUX_S1          $ c2 on grip only; WEAR_RL_MM: Rl += c·(E − N1) mm;
//! WEAR_NEUTRAL_MJ, WEAR_NEUTRAL_MJ2 $ N1, N2: 0 for a given model, the mean over the points for a
//!                                   $ base fitted to the same logs
//! BREAKIN_ENERGY_KJ, BREAKIN_THRESHOLD_KW, BREAKIN_MUY, BREAKIN_MUY_S1, …
//!                                   $ λ ×= exp(c·(r − N1) + c2·(r₁₀ − N2)), r = exp(−E_sev/E₀),
//!                                   $ r₁₀ = exp(−E_sev/10E₀) (slow stage: grip and stiffness),
//!                                   $ E_sev above the threshold; BREAKIN_NEUTRAL(_SLOW): N1, N2
//! SPEED_VREF_MPS, SPEED_MUY, …      $ λ ×= exp(c·(V − VREF)/VREF)
//! SPECIMEN_MUY_T1, …                $ λ ×= exp(c) on the test's tyre 1 (2, …)
//! TRANSIENT_SIGMA_Y0_M, TRANSIENT_ALPHA_HALF_DEG (…_X0_M, …_KAPPA_HALF)
//!                                   $ dα'/ds = (α − α')/σ, σ = σ0/(1 + (α'/α½)²)
//! REFIT_PRESSURE            = 'PPY1,PPY3,…' $ refitted coefficients (already in their sections)
//! REFIT_REBASE              = 'PDX1,…'      $ the base refitted beside a state effect scored
//!                                   $ against the form error (docs/doctor.md)
//! ```

use crate::DoctorError;
use crate::effects::{Effect, EffectParams};
use crate::state;
use mftyre::{ExtraSection, ScalingFactors, TirValue, TyreParams};

/// Name of the extension section.
pub const SECTION: &str = "TYRERIG_EXTENSIONS";

/// Writes `effects` into a copy of `base`: refits into the MF sections, extension terms into
/// [`SECTION`].
pub fn extended_params(base: &TyreParams, effects: &[EffectParams], refs: &state::References) -> TyreParams {
    let mut p = base.clone();
    let mut sec = ExtraSection::default();
    sec.lines
        .push("$ Added by `tyrerig doctor` (see docs/doctor.md). MF-Tyre 6.1 readers ignore this section;".to_owned());
    sec.lines.push("$ the terms need state inputs (grip temperature, sliding energy, travelled distance).".to_owned());
    sec.set("FORMAT_VERSION", TirValue::Number(5.0));
    let names: Vec<&str> = effects.iter().map(|e| e.effect.name()).collect();
    sec.set("EFFECTS", TirValue::Text(names.join(",")));
    for e in effects {
        if e.effect.is_refit() {
            for (k, v) in e.keys.iter().zip(&e.values) {
                let _ = p.set(k, *v);
            }
            sec.set(&format!("REFIT_{}", e.effect.name().to_ascii_uppercase()), TirValue::Text(e.keys.join(",")));
            continue;
        }
        if e.effect == Effect::Speed {
            sec.set("SPEED_VREF_MPS", TirValue::Number(refs.v_ref_mps));
        }
        for (k, v) in e.keys.iter().zip(&e.values) {
            sec.set(k, TirValue::Number(*v));
        }
    }
    p.extra_sections.insert(SECTION.to_owned(), sec);
    p
}

/// The state an extended model needs beyond MF-Tyre 6.1's inputs.
#[derive(Debug, Clone, Copy, Default)]
pub struct ExtState {
    /// The temperature `THERMAL_SOURCE` names (0: grip temperature, 1: the tread lasers' mean):
    /// `THERMAL_SURFACE_WEIGHT` of it as read plus the rest through the first-order lag
    /// `THERMAL_LAG_S` [°C].
    pub temp_grip_c: f64,
    /// Sliding energy on the tyre so far [MJ].
    pub sliding_energy_mj: f64,
    /// Sliding energy above `BREAKIN_THRESHOLD_KW` so far [kJ].
    pub severe_energy_kj: f64,
    /// Belt speed [m/s].
    pub speed_mps: f64,
    /// Ordinal of the tyre in the test the model was diagnosed on (0: the first).
    pub tyre: usize,
}

/// The extension terms of an extended `.tir`, ready to apply.
#[derive(Debug, Clone, Default)]
pub struct Extensions {
    /// Effects listed, in order.
    pub effects: Vec<Effect>,
    values: Vec<(String, f64)>,
}

impl Extensions {
    /// Reads [`SECTION`] of `params` (empty when absent).
    pub fn from_params(params: &TyreParams) -> Result<Self, DoctorError> {
        let Some(sec) = params.extra_sections.get(SECTION) else { return Ok(Self::default()) };
        let mut out = Self::default();
        for (k, v) in sec.entries() {
            match v {
                TirValue::Number(x) => out.values.push((k.to_ascii_uppercase(), x)),
                TirValue::Text(t) if k.eq_ignore_ascii_case("EFFECTS") => {
                    for name in t.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                        out.effects.push(Effect::parse(name).ok_or_else(|| DoctorError::Model {
                            file: params.source.clone(),
                            detail: format!("[{SECTION}] EFFECTS: unknown effect {name:?}"),
                        })?);
                    }
                }
                TirValue::Text(_) => {}
            }
        }
        Ok(out)
    }

    /// A value by key (0 when absent).
    pub fn get(&self, key: &str) -> f64 {
        self.values.iter().find(|(k, _)| k.eq_ignore_ascii_case(key)).map_or(0.0, |(_, v)| *v)
    }

    /// The scaling factors at `state` (the transient terms act on the slips instead, see
    /// [`crate::effects::Evaluator::relaxed`]) and the loaded-radius change [m].
    pub fn scaling(&self, base: &ScalingFactors, st: &ExtState) -> (ScalingFactors, f64) {
        let refs =
            state::References { t_ref_c: self.get("THERMAL_TREF_C"), v_ref_mps: self.get("SPEED_VREF_MPS").max(1.0) };
        let at = state::StateAt {
            temp_c: st.temp_grip_c,
            energy_mj: st.sliding_energy_mj,
            severe_kj: st.severe_energy_kj,
            speed_mps: st.speed_mps,
            tyre: st.tyre,
        };
        let mut log_f = [0.0; 8];
        let mut drl_m = 0.0;
        for &e in self.effects.iter().filter(|e| state::is_state_scaling(**e)) {
            let parsed = state::Parsed::from_entries(e, self.values.iter().map(|(k, v)| (k.as_str(), *v)));
            parsed.accumulate(&at, &refs, &mut log_f, &mut drl_m);
        }
        let mut s = *base;
        state::apply(&mut s, &log_f);
        (s, drl_m)
    }
}
