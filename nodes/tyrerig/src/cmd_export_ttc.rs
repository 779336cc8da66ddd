//! `tyrerig export ttc`: a virtual rig run as a Calspan TIRF / FSAE TTC run file, with every
//! quirk real files have (`rigdata::virtual_export`, `docs/ttc-export.md`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use clap::ValueEnum;
use rigdata::virtual_export::{
    ForceUnit, PressureUnit, TtcExportOptions, UnitSpelling, VirtualRun, export_ttc, to_dat_compact,
};

/// Spelling of the units line (`--units`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum UnitsArg {
    /// s, kph, rpm, deg, cm, kPa, N, N-m, none, degC (AMBTMP °F under a degC label)
    Ttc,
    /// A later round: sec, Nm, deg C, AMBTMP in deg F, SL in SAE
    LaterRound,
    /// US units: mph, in, psi, lbf, degF
    Us,
}

/// Arguments of `tyrerig export ttc`.
#[derive(Debug, Args)]
pub struct ExportTtcArgs {
    /// MCAP log of a virtual rig run (`tyrerig run --headless …`)
    pub log: PathBuf,
    /// Output .dat file (default: the log's name with .dat)
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Output rate: 50 (older TTC rounds) or 100 Hz
    #[arg(long, default_value_t = 50)]
    pub rate_hz: u32,
    /// Pressure in psi instead of kPa
    #[arg(long)]
    pub psi: bool,
    /// Forces in lbf instead of N
    #[arg(long)]
    pub lbf: bool,
    /// Units line as a test round spells it
    #[arg(long, value_enum, default_value_t = UnitsArg::Ttc)]
    pub units: UnitsArg,
    /// Leave out the testid (as some files do)
    #[arg(long)]
    pub no_testid: bool,
    /// Leave out the NFX channel (as some files do)
    #[arg(long)]
    pub no_nfx: bool,
    /// Leave out the SL channel (as some files do: then only the rig's SR is left)
    #[arg(long)]
    pub no_sl: bool,
    /// Run number in the title line
    #[arg(long, default_value_t = 4)]
    pub run: u32,
    /// Tyre specimen number in the tireid (`-- Tire N`)
    #[arg(long, default_value_t = 1)]
    pub tire_number: u32,
    /// testid (default: the procedure's title)
    #[arg(long)]
    pub test_id: Option<String>,
    /// Seed of the exporter's sensor noise (wheel-speed encoder, ambient and road temperature)
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Runs `tyrerig export ttc`.
pub fn run(a: ExportTtcArgs) -> Result<()> {
    let run = VirtualRun::from_log(&a.log)?;
    let opts = TtcExportOptions {
        units: match a.units {
            UnitsArg::Ttc => UnitSpelling::Ttc,
            UnitsArg::LaterRound => UnitSpelling::LaterRound,
            UnitsArg::Us => UnitSpelling::Us,
        },
        rate_hz: a.rate_hz,
        pressure_unit: if a.psi { PressureUnit::Psi } else { PressureUnit::Kpa },
        force_unit: if a.lbf { ForceUnit::Lbf } else { ForceUnit::N },
        with_test_id: !a.no_testid,
        with_nfx: !a.no_nfx,
        with_sl: !a.no_sl,
        run: a.run,
        tire_number: a.tire_number,
        test_id: a.test_id.clone(),
        seed: a.seed,
        ..TtcExportOptions::default()
    };
    let table = export_ttc(&run, &opts)?;
    // The .dat layout carries the title (with Tire_Name) but no tireid/testid strings; a .mat
    // writer would take `table` as it is (tire_id, test_id included).
    let out = a.out.unwrap_or_else(|| a.log.with_extension("dat"));
    std::fs::write(&out, to_dat_compact(&table)).with_context(|| format!("writing {}", out.display()))?;
    eprintln!(
        "wrote {} ({} rows at {} Hz, {} channels; tireid {:?}, testid {:?})",
        out.display(),
        table.rows(),
        opts.rate_hz,
        table.columns.len(),
        table.tire_id.as_deref().unwrap_or(""),
        table.test_id.as_deref().unwrap_or("")
    );
    Ok(())
}
