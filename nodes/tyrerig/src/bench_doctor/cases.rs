//! The benchmark's cases: tyres × plans × effect sets × seeds.

use hidden::EffectKind;
use std::path::{Path, PathBuf};

/// A virtual tyre and the rig config it runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tyre {
    /// The MF-Tyre 6.1 tyre (`virtual_rig.toml`), diagnosed with `--model` (its own .tir).
    Mf,
    /// The brush road tyre, diagnosed with `--fit` (MF cannot represent it exactly).
    BrushRoad,
    /// The brush race tyre, likewise.
    BrushRace,
}

impl Tyre {
    pub const ALL: [Tyre; 3] = [Tyre::Mf, Tyre::BrushRoad, Tyre::BrushRace];

    pub fn name(self) -> &'static str {
        match self {
            Tyre::Mf => "mf",
            Tyre::BrushRoad => "brush_road",
            Tyre::BrushRace => "brush_race",
        }
    }

    /// Its rig config under `launch-config/`.
    pub fn rig_config(self, launch: &Path) -> PathBuf {
        launch.join(match self {
            Tyre::Mf => "virtual_rig.toml",
            Tyre::BrushRoad => "virtual_rig_brush_road.toml",
            Tyre::BrushRace => "virtual_rig_brush_race.toml",
        })
    }
}

/// A test plan: one procedure, or the TTC pair of runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plan {
    /// GS2MF's free-rolling part (the full GS2MF takes the doctor minutes per case).
    Gs2mfFreeRolling,
    /// TTC-style cornering + drive/brake runs, through the TTC export (`.dat` files).
    Ttc,
    /// The Square Matrix.
    SquareMatrix,
}

impl Plan {
    pub const ALL: [Plan; 3] = [Plan::Gs2mfFreeRolling, Plan::Ttc, Plan::SquareMatrix];

    pub fn name(self) -> &'static str {
        match self {
            Plan::Gs2mfFreeRolling => "gs2mf_fr",
            Plan::Ttc => "ttc",
            Plan::SquareMatrix => "square_matrix",
        }
    }

    /// The procedure files of its runs, under `launch-config/procedures/` (the race tyre runs
    /// the race TTC procedures, its drive/brake run opened by warm-up sweeps as the real race
    /// tyre's is; the other two the road ones, without).
    pub fn procedures(self, tyre: Tyre) -> Vec<&'static str> {
        match (self, tyre) {
            (Plan::Gs2mfFreeRolling, _) => vec!["gs2mf_freerolling.toml"],
            (Plan::SquareMatrix, _) => vec!["square_matrix.toml"],
            (Plan::Ttc, Tyre::BrushRace) => vec!["ttc_cornering_race.toml", "ttc_drive_brake_race_warmup.toml"],
            (Plan::Ttc, _) => vec!["ttc_cornering_road.toml", "ttc_drive_brake_road.toml"],
        }
    }

    /// The doctor reads the TTC export of the logs, not the logs.
    pub fn through_ttc(self) -> bool {
        self == Plan::Ttc
    }
}

/// One case.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    pub tyre: Tyre,
    pub plan: Plan,
    /// Kinds injected (none: a clean case).
    pub effects: Vec<EffectKind>,
    /// Seed of the effects' forms (and of the strength).
    pub seed: u64,
}

impl Case {
    /// `tyre/plan/effects/s<seed>`.
    pub fn id(&self) -> String {
        format!("{}/{}/{}/s{}", self.tyre.name(), self.plan.name(), self.effects_name(), self.seed)
    }

    /// `clean`, `thermal`, `thermal+wear`, ….
    pub fn effects_name(&self) -> String {
        if self.effects.is_empty() {
            "clean".into()
        } else {
            self.effects.iter().map(|k| k.name()).collect::<Vec<_>>().join("+")
        }
    }

    /// The strength every effect of the case is drawn at: cycles through 1, 2, 0.6, 1.5 with the
    /// seed, so some cases fall below 3 noise σ (recall is not counted on those) and most do not.
    pub fn strength(&self) -> f64 {
        [1.0, 2.0, 0.6, 1.5][(self.seed.saturating_sub(1) % 4) as usize]
    }

    /// A directory name for it.
    pub fn dir_name(&self) -> String {
        self.id().replace('/', "_")
    }
}

/// The effect sets: clean, each single effect, and two pairs.
fn effect_sets() -> Vec<Vec<EffectKind>> {
    use EffectKind::{BreakIn, Thermal, Wear};
    vec![vec![], vec![Thermal], vec![Wear], vec![BreakIn], vec![Thermal, Wear], vec![Wear, BreakIn]]
}

/// Every case: per tyre and plan one clean case (its log is the same whatever the seed), each
/// single effect with `seeds` seeds and each pair with half as many (at least one).
pub fn all_cases(seeds: u64) -> Vec<Case> {
    let mut out = Vec::new();
    for tyre in Tyre::ALL {
        for plan in Plan::ALL {
            for set in effect_sets() {
                let n = match set.len() {
                    0 => 1,
                    1 => seeds.max(1),
                    _ => seeds.div_ceil(2).max(1),
                };
                for seed in 1..=n {
                    out.push(Case { tyre, plan, effects: set.clone(), seed });
                }
            }
        }
    }
    out
}

/// Eight cases spanning the tyres, plans and effect sets.
pub fn quick_cases() -> Vec<Case> {
    use EffectKind::{BreakIn, Thermal, Wear};
    let c = |tyre, plan, effects: &[EffectKind]| Case { tyre, plan, effects: effects.to_vec(), seed: 1 };
    vec![
        c(Tyre::Mf, Plan::Gs2mfFreeRolling, &[]),
        c(Tyre::Mf, Plan::Gs2mfFreeRolling, &[Thermal]),
        c(Tyre::Mf, Plan::Ttc, &[Wear]),
        c(Tyre::Mf, Plan::SquareMatrix, &[Thermal]),
        c(Tyre::BrushRoad, Plan::Gs2mfFreeRolling, &[BreakIn]),
        c(Tyre::BrushRoad, Plan::Ttc, &[Thermal, Wear]),
        c(Tyre::BrushRace, Plan::Ttc, &[]),
        c(Tyre::BrushRace, Plan::Gs2mfFreeRolling, &[Wear, BreakIn]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_full_set_has_at_least_60_cases_and_quick_spans_every_tyre_and_plan() {
        let all = all_cases(2);
        assert_eq!(all.len(), 9 * (1 + 3 * 2 + 2));
        assert!(all.len() >= 60);
        let ids: std::collections::BTreeSet<String> = all.iter().map(Case::id).collect();
        assert_eq!(ids.len(), all.len(), "ids are unique");
        let quick = quick_cases();
        for t in Tyre::ALL {
            assert!(quick.iter().any(|c| c.tyre == t), "{t:?}");
        }
        for p in Plan::ALL {
            assert!(quick.iter().any(|c| c.plan == p), "{p:?}");
        }
        assert!(quick.iter().all(|c| ids.contains(&c.id())), "quick cases are cases of the full set");
    }
}
