//! `tyrerig export tydex` and `tyrerig import ttc|tydex`: the data formats people already have.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use mffit::tydex::Convention;

/// `tyrerig export …`
#[derive(Debug, Subcommand)]
pub enum ExportCmd {
    /// Write a log's sweep data as a TYDEX .tdx file (ISO-W, the thesis's channels)
    Tydex(ExportTydexArgs),
    /// Write a virtual rig run as a Calspan TIRF / TTC-style .dat with every quirk of real files
    Ttc(crate::cmd_export_ttc::ExportTtcArgs),
}

/// Arguments of `tyrerig export tydex`.
#[derive(Debug, Args)]
pub struct ExportTydexArgs {
    /// MCAP log
    pub log: PathBuf,
    /// Output file (default: the log's name with .tdx)
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `tyrerig import …`
#[derive(Debug, Subcommand)]
pub enum ImportCmd {
    /// Calspan TTC-style tab-separated data (SAE signs by default) → MCAP log
    Ttc(ImportTtcArgs),
    /// TYDEX .tdx → MCAP log
    Tydex(ImportTydexArgs),
}

/// Arguments of `tyrerig import ttc`.
#[derive(Debug, Args)]
pub struct ImportTtcArgs {
    /// TTC-style .dat file
    pub file: PathBuf,
    /// Output MCAP log (default: the file's name with .mcap)
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The file is already in ISO-W signs (default: SAE, converted)
    #[arg(long)]
    pub iso: bool,
    /// Nominal load Fz0 to record in the log [N]
    #[arg(long)]
    pub fnomin: Option<f64>,
}

/// Arguments of `tyrerig import tydex`.
#[derive(Debug, Args)]
pub struct ImportTydexArgs {
    /// TYDEX .tdx file
    pub file: PathBuf,
    /// Output MCAP log (default: the file's name with .mcap)
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `tyrerig export …`.
pub fn run_export(cmd: ExportCmd) -> Result<()> {
    match cmd {
        ExportCmd::Tydex(a) => {
            let data = mffit::logs::read_log(&a.log)?;
            let out = a.out.unwrap_or_else(|| a.log.with_extension("tdx"));
            mffit::tydex::write_tydex(&out, &data).with_context(|| format!("writing {}", out.display()))?;
            eprintln!("wrote {} ({} segments, {} samples)", out.display(), data.segments.len(), data.len());
            Ok(())
        }
        ExportCmd::Ttc(a) => crate::cmd_export_ttc::run(a),
    }
}

/// Runs `tyrerig import …`.
pub fn run_import(cmd: ImportCmd) -> Result<()> {
    let (data, out) = match cmd {
        ImportCmd::Ttc(a) => {
            let conv = if a.iso { Convention::IsoW } else { Convention::Sae };
            let mut d = mffit::tydex::read_ttc(&a.file, conv)?;
            d.fnomin_n = a.fnomin.or(d.fnomin_n);
            (d, a.out.unwrap_or_else(|| a.file.with_extension("mcap")))
        }
        ImportCmd::Tydex(a) => {
            (mffit::tydex::read_tydex(&a.file)?, a.out.unwrap_or_else(|| a.file.with_extension("mcap")))
        }
    };
    mffit::logs::write_log(&out, &data).with_context(|| format!("writing {}", out.display()))?;
    eprintln!("wrote {} ({} segments, {} samples)", out.display(), data.segments.len(), data.len());
    Ok(())
}
