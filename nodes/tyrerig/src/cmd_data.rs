//! `tyrerig import ttc|tydex`, `tyrerig inspect` and `tyrerig export tydex|mat`: measured files
//! as rigs write them (Calspan TTC `.dat`/`.mat`, TYDEX `.tdx`, folders of them) in and out,
//! through the `rigdata` readers (see `docs/real-data.md`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand, ValueEnum};
use rigdata::import::{FileFormat, ReadOptions, files_of, read_path};
use rigdata::mat::{MatLayout, MatWriteOptions};
use rigdata::{Convention, Import};

/// `tyrerig export …`
#[derive(Debug, Subcommand)]
pub enum ExportCmd {
    /// Write a log's sweep data as a TYDEX .tdx file (ISO-W, the thesis's channels)
    Tydex(ExportTydexArgs),
    /// Write a measured file's channels (.dat, .mat, .tdx) as a MATLAB .mat file (TTC layout)
    Mat(ExportMatArgs),
    /// Write a virtual rig run as a Calspan TIRF / TTC-style .dat with every quirk of real files
    Ttc(crate::cmd_export_ttc::ExportTtcArgs),
    /// Write one small synthetic TTC-style file per quirk of other test rounds (unit spellings,
    /// US units, no SL, wandering load, camber sweeps, slip ratio to 0.65, warm-up sweeps)
    QuirkFixtures(ExportQuirksArgs),
}

/// Arguments of `tyrerig export quirk-fixtures`.
#[derive(Debug, Args)]
pub struct ExportQuirksArgs {
    /// Output folder (created if missing)
    pub dir: PathBuf,
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

/// Arguments of `tyrerig export mat`.
#[derive(Debug, Args)]
pub struct ExportMatArgs {
    /// Measured file (.dat, .mat, .tdx)
    pub file: PathBuf,
    /// Output .mat file
    #[arg(long)]
    pub out: PathBuf,
    /// Do not compress (MATLAB `-v6`); default compresses as `-v7` does
    #[arg(long)]
    pub uncompressed: bool,
    /// Put the channels in one struct variable of this name instead of one variable each
    #[arg(long)]
    pub r#struct: Option<String>,
    /// Big-endian byte order
    #[arg(long)]
    pub big_endian: bool,
}

/// Sign convention choice on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ConventionArg {
    /// From the data: FZ negative under load is SAE
    Auto,
    /// SAE (Calspan TTC)
    Sae,
    /// ISO-W (TYDEX-W)
    Iso,
}

impl From<ConventionArg> for Convention {
    fn from(c: ConventionArg) -> Self {
        match c {
            ConventionArg::Auto => Convention::Auto,
            ConventionArg::Sae => Convention::Sae,
            ConventionArg::Iso => Convention::IsoW,
        }
    }
}

/// How a measured file is read (shared by import and inspect).
#[derive(Debug, Args)]
pub struct ReadArgs {
    /// Sign convention of the file
    #[arg(long, value_enum, default_value_t = ConventionArg::Auto)]
    pub convention: ConventionArg,
    /// Print machine-readable JSON instead of text
    #[arg(long)]
    pub json: bool,
    /// List every sweep, not only the sweeps per cell
    #[arg(long, short)]
    pub verbose: bool,
}

impl ReadArgs {
    fn options(&self) -> ReadOptions {
        ReadOptions { convention: self.convention.into(), ..ReadOptions::default() }
    }
}

/// `tyrerig import …`
#[derive(Debug, Subcommand)]
pub enum ImportCmd {
    /// Calspan TIRF / TTC run files (.dat, .mat, or a folder of them) → MCAP log
    Ttc(ImportArgs),
    /// TYDEX .tdx files (one file, or a folder: one file per measurement) → MCAP log
    Tydex(ImportArgs),
}

