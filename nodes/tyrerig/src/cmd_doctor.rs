//! `tyrerig doctor`: find where an MF-Tyre 6.1 model and rig logs disagree beyond the noise,
//! name the missing effect (thermal, wear, break-in, transient, pressure, …), add it to the
//! model and show the gap shrink. See `docs/doctor.md` and the `doctor` crate.

use anyhow::{Context, Result, bail};
use clap::Args;
use doctor::{DataOptions, Dataset, DoctorConfig, Effect, RawLog, diagnose, report};
use mftyre::TyreParams;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `tyrerig doctor`.
#[derive(Debug, Args)]
pub struct DoctorArgs {
    /// MCAP logs of the test, or measured files (TTC `.dat`/`.mat`, TYDEX `.tdx` or a folder of
    /// them), in test order (each is one tyre's run)
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    /// Base MF-Tyre 6.1 model to diagnose
    #[arg(long, conflicts_with = "fit")]
    model: Option<PathBuf>,
    /// Fit the base model to the logs first (mffit's staged GS2MF fit), then diagnose it
    #[arg(long)]
    fit: bool,
    /// With --fit: a fit stage not to run (its channels are then not diagnosed); repeatable
    #[arg(long = "skip-stage", value_name = "STAGE", requires = "fit")]
    skip_stages: Vec<String>,
    /// Output directory (doctor.json, report.md, plots, <model>_doctor.tir)
    #[arg(long)]
    out: PathBuf,
    /// Rate of the residual points inside sweeps [Hz]
    #[arg(long, default_value_t = 10.0)]
    rate_hz: f64,
    /// Held-out folds (sweeps dealt round-robin)
    #[arg(long, default_value_t = 4)]
    folds: usize,
    /// Smallest evidence (share of held-out χ² explained, after the parameter penalty) to name
    /// an effect
    #[arg(long, default_value_t = 0.05)]
    min_evidence: f64,
    /// Most effects named of each family (state effects, form errors)
    #[arg(long, default_value_t = 3)]
    max_effects: usize,
    /// Candidates to test (comma list; default: all of thermal, wear, break_in, transient,
    /// pressure, camber, speed, load, offset, specimen)
    #[arg(long)]
    candidates: Option<String>,
    /// Score state effects against the present model plus its form error (the residual other
    /// sweeps show at the same operating point): `auto` = on with --fit, off with --model
    #[arg(long, value_enum, default_value_t = FormCorrection::Auto)]
    form_correction: FormCorrection,
    /// Resamples of the block bootstrap over sweeps that decides whether a gain is consistent
    /// (default: the doctor's)
    #[arg(long)]
    bootstrap_resamples: Option<usize>,
}

/// When the doctor separates the model's form error from state effects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormCorrection {
    /// On for a base fitted to the same logs (--fit), off for a given model (--model).
    Auto,
    /// Always.
    On,
    /// Never.
    Off,
}

/// Runs `tyrerig doctor`.
pub fn run(args: DoctorArgs) -> Result<()> {
    let t0 = Instant::now();
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create", args.out.display()))?;
    // Measured files are imported into MCAP logs in the output directory first: the doctor and
    // the base fit then read every source the same way (samples and sweep states).
    let mut log_paths = Vec::new();
    for p in &args.logs {
        log_paths.push(import_if_measured(p, &args.out)?);
    }
    let mut logs = Vec::new();
    for p in &log_paths {
        logs.push(RawLog::read_mcap(p)?);
    }
    let ds = Dataset::from_logs(&logs, &DataOptions { point_rate_hz: args.rate_hz, ..DataOptions::default() })?;
    // Channels the base model says nothing trustworthy about are not diagnosed (a given model
    // speaks for every channel; a fitted one only for the channels its stages fitted).
    let mut not_diagnosed: Vec<(usize, String)> = Vec::new();
    let (base, base_name): (TyreParams, String) = match (&args.model, args.fit) {
        (Some(m), _) => (
            TyreParams::read_tir(m).with_context(|| format!("{}: cannot read the base model", m.display()))?,
            m.display().to_string(),
        ),
        (None, true) => {
            let paths: Vec<&std::path::Path> = log_paths.iter().map(PathBuf::as_path).collect();
            let data = mffit::logs::read_logs(&paths).context("reading the logs for the base fit")?;
            eprintln!("fitting the base model to {} log(s) …", paths.len());
            // The base only has to be the best model the data give: no cross-validation here.
            let opts = mffit::stages::FitOptions {
                folds: 0,
                skip_stages: args.skip_stages.clone(),
                ..mffit::stages::FitOptions::default()
            };
            let fit = mffit::stages::fit(&data, &opts).context("base model fit")?;
            not_diagnosed = unfitted_channels(&fit);
            let path = args.out.join("base_fit.tir");
            std::fs::write(&path, fit.params.to_tir_string()).with_context(|| format!("{}", path.display()))?;
            (fit.params, path.display().to_string())
        }
        (None, false) => bail!("give the base model with --model <base.tir>, or --fit to fit one to the logs"),
    };
    let candidates = match &args.candidates {
        None => Effect::ALL.to_vec(),
        Some(list) => list
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| {
                Effect::parse(s).with_context(|| {
                    format!(
                        "--candidates: unknown effect {s:?} (expected {})",
                        Effect::ALL.map(Effect::name).join(", ")
                    )
                })
            })
            .collect::<Result<Vec<_>>>()?,
    };
    let cfg = DoctorConfig {
        folds: args.folds,
        min_evidence: args.min_evidence,
        max_effects: args.max_effects,
        candidates,
        not_diagnosed,
        form_correction: match args.form_correction {
            FormCorrection::Auto => args.fit,
            FormCorrection::On => true,
            FormCorrection::Off => false,
        },
        bootstrap_resamples: args.bootstrap_resamples.unwrap_or(DoctorConfig::default().bootstrap_resamples),
        ..DoctorConfig::default()
    };
    for nd in &cfg.not_diagnosed {
        eprintln!("{} not diagnosed: {}", doctor::effects::CHANNELS[nd.0], nd.1);
    }
    eprintln!("{} points in {} sweeps; testing {} candidates …", ds.len(), ds.sweeps.len(), cfg.candidates.len());
    let dx = diagnose(&ds, &base, &cfg)?;
    let wall = t0.elapsed().as_secs_f64();
    let w = report::write_all(&args.out, &ds, &base, &dx, &base_name, wall)?;
    if dx.state_effects().next().is_none() {
        println!("no missing effect of the tyre's state named: {}", dx.stop_reason);
    }
    for (i, n) in dx.named.iter().enumerate() {
        let family = match (n.family, n.indistinct_from) {
            (doctor::Family::State, None) => "state effect".to_owned(),
            (doctor::Family::State, Some(other)) => format!("state effect, not told from {}: not named", other.name()),
            (doctor::Family::FormError, _) => "form error".to_owned(),
        };
        println!(
            "{}. {} [{family}] (evidence {:.3}, p {}; runner-up {}): {} RMS in its region {:.4} → {:.4} held-out, {:.4} → {:.4} fit",
            i + 1,
            n.effect.name(),
            n.evidence,
            doctor::diagnose::p_text(n.p_value),
            n.runner_up.map_or("none".to_owned(), |(e, v)| format!("{} {:.3}", e.name(), v)),
            n.channel,
            n.rms_before_heldout,
            n.rms_after_heldout,
            n.rms_before,
            n.rms_after
        );
    }
    for w in &dx.written_model_worse {
        println!("warning: {w}");
    }
    for ni in dx.not_identifiable.iter().chain(&dx.dropped) {
        println!("{ni}");
    }
    println!("report: {}", w.markdown.display());
    println!("json:   {}", w.json.display());
    if let Some(m) = &w.model {
        println!("model:  {}", m.display());
    }
    println!("wall time {wall:.1} s");
    Ok(())
}

