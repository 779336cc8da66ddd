//! `tyrerig bench doctor`: the doctor's diagnosis benchmark (issue 30, docs/doctor-benchmark.md).
//!
//! Known effects, drawn from a family wider than the doctor's own forms (`hidden`), are hidden
//! in clean virtual-rig logs of three tyres and three plans and the doctor is run on each case
//! exactly as the CLI runs it (this binary, `tyrerig doctor`); its `named_effects` are scored
//! against the injected kinds: confusion table, precision and recall per effect, false names on
//! clean cases, the held-out cut in each named effect's region, wall time. Cases run one after
//! another: the doctor uses every core itself.

mod cases;
mod steps;

use anyhow::{Context, Result};
use hidden::score::{CaseRecord, Score};
use std::path::{Path, PathBuf};
use std::time::Instant;

use cases::Case;

/// `tyrerig bench doctor` arguments.
#[derive(Debug, clap::Args)]
pub struct DoctorBench {
    /// Where the clean logs (made once, reused by later runs), the cases' injected logs and
    /// doctor outputs go
    #[arg(long, default_value = "out/bench_doctor")]
    pub work_dir: PathBuf,
    /// Eight cases spanning the tyres, plans and effect sets instead of all of them
    #[arg(long)]
    pub quick: bool,
    /// Only the cases whose id (`tyre/plan/effects/s<seed>`) contains this
    #[arg(long)]
    pub cases: Option<String>,
    /// Seeds per single effect (pairs get half as many, clean cases one): 2 gives 81 cases
    #[arg(long, default_value_t = 2)]
    pub seeds: u64,
    /// Write every case's record and the scores as JSON
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Keep each case's injected logs and TTC files (otherwise only truth.json and the
    /// doctor's output stay)
    #[arg(long)]
    pub keep_logs: bool,
    /// The launch-config directory (rig configs, procedures, the MF tyre)
    #[arg(long, default_value = "launch-config")]
    pub launch_config: PathBuf,
    /// One more argument for every case's `tyrerig doctor` (repeatable, e.g.
    /// `--doctor-arg=--folds --doctor-arg=8`): to measure a setting of the doctor on all cases
    #[arg(long = "doctor-arg", allow_hyphen_values = true)]
    pub doctor_args: Vec<String>,
}

/// Runs the benchmark.
pub fn run(args: &DoctorBench) -> Result<()> {
    let mut list = if args.quick { cases::quick_cases() } else { cases::all_cases(args.seeds) };
    if let Some(f) = &args.cases {
        list.retain(|c| c.id().contains(f.as_str()));
    }
    if list.is_empty() {
        anyhow::bail!("no case matches --cases {:?}", args.cases.as_deref().unwrap_or(""));
    }
    let clean_dir = args.work_dir.join("clean");
    std::fs::create_dir_all(&clean_dir).with_context(|| format!("{}: cannot create", clean_dir.display()))?;
    let t0 = Instant::now();
    let mut records = Vec::with_capacity(list.len());
    for (i, case) in list.iter().enumerate() {
        eprintln!("[{}/{}] {} (strength {})", i + 1, list.len(), case.id(), case.strength());
        let r = run_case(args, case, &clean_dir);
        match &r.error {
            Some(e) => eprintln!("  error: {e}"),
            None => eprintln!(
                "  named [{}] (form errors [{}]{}); truth [{}]; {:.1} s (doctor {:.1} s)",
                r.named.join(", "),
                r.form_errors.join(", "),
                r.indistinct.iter().map(|[a, b]| format!("; not told apart: {a} or {b}")).collect::<String>(),
                r.truth
                    .iter()
                    .map(|t| format!("{} {:.1} σ", t.kind, t.strength_noise_units))
                    .collect::<Vec<_>>()
                    .join(", "),
                r.wall_time_s,
                r.doctor_wall_time_s
            ),
        }
        records.push(r);
    }
    let score = Score::of(&records);
    println!("{}", score.render());
    println!("benchmark wall time {:.1} min", t0.elapsed().as_secs_f64() / 60.0);
    if let Some(path) = &args.json {
        let v = serde_json::json!({ "tool": "tyrerig bench doctor", "cases": records, "score": score });
        std::fs::write(path, serde_json::to_string_pretty(&v)?)
            .with_context(|| format!("{}: cannot write", path.display()))?;
        println!("json: {}", path.display());
    }
    Ok(())
}

/// One case, its failure kept in the record (the benchmark goes on).
fn run_case(args: &DoctorBench, case: &Case, clean_dir: &Path) -> CaseRecord {
    let t0 = Instant::now();
    let mut record = CaseRecord {
        case: case.id(),
        tyre: case.tyre.name().into(),
        plan: case.plan.name().into(),
        seed: case.seed,
        truth: Vec::new(),
        named: Vec::new(),
        named_detail: Vec::new(),
        form_errors: Vec::new(),
        indistinct: Vec::new(),
        wall_time_s: 0.0,
        doctor_wall_time_s: f64::NAN,
        error: None,
    };
    // The clean logs are shared by every case of a tyre and plan, so not counted in its time.
    let clean = match steps::clean_logs(&args.launch_config, clean_dir, case.tyre, case.plan) {
        Ok(c) => c,
        Err(e) => {
            record.error = Some(format!("clean logs: {e:#}"));
            return record;
        }
    };
    let t_case = Instant::now();
    if let Err(e) = diagnose_case(args, case, &clean, &mut record) {
        record.error = Some(format!("{e:#}"));
    }
    record.wall_time_s = t_case.elapsed().as_secs_f64();
    tracing::debug!("{}: {:.1} s with the clean logs", case.id(), t0.elapsed().as_secs_f64());
    record
}

fn diagnose_case(args: &DoctorBench, case: &Case, clean: &[PathBuf], record: &mut CaseRecord) -> Result<()> {
    let case_dir = args.work_dir.join("cases").join(case.dir_name());
    std::fs::create_dir_all(&case_dir).with_context(|| format!("{}: cannot create", case_dir.display()))?;
    let rig_config = case.tyre.rig_config(&args.launch_config);
    let (logs, truth) = steps::inject(case, &rig_config, clean, &case_dir)?;
    record.truth = truth;
    let inputs = if case.plan.through_ttc() { steps::export_ttc(&logs, &case_dir)? } else { logs.clone() };
    let verdict = steps::doctor(&args.launch_config, case.tyre, &inputs, &args.doctor_args, &case_dir.join("doctor"));
    if !args.keep_logs {
        // Only the case's own files: never the shared clean logs.
        let own: std::collections::BTreeSet<&PathBuf> =
            logs.iter().chain(&inputs).filter(|p| p.starts_with(&case_dir)).collect();
        for p in own {
            if let Err(e) = std::fs::remove_file(p) {
                eprintln!("  {}: cannot remove: {e}", p.display());
            }
        }
    }
    let verdict = verdict?;
    record.named = verdict.named;
    record.named_detail = verdict.named_detail;
    record.form_errors = verdict.form_errors;
    record.indistinct = verdict.indistinct;
    record.doctor_wall_time_s = verdict.wall_time_s;
    Ok(())
}
