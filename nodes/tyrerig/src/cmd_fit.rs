//! `tyrerig fit`: staged MF-Tyre 6.1 fit of GS2MF logs (see `docs/fitting.md`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use mffit::stages::crossval::REPEAT_BAND_LEVEL;
use mffit::stages::{FitOptions, fit};
use mftyre::TyreParams;

/// Arguments of `tyrerig fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Data to fit: MCAP logs of the FreeRolling, BrkDrv and StaticLong procedures, or measured
    /// files (TTC `.dat`/`.mat`, TYDEX `.tdx`) and folders of them
    #[arg(required = true)]
    pub logs: Vec<PathBuf>,
    /// The fitted tyre property file (FITTYP 61)
    #[arg(long)]
    pub out: PathBuf,
    /// Directory for the report (report.md, fit.json, PNG/SVG plots)
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Nominal load Fz0 [N] (default: the log's metadata, else the median sweep load)
    #[arg(long)]
    pub fnomin: Option<f64>,
    /// Template .tir for the coefficients no stage fits (inertia, contact patch, …)
    #[arg(long)]
    pub template: Option<PathBuf>,
    /// Also fit the graph sweeps (drift/wear checks; excluded by default as in the thesis)
    #[arg(long)]
    pub include_graph_sweeps: bool,
    /// Robust (soft-L1) loss with this threshold in % of each channel's peak
    #[arg(long)]
    pub robust: Option<f64>,
    /// Largest number of 10 Hz points per stage (evenly decimated beyond)
    #[arg(long, default_value_t = 3000)]
    pub max_points: usize,
    /// Worker threads (default: all cores)
    #[arg(long)]
    pub threads: Option<usize>,
    /// Reference tyre (e.g. the virtual rig's): adds a held-out accuracy table to the report
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Another run to validate the fitted model on (e.g. a repeat run on a second tyre); repeatable
    #[arg(long)]
    pub validate: Vec<PathBuf>,
    /// Folds of the k-fold cross-validation over sweeps (0: none)
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// Stage not to run (its coefficients keep the template's values); repeatable
    #[arg(long = "skip-stage", value_name = "STAGE")]
    pub skip_stages: Vec<String>,
    /// Exit with success even when the model is non-physical (the .tir is written either way)
    #[arg(long)]
    pub allow_nonphysical: bool,
}

/// Exit code of `tyrerig fit` when the model was written but is non-physical.
pub const EXIT_NONPHYSICAL: i32 = 3;

/// What one path given to `tyrerig fit` holds.
struct DataRead {
    dataset: mffit::Dataset,
    /// What a log is missing (logs say what they lost).
    warnings: Vec<String>,
    /// The tyre each measured file names: (file, tyre).
    tyres: Vec<(String, String)>,
}

/// A data file or folder, read.
fn read_any(path: &Path) -> Result<DataRead> {
    let measured = path.is_dir() || rigdata::import::FileFormat::of(path).is_some();
    if !measured {
        let (dataset, warnings) = mffit::logs::read_log_with_warnings(path)?;
        return Ok(DataRead { dataset, warnings, tyres: Vec::new() });
    }
    let import = rigdata::read_path(path, &rigdata::ReadOptions::default())?;
    let tyres = import.inspection.files.iter().filter_map(|f| Some((f.file.clone(), f.tire_id.clone()?))).collect();
    for f in &import.inspection.files {
        let conditioning = f.conditioning_sweeps;
        eprintln!(
            "{}: {} sweeps ({} conditioning, not fitted), {} rows excluded, {} warnings (`tyrerig inspect` lists them)",
            f.file,
            f.sweeps.len() - conditioning,
            conditioning,
            f.excluded.iter().map(|e| e.1).sum::<usize>(),
            f.warnings.len()
        );
    }
    Ok(DataRead { dataset: import.dataset, warnings: Vec::new(), tyres })
}

/// A warning when the measured files name more than one tyre: a TTC cornering run and its
/// drive/brake run are often on two specimens of one tyre model (`Tire 19`, `Tire 21`), which
/// can differ by 10–14 % in peak FX; the fit takes them as one tyre.
fn specimen_warning(tyres: &[(String, String)]) -> Option<String> {
    let mut names: Vec<&str> = tyres.iter().map(|(_, t)| t.as_str()).collect();
    names.sort_unstable();
    names.dedup();
    (names.len() > 1).then(|| {
        let each: Vec<String> = tyres.iter().map(|(f, t)| format!("{f}: {t:?}")).collect();
        format!(
            "the files name {} tyres ({}): fitted as one tyre; two specimens of one tyre model can differ by 10–14 % in peak FX and ~20 % in slip stiffness, so expect a misfit between the runs (validate on a repeat run with --validate)",
            names.len(),
            each.join("; ")
        )
    })
}