/// The doctor's channels (FX, FYW, MZW, DSTWOWHC) whose stages the base fit did not fit from
/// these logs, each with the reason.
fn unfitted_channels(fit: &mffit::FitResult) -> Vec<(usize, String)> {
    use doctor::effects::{CH_FX, CH_FY, CH_MZ, CH_RL};
    let why = |what: &str, stages: &[&str]| -> Option<String> {
        (!stages.iter().any(|s| fit.fitted(s))).then(|| {
            format!("the base's {what} was not fitted from these logs (stage {} did not run)", stages.join("/"))
        })
    };
    [
        (CH_FX, why("longitudinal force", &["fx_pure", "fx_combined"])),
        (CH_FY, why("lateral force", &["fy_pure", "fy_combined"])),
        (CH_MZ, why("aligning moment", &["mz_pure", "mz_combined"])),
        (CH_RL, why("loaded radius", &["radius_stiffness"])),
    ]
    .into_iter()
    .filter_map(|(ch, r)| r.map(|r| (ch, r)))
    .collect()
}

/// The MCAP log to read for `path`: itself, or for a measured file (TTC `.dat`/`.mat`, TYDEX, a
/// folder) the log it is imported into, `<out>/<name>.imported.mcap`.
fn import_if_measured(path: &std::path::Path, out: &std::path::Path) -> Result<PathBuf> {
    let measured = path.is_dir() || rigdata::import::FileFormat::of(path).is_some();
    if !measured {
        return Ok(path.to_path_buf());
    }
    // A sweep begun on a cold tyre stays a measurement here: a visit in another thermal state is
    // what tells a state effect from the operating point, and left out of the base fit (as
    // `tyrerig fit` leaves it out) an outsider's thermal effect in relaxing TTC-style runs lost
    // its significance (bootstrap p 0.005 → 0.0075 against α/m = 0.0063, its gain then resting
    // on that one sweep; `doctor_cli::thermal_hidden_in_relaxing_ttc_runs_is_named_beside_transient`).
    let read = rigdata::ReadOptions {
        sweeps: rigdata::sweeps::SweepOptions { cold_start: false, ..Default::default() },
        ..Default::default()
    };
    let import = rigdata::read_path(path, &read).with_context(|| format!("reading {}", path.display()))?;
    for f in &import.inspection.files {
        eprintln!(
            "{}: {} sweeps, {} rows excluded, {} warnings (`tyrerig inspect` lists them)",
            f.file,
            f.sweeps.len(),
            f.excluded.iter().map(|e| e.1).sum::<usize>(),
            f.warnings.len()
        );
    }
    let name = path.file_name().map_or_else(|| "measured".to_owned(), |n| n.to_string_lossy().into_owned());
    let log = out.join(format!("{name}.imported.mcap"));
    mffit::logs::write_log(&log, &import.dataset).with_context(|| format!("writing {}", log.display()))?;
    Ok(log)
}
