//! The extended model file: the base `.tir` with refitted MF coefficients written into their
//! own sections, plus a `[TYRERIG_EXTENSIONS]` section for the terms MF-Tyre 6.1 lacks.
//!
//! ```text
//! [TYRERIG_EXTENSIONS]
//! $ Added by `tyrerig doctor` (docs/doctor.md). MF-Tyre 6.1 readers ignore this section.
//! FORMAT_VERSION            = 1
//! EFFECTS                   = 'thermal,wear'
//! THERMAL_TREF_C            = 52.3    $ x = (T_grip − TREF)/10 K
//! THERMAL_MU0 … THERMAL_MU2         $ λμx,y ×= 1 + MU0 + MU1·x + MU2·x²
//! THERMAL_K0, THERMAL_K1            $ λKx,y ×= 1 + K0 + K1·x
//! WEAR_K_PER_MJ, WEAR_C_PER_MJ      $ λK ×= 1 + K·E, λC ×= 1 + C·E, E = sliding energy [MJ]
//! WEAR_RL_MM_PER_MJ                 $ Rl −= RL·E mm
//! BREAKIN_DEFICIT, BREAKIN_LOG10_ENERGY_KJ, BREAKIN_THRESHOLD_KW
//!                                   $ λμ ×= 1 − D·exp(−E_sev/10^L kJ), E_sev above THRESHOLD
//! TRANSIENT_SIGMA_Y0_M, TRANSIENT_ALPHA_HALF_DEG (…_X0_M, …_KAPPA_HALF)
//!                                   $ dα'/ds = (α − α')/σ, σ = σ0/(1 + (α'/α½)²)
//! SPEED_VREF_MPS, SPEED_MU1, SPEED_K1  $ λμ ×= 1 + MU1·(V − VREF)/VREF, λK likewise
//! REFIT_PRESSURE            = 'PPY1,PPY3,…' $ refitted coefficients (already in their sections)
//! ```

use crate::DoctorError;
use crate::effects::{Effect, EffectParams};
use mftyre::{ExtraSection, ScalingFactors, TirValue, TyreParams};

/// Name of the extension section.
pub const SECTION: &str = "TYRERIG_EXTENSIONS";

/// Writes `effects` into a copy of `base`: refits into the MF sections, extension terms into
/// [`SECTION`].
pub fn extended_params(base: &TyreParams, effects: &[EffectParams], t_ref_c: f64, v_ref_mps: f64) -> TyreParams {
    let mut p = base.clone();
    let mut sec = ExtraSection::default();
    sec.lines
        .push("$ Added by `tyrerig doctor` (see docs/doctor.md). MF-Tyre 6.1 readers ignore this section;".to_owned());
    sec.lines.push("$ the terms need state inputs (grip temperature, sliding energy, travelled distance).".to_owned());
    sec.set("FORMAT_VERSION", TirValue::Number(1.0));
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
        match e.effect {
            Effect::Thermal => sec.set("THERMAL_TREF_C", TirValue::Number(t_ref_c)),
            Effect::Speed => sec.set("SPEED_VREF_MPS", TirValue::Number(v_ref_mps)),
            Effect::BreakIn => sec.set("BREAKIN_THRESHOLD_KW", TirValue::Number(e.threshold_w * 1e-3)),
            _ => {}
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
    /// Grip temperature [°C].
    pub temp_grip_c: f64,
    /// Sliding energy on the tyre so far [MJ].
    pub sliding_energy_mj: f64,
    /// Sliding energy above the break-in threshold so far [kJ].
    pub severe_energy_kj: f64,
    /// Belt speed [m/s].
    pub speed_mps: f64,
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
        let (mut mu, mut k, mut c, mut drl) = (1.0, 1.0, 1.0, 0.0);
        for e in &self.effects {
            match e {
                Effect::Thermal => {
                    let x = (st.temp_grip_c - self.get("THERMAL_TREF_C")) / 10.0;
                    mu *=
                        (1.0 + self.get("THERMAL_MU0") + self.get("THERMAL_MU1") * x + self.get("THERMAL_MU2") * x * x)
                            .max(0.2);
                    k *= (1.0 + self.get("THERMAL_K0") + self.get("THERMAL_K1") * x).max(0.2);
                }
                Effect::Wear => {
                    let x = st.sliding_energy_mj;
                    k *= (1.0 + self.get("WEAR_K_PER_MJ") * x).max(0.2);
                    c *= (1.0 + self.get("WEAR_C_PER_MJ") * x).max(0.2);
                    drl -= self.get("WEAR_RL_MM_PER_MJ") * x * 1e-3;
                }
                Effect::BreakIn => {
                    let e0 = 10f64.powf(self.get("BREAKIN_LOG10_ENERGY_KJ"));
                    mu *= (1.0 - self.get("BREAKIN_DEFICIT") * (-st.severe_energy_kj / e0).exp()).max(0.2);
                }
                Effect::Speed => {
                    let vr = self.get("SPEED_VREF_MPS").max(1.0);
                    let x = (st.speed_mps - vr) / vr;
                    mu *= (1.0 + self.get("SPEED_MU1") * x).max(0.2);
                    k *= (1.0 + self.get("SPEED_K1") * x).max(0.2);
                }
                _ => {}
            }
        }
        let mut s = *base;
        s.lmux *= mu;
        s.lmuy *= mu;
        s.lkx *= k;
        s.lky *= k;
        s.lcx *= c;
        s.lcy *= c;
        (s, drl)
    }
}