/// Arguments of `tyrerig import ttc|tydex`.
#[derive(Debug, Args)]
pub struct ImportArgs {
    /// File or folder
    pub path: PathBuf,
    /// Output MCAP log (default: the file's or folder's name with .mcap)
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Nominal load Fz0 to record in the log [N]
    #[arg(long)]
    pub fnomin: Option<f64>,
    /// Print what was found and write nothing
    #[arg(long)]
    pub dry_run: bool,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// Arguments of `tyrerig inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// File (.dat, .mat, .tdx) or folder
    pub path: PathBuf,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// Runs `tyrerig export …`.
pub fn run_export(cmd: ExportCmd) -> Result<()> {
    match cmd {
        ExportCmd::Tydex(a) => {
            let data = mffit::logs::read_log(&a.log)?;
            let out = a.out.unwrap_or_else(|| a.log.with_extension("tdx"));
            rigdata::tydex::write_tydex(&out, &data).with_context(|| format!("writing {}", out.display()))?;
            eprintln!("wrote {} ({} segments, {} samples)", out.display(), data.segments.len(), data.len());
            Ok(())
        }
        ExportCmd::Mat(a) => {
            let table = read_table(&a.file)?;
            let opt = MatWriteOptions {
                compress: !a.uncompressed,
                big_endian: a.big_endian,
                layout: a.r#struct.map(MatLayout::Struct).unwrap_or_default(),
                ..MatWriteOptions::default()
            };
            rigdata::mat::write_mat(&a.out, &table, &opt)?;
            eprintln!("wrote {} ({} channels, {} rows)", a.out.display(), table.columns.len(), table.rows());
            Ok(())
        }
        ExportCmd::Ttc(a) => crate::cmd_export_ttc::run(a),
        ExportCmd::QuirkFixtures(a) => export_quirks(&a.dir),
    }
}

/// Writes `rigdata::fixture::quirk_fixtures()` into `dir`, `.dat` or `.mat` by name.
fn export_quirks(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for q in rigdata::fixture::quirk_fixtures() {
        let run = rigdata::fixture::ttc_run(&q.spec);
        let out = dir.join(q.file);
        if q.file.ends_with(".mat") {
            rigdata::mat::write_mat(&out, &run.table, &MatWriteOptions { units: q.mat_units, ..Default::default() })?;
        } else {
            std::fs::write(&out, rigdata::virtual_export::to_dat_compact(&run.table))
                .with_context(|| format!("writing {}", out.display()))?;
        }
        eprintln!(
            "wrote {} ({} rows, {} sweeps planned): {}",
            out.display(),
            run.table.rows(),
            run.sweeps.len(),
            q.quirk
        );
    }
    Ok(())
}

/// A measured file's raw table (any format).
fn read_table(path: &Path) -> Result<rigdata::ChannelTable> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let file = path.display().to_string();
    Ok(match FileFormat::of(path).unwrap_or_else(|| FileFormat::sniff(&bytes)) {
        FileFormat::Dat => rigdata::dat::parse_dat(&bytes, &file)?.table,
        FileFormat::Mat => rigdata::mat::parse_mat(&bytes, &file)?.table,
        FileFormat::Tdx => {
            let tdx = rigdata::tydex::parse_tdx(&String::from_utf8_lossy(&bytes), &file)?;
            tdx.to_table(&file).0
        }
    })
}

fn print_inspection(import: &Import, read: &ReadArgs) -> Result<()> {
    if read.json {
        println!("{}", serde_json::to_string_pretty(&import.inspection)?);
    } else {
        print!("{}", import.inspection.to_text(read.verbose));
    }
    Ok(())
}

/// Runs `tyrerig import …`.
pub fn run_import(cmd: ImportCmd) -> Result<()> {
    let (a, ttc) = match cmd {
        ImportCmd::Ttc(a) => (a, true),
        ImportCmd::Tydex(a) => (a, false),
    };
    for f in files_of(&a.path)? {
        let is_tdx = FileFormat::of(&f) == Some(FileFormat::Tdx);
        if ttc == is_tdx {
            bail!(
                "{}: {} file; use `tyrerig import {}`",
                f.display(),
                if is_tdx { "a TYDEX" } else { "not a TYDEX" },
                if is_tdx { "tydex" } else { "ttc" }
            );
        }
    }
    let mut import = read_path(&a.path, &a.read.options())?;
    import.dataset.fnomin_n = a.fnomin.or(import.dataset.fnomin_n);
    if a.dry_run {
        return print_inspection(&import, &a.read);
    }
    if a.read.json {
        print_inspection(&import, &a.read)?;
    } else {
        eprint!("{}", import.inspection.to_text(a.read.verbose));
    }
    if import.dataset.segments.is_empty() {
        bail!("{}: no sweep found: nothing to import", a.path.display());
    }
    let out = a.out.unwrap_or_else(|| default_out(&a.path));
    mffit::logs::write_log(&out, &import.dataset).with_context(|| format!("writing {}", out.display()))?;
    eprintln!("wrote {} ({} segments, {} samples)", out.display(), import.dataset.segments.len(), import.dataset.len());
    Ok(())
}

/// `run.dat` → `run.mcap`; a folder `runs/` → `runs.mcap` beside it.
fn default_out(path: &Path) -> PathBuf {
    if path.is_dir() {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "import".into());
        path.with_file_name(format!("{name}.mcap"))
    } else {
        path.with_extension("mcap")
    }
}

/// Runs `tyrerig inspect`.
pub fn run_inspect(a: InspectArgs) -> Result<()> {
    let import = read_path(&a.path, &a.read.options())?;
    print_inspection(&import, &a.read)
}