/// Runs the fit.
pub fn run(args: FitArgs) -> Result<()> {
    // The folder of the property file is made before the fit, so a path that cannot be written
    // fails in a moment, not after it.
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create the folder for --out", dir.display()))?;
    }
    let mut data = mffit::Dataset::default();
    let mut data_warnings = Vec::new();
    let mut tyres = Vec::new();
    for p in &args.logs {
        let read = read_any(p).with_context(|| format!("reading {}", p.display()))?;
        let d = read.dataset;
        eprintln!("{}: {} segments, {} samples", p.display(), d.segments.len(), d.len());
        data.extend(d);
        data_warnings.extend(read.warnings);
        tyres.extend(read.tyres);
    }
    data_warnings.extend(specimen_warning(&tyres));
    if data.is_empty() {
        bail!("no data in {:?}", args.logs);
    }
    let template = match &args.template {
        Some(t) => Some(TyreParams::read_tir(t)?),
        None => None,
    };
    let mut opts = FitOptions {
        include_graph_sweeps: args.include_graph_sweeps,
        robust_pct: args.robust,
        max_points: args.max_points,
        fnomin_n: args.fnomin,
        template,
        folds: args.folds,
        skip_stages: args.skip_stages.clone(),
        ..FitOptions::default()
    };
    for s in &opts.skip_stages {
        if !mffit::stages::STAGES.iter().any(|st| st.name() == s) {
            let names: Vec<&str> = mffit::stages::STAGES.iter().map(|st| st.name()).collect();
            bail!("--skip-stage {s}: no such stage (stages: {})", names.join(", "));
        }
    }
    if let Some(t) = args.threads {
        opts.threads = t.max(1);
    }
    let mut result = fit(&data, &opts)?;
    // What the logs are missing heads the warnings (and the report's list of them).
    data_warnings.append(&mut result.warnings);
    result.warnings = data_warnings;
    eprintln!(
        "{:<18} {:>6} {:>12} {:>9} {:>9} {:>5} {:>5} {:>8}",
        "stage", "points", "rmse", "nrmse %", "held-out", "fit", "held", "wall s"
    );
    for s in &result.stages {
        match &s.skipped {
            Some(r) => eprintln!("{:<18} skipped: {r}", s.stage),
            None => eprintln!(
                "{:<18} {:>6} {:>12.4} {:>9.2} {:>9} {:>5} {:>5} {:>8.2}",
                s.stage,
                s.points,
                s.rmse,
                s.nrmse_pct(),
                s.heldout.as_ref().map(|h| format!("{:.2}", h.nrmse_pct)).unwrap_or_else(|| "–".into()),
                s.keys.len(),
                s.held.len(),
                s.wall_s
            ),
        }
    }
    print_repeat_bands(&result);
    for v in &args.validate {
        let other = read_any(v).with_context(|| format!("reading {} (--validate)", v.display()))?;
        let rows = mffit::stages::validate(&result, &other.dataset, &opts);
        eprintln!("validation on {}:", v.display());
        for r in &rows {
            let band = match (r.repeat_band, r.in_repeat_band_pct) {
                (Some(b), Some(p)) => {
                    format!(", {p:.1} % within ±{b:.4} (predicted {:.0} %)", 100.0 * REPEAT_BAND_LEVEL)
                }
                _ => String::new(),
            };
            eprintln!(
                "  {:<18} {:>6} pts  NRMSE {:>6.2} %  (rmse {:.4}, bias {:+.4}){band}",
                r.stage, r.points, r.nrmse_pct, r.rmse, r.bias
            );
        }
        result.validation.push((v.display().to_string(), rows));
    }
    for w in &result.warnings {
        eprintln!("warning: {w}");
    }
    eprintln!("total wall time {:.2} s", result.wall_s);
    std::fs::write(&args.out, result.params.to_tir_string())
        .with_context(|| format!("{}: cannot write", args.out.display()))?;
    // The written file must load back (the same reader `tyrerig model eval` uses).
    TyreParams::read_tir(&args.out)
        .with_context(|| format!("{}: written file does not read back", args.out.display()))?;
    eprintln!("wrote {}", args.out.display());
    let accuracy = match &args.truth {
        Some(t) => {
            let truth = TyreParams::read_tir(t)?;
            let acc = mffit::accuracy::compare(
                &truth,
                &result.params,
                &result.range,
                &mffit::accuracy::Support::of_fit(&result),
            );
            eprintln!("accuracy against {} (held-out grid inside the tested range):", t.display());
            for a in &acc {
                eprintln!(
                    "  {:<12} {:>7.2} % of peak RMS (max {:>6.2} %)",
                    a.channel, a.rms_pct_of_peak, a.max_pct_of_peak
                );
            }
            Some(acc)
        }
        None => None,
    };
    if let Some(dir) = &args.report {
        let files = mffit::report::write(dir, &result, accuracy.as_deref())?;
        eprintln!("report: {} files in {}", files.len(), dir.display());
    }
    let bad = result.nonphysical_stages();
    if !bad.is_empty() {
        for st in result.stages.iter().filter(|s| !s.nonphysical.is_empty()) {
            eprintln!(
                "error: stage {} is non-physical: {}{}",
                st.stage,
                st.nonphysical[0],
                if st.nonphysical.len() > 1 {
                    format!(" (and {} more)", st.nonphysical.len() - 1)
                } else {
                    String::new()
                }
            );
        }
        if !args.allow_nonphysical {
            eprintln!(
                "{} was written, but the model is non-physical in stage(s) {}; rerun with --allow-nonphysical to accept it",
                args.out.display(),
                bad.join(", ")
            );
            std::process::exit(EXIT_NONPHYSICAL);
        }
        eprintln!("warning: non-physical model accepted (--allow-nonphysical)");
    }
    Ok(())
}

/// The band each cross-validated stage predicts for a repeat run (`crossval::repeat_band`).
fn print_repeat_bands(result: &mffit::stages::FitResult) {
    let bands: Vec<String> = result
        .stages
        .iter()
        .filter_map(|s| s.heldout.as_ref().filter(|h| h.repeat_band.is_finite()).map(|h| (s, h)))
        .map(|(s, h)| format!("{} ±{:.4} ({:.2} % of peak)", s.stage, h.repeat_band, 100.0 * h.repeat_band / h.peak))
        .collect();
    if !bands.is_empty() {
        eprintln!(
            "band for a repeat run ({:.0} % of held-out errors within): {}",
            100.0 * REPEAT_BAND_LEVEL,
            bands.join(", ")
        );
    }
}
