//! What to run: procedure, tyre, rig config, effects, seed and run inputs.

use procedure::{RunInputs, SweepStyle};
use std::path::{Path, PathBuf};

/// The procedures `tyrerig run` knows by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProcedureChoice {
    Gs2mf,
    FreeRolling,
    BrkDrv,
    StaticLong,
    SquareMatrix,
}

impl ProcedureChoice {
    pub const ALL: [ProcedureChoice; 5] = [
        ProcedureChoice::Gs2mf,
        ProcedureChoice::FreeRolling,
        ProcedureChoice::BrkDrv,
        ProcedureChoice::StaticLong,
        ProcedureChoice::SquareMatrix,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ProcedureChoice::Gs2mf => "gs2mf",
            ProcedureChoice::FreeRolling => "freerolling",
            ProcedureChoice::BrkDrv => "brkdrv",
            ProcedureChoice::StaticLong => "staticlong",
            ProcedureChoice::SquareMatrix => "square-matrix",
        }
    }

    /// The procedure file under `launch-config/procedures/`.
    pub fn file_name(self) -> &'static str {
        match self {
            ProcedureChoice::Gs2mf => "gs2mf.toml",
            ProcedureChoice::FreeRolling => "gs2mf_freerolling.toml",
            ProcedureChoice::BrkDrv => "gs2mf_brkdrv.toml",
            ProcedureChoice::StaticLong => "gs2mf_staticlong.toml",
            ProcedureChoice::SquareMatrix => "square_matrix.toml",
        }
    }

    pub fn parse(s: &str) -> Result<Self, String> {
        Self::ALL.into_iter().find(|p| p.name() == s).ok_or_else(|| {
            format!("unknown procedure {s:?}: expected one of {}", Self::ALL.map(|p| p.name()).join(", "))
        })
    }
}

/// A complete description of a run.
#[derive(Debug, Clone)]
pub struct RunSpec {
    /// The procedure file.
    pub procedure_file: PathBuf,
    /// The virtual rig's config (`launch-config/virtual_rig.toml`).
    pub rig_config: PathBuf,
    /// A tyre file replacing the rig config's.
    pub tyre: Option<PathBuf>,
    /// Effects replacing the rig config's (`none`, `all` or a comma list).
    pub effects: Option<String>,
    /// Wear-rate multiplier on top of the rig config's (tests of the wear alarm use 5).
    pub wear_multiplier: Option<f64>,
    /// Noise seed.
    pub seed: u64,
    /// Load index, pressures, speed, sweep style, rig limits.
    pub inputs: RunInputs,
    /// For a brush tyre, take the nominal load (or its load index) and the three test
    /// pressures from its parameter file instead of `inputs` (a race tyre has no ETRTO index).
    /// Off when the operator gives the load index or pressures explicitly.
    pub use_tyre_ratings: bool,
    /// Stop after this much rig time even if the procedure is not complete (a safety net).
    pub max_rig_time_s: f64,
}

impl RunSpec {
    /// The default run of `choice` with the files under `launch_config`.
    pub fn new(launch_config: &Path, choice: ProcedureChoice) -> Self {
        Self {
            procedure_file: launch_config.join("procedures").join(choice.file_name()),
            rig_config: launch_config.join("virtual_rig.toml"),
            tyre: None,
            effects: None,
            wear_multiplier: None,
            seed: 1,
            inputs: RunInputs { sweeps: SweepStyle::Variable, ..RunInputs::default() },
            use_tyre_ratings: true,
            max_rig_time_s: 200_000.0,
        }
    }
}
