//! The fit report: `report.md` (stages, metrics, valid range, findings), `fit.json` (per-stage
//! `{"stage", "channel", "rmse", "nrmse_pct", "r2"}` and the total wall time) and the plots of
//! [`crate::plots`], as PNG and SVG.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plotters::prelude::{BitMapBackend, IntoDrawingArea, SVGBackend};
use serde::Serialize;

use crate::accuracy::AccuracyRow;
use crate::error::FitError;
use crate::metrics::{self, Metrics};
use crate::plots;
use crate::stages::FitResult;

/// One row of `fit.json`'s `stages` array.
#[derive(Debug, Clone, Serialize)]
pub struct StageJson {
    /// Stage name.
    pub stage: String,
    /// Channel.
    pub channel: String,
    /// RMSE, channel units.
    pub rmse: f64,
    /// RMSE in % of peak.
    pub nrmse_pct: f64,
    /// R².
    pub r2: f64,
    /// Bias.
    pub bias: f64,
    /// Largest error.
    pub max_err: f64,
    /// Points.
    pub points: usize,
    /// Wall time of the stage, s.
    pub wall_s: f64,
    /// k-fold held-out NRMSE over sweeps, % of peak (None when not cross-validated).
    pub heldout_nrmse_pct: Option<f64>,
    /// The band for a repeat run, channel units: ± this holds 95 % of held-out errors
    /// (`crossval::repeat_band`; None when not cross-validated).
    pub repeat_band_95: Option<f64>,
    /// % of held-out points inside the in-sample ±1.96·RMSE band.
    pub fit_band_heldout_pct: Option<f64>,
    /// Fitted coefficients with their standard deviations.
    pub coefficients: Vec<crate::identify::Estimate>,
    /// Coefficients left at their template (or start) values, and why.
    pub held: Vec<crate::identify::Held>,
    /// Physical margins of the stage that fail on the final model.
    pub nonphysical: Vec<String>,
}

#[derive(Serialize)]
struct FitJson<'a> {
    stages: Vec<StageJson>,
    wall_time_s: f64,
    stage_wall_s: Vec<(String, f64)>,
    nominal: &'a crate::stages::Nominal,
    valid_range: &'a crate::data::ValidRange,
    warnings: &'a [String],
    notes: Vec<(String, Vec<String>)>,
    skipped: Vec<(String, String)>,
    groups: &'a [Metrics],
    accuracy: Option<&'a [AccuracyRow]>,
    validation: &'a [(String, Vec<crate::stages::ValidationRow>)],
    nonphysical_stages: Vec<&'a str>,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> FitError + '_ {
    move |source| FitError::Io { path: path.to_owned(), source }
}

/// Writes the report into `dir` (created if needed); returns the files written.
pub fn write(dir: &Path, result: &FitResult, accuracy: Option<&[AccuracyRow]>) -> Result<Vec<PathBuf>, FitError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let params = &result.params;
    let groups = metrics::all(params, &result.data, result.nominal.fz0_n);
    let mut stages_json = Vec::new();
    for s in &result.stages {
        if let Some(m) = groups.iter().find(|m| m.stage == s.stage && m.group == "all") {
            stages_json.push(StageJson {
                stage: s.stage.clone(),
                channel: m.channel.clone(),
                rmse: m.rmse,
                nrmse_pct: m.nrmse_pct,
                r2: m.r2,
                bias: m.bias,
                max_err: m.max_err,
                points: m.points,
                wall_s: s.wall_s,
                heldout_nrmse_pct: s.heldout.as_ref().map(|h| h.nrmse_pct),
                repeat_band_95: s.heldout.as_ref().map(|h| h.repeat_band).filter(|b| b.is_finite()),
                fit_band_heldout_pct: s.heldout.as_ref().map(|h| h.fit_band_heldout_pct),
                coefficients: s.estimates.clone(),
                held: s.held.clone(),
                nonphysical: s.nonphysical.clone(),
            });
        }
    }
    let json = FitJson {
        stages: stages_json.clone(),
        wall_time_s: result.wall_s,
        stage_wall_s: result.stages.iter().map(|s| (s.stage.clone(), s.wall_s)).collect(),
        nominal: &result.nominal,
        valid_range: &result.range,
        warnings: &result.warnings,
        notes: result.stages.iter().map(|s| (s.stage.clone(), s.notes.clone())).collect(),
        skipped: result.stages.iter().filter_map(|s| s.skipped.clone().map(|r| (s.stage.clone(), r))).collect(),
        groups: &groups,
        accuracy,
        validation: &result.validation,
        nonphysical_stages: result.nonphysical_stages(),
    };
    let mut written = Vec::new();
    let jpath = dir.join("fit.json");
    let text =
        serde_json::to_string_pretty(&json).map_err(|e| FitError::Io { path: jpath.clone(), source: e.into() })?;
    std::fs::write(&jpath, text).map_err(io(&jpath))?;
    written.push(jpath);

    let plots = plots::all(result);
    for p in &plots {
        let size = p.size_px();
        for ext in ["png", "svg"] {
            let path = dir.join(format!("{}.{ext}", p.stem));
            let r = if ext == "png" {
                plots::draw(BitMapBackend::new(&path, size).into_drawing_area(), p)
            } else {
                plots::draw(SVGBackend::new(&path, size).into_drawing_area(), p)
            };
            r.map_err(|message| FitError::Plot { path: path.clone(), message })?;
            written.push(path);
        }
    }

    let md = markdown(result, &groups, &stages_json, accuracy, &plots);
    let mpath = dir.join("report.md");
    std::fs::write(&mpath, md).map_err(io(&mpath))?;
    written.push(mpath);
    Ok(written)
}

fn markdown(
    result: &FitResult,
    groups: &[Metrics],
    stages: &[StageJson],
    accuracy: Option<&[AccuracyRow]>,
    plots: &[plots::Figure],
) -> String {
    let mut s = String::new();
    let n = &result.nominal;
    let _ = writeln!(s, "# MF-Tyre 6.1 fit report\n");
    let _ = writeln!(
        s,
        "Nominal values: V0 = {:.1} m/s, P0 = {:.0} Pa, Fz0 = {:.0} N, R0 = {:.4} m.\n",
        n.v0_mps, n.p0_pa, n.fz0_n, n.r0_m
    );
    for note in &n.notes {
        let _ = writeln!(s, "- {note}");
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "Total wall time: {:.2} s.\n", result.wall_s);
    let _ = writeln!(s, "## Stages\n");
    let _ = writeln!(
        s,
        "NRMSE is the RMS error in % of the stage's peak |measured|; *held-out* is the k-fold cross-validation over \
         sweeps (each point predicted by a fit that never saw its sweep).\n"
    );
    let _ = writeln!(
        s,
        "| stage | channel | points | RMSE | NRMSE % | held-out NRMSE % | bias | max err | R² | iterations | wall s |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
    for st in &result.stages {
        match stages.iter().find(|j| j.stage == st.stage) {
            Some(j) => {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {:.4} | {:.2} | {} | {:.4} | {:.4} | {:.4} | {} | {:.2} |",
                    st.stage,
                    j.channel,
                    j.points,
                    j.rmse,
                    j.nrmse_pct,
                    j.heldout_nrmse_pct.map(|v| format!("{v:.2}")).unwrap_or_else(|| "–".into()),
                    j.bias,
                    j.max_err,
                    j.r2,
                    st.iterations,
                    st.wall_s
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "| {} | {} | – | – | – | – | – | – | – | {} | {:.2} |",
                    st.stage, st.channel, st.iterations, st.wall_s
                );
            }
        }
    }
    write_repeat_bands(&mut s, result, stages);
    let _ = writeln!(s, "\n## Notes per stage\n");
    for st in &result.stages {
        if let Some(r) = &st.skipped {
            let _ = writeln!(s, "- **{}**: skipped — {r}", st.stage);
        }
        for note in &st.notes {
            let _ = writeln!(s, "- **{}**: {note}", st.stage);
        }
        if !st.keys.is_empty() {
            let _ = writeln!(s, "- **{}** fitted: {}", st.stage, st.keys.join(", "));
        }
    }
    let _ = writeln!(s, "\n## Coefficients\n");
    let _ = writeln!(
        s,
        "Each stage fits only the coefficients its data identify: what a coefficient multiplies must vary in the \
         data (two loads for a load term, three for a quadratic one; two cambers; two pressures), and the Jacobian at \
         the solution must tell it apart from the others. The rest keep the template's (or the stage's documented \
         starting) values. ±1σ comes from the Jacobian and the residual variance, inflated for serially correlated \
         residuals; it describes repeatability, not model-form error (see the held-out column above). ±1σ over \
         sweeps is the grouped jackknife over the cross-validation's folds (each fold's refit leaves out a fifth of \
         the sweeps): how much the value depends on which sweeps were tested, form error included; where it is \
         much larger than ±1σ, trust it.\n"
    );
    for st in result.stages.iter().filter(|st| !st.estimates.is_empty() || !st.held.is_empty()) {
        let _ = writeln!(s, "### {}\n", st.stage);
        if !st.estimates.is_empty() {
            let _ = writeln!(s, "| key | value | ±1σ | ±1σ over sweeps |\n|---|---|---|---|");
            for e in &st.estimates {
                let sweeps = e.std_sweeps.map_or_else(|| "–".to_owned(), |v| format!("{v:.3e}"));
                let _ = writeln!(s, "| {} | {:.6} | {:.3e} | {sweeps} |", e.key, e.value, e.std);
            }
            let _ = writeln!(s, "\n(serial-correlation variance inflation ×{:.1})\n", st.serial_inflation);
        }
        if !st.held.is_empty() {
            let _ = writeln!(s, "| key held | value | why |\n|---|---|---|");
            for h in &st.held {
                let _ = writeln!(s, "| {} | {} | {} |", h.key, h.value, h.reason);
            }
            let _ = writeln!(s);
        }
    }
    if !result.validation.is_empty() {
        let _ = writeln!(s, "\n## Validation on other runs\n");
        let _ = writeln!(
            s,
            "The fitted model as it is, on the same stage selections of another run. *In band* checks the band for a \
             repeat run (above): the share of this run's points within ±band of the model, predicted {:.0} %.\n",
            100.0 * crate::stages::crossval::REPEAT_BAND_LEVEL
        );
        for (src, rows) in &result.validation {
            let _ = writeln!(
                s,
                "**{src}**\n\n| stage | channel | points | RMSE | NRMSE % | bias | band ± | in band % |\n\
                 |---|---|---|---|---|---|---|---|"
            );
            for r in rows {
                let (band, inside) = match (r.repeat_band, r.in_repeat_band_pct) {
                    (Some(b), Some(p)) => (format!("{b:.4}"), format!("{p:.1}")),
                    _ => ("–".into(), "–".into()),
                };
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {:.4} | {:.2} | {:.4} | {band} | {inside} |",
                    r.stage, r.channel, r.points, r.rmse, r.nrmse_pct, r.bias
                );
            }
            let _ = writeln!(s);
        }
    }
    let _ = writeln!(s, "\n## Failure-mode checks\n");
    let bad = result.nonphysical_stages();
    if !bad.is_empty() {
        let _ = writeln!(
            s,
            "**Non-physical model**: the physical margins of stage(s) {} fail on the final model.\n",
            bad.join(", ")
        );
        for st in result.stages.iter().filter(|st| !st.nonphysical.is_empty()) {
            for m in st.nonphysical.iter().take(10) {
                let _ = writeln!(s, "- {}: {m}", st.stage);
            }
            if st.nonphysical.len() > 10 {
                let _ = writeln!(s, "- {}: … {} more", st.stage, st.nonphysical.len() - 10);
            }
        }
    }
    if result.warnings.is_empty() {
        let _ = writeln!(
            s,
            "No findings: C > 0, D > 0, E ≤ 1 over the tested range; friction ellipse round; stable just outside the range."
        );
    }
    for w in &result.warnings {
        let _ = writeln!(s, "- {w}");
    }
    let r = &result.range;
    let _ = writeln!(s, "\n## Valid range (tested range, written to the .tir limits)\n");
    let _ = writeln!(s, "| quantity | min | max |\n|---|---|---|");
    let _ = writeln!(s, "| FZW, N | {:.0} | {:.0} |", r.fz_n.min, r.fz_n.max);
    let _ =
        writeln!(s, "| SLIPANGL, deg | {:.1} | {:.1} |", r.alpha_rad.min.to_degrees(), r.alpha_rad.max.to_degrees());
    let _ = writeln!(s, "| LONGSLIP | {:.3} | {:.3} |", r.kappa.min, r.kappa.max);
    let _ =
        writeln!(s, "| INCLANGL, deg | {:.1} | {:.1} |", r.gamma_rad.min.to_degrees(), r.gamma_rad.max.to_degrees());
    let _ = writeln!(s, "| INFLPRES, bar | {:.2} | {:.2} |", r.p_pa.min / 1e5, r.p_pa.max / 1e5);
    let _ = writeln!(s, "| TRAJVELW, m/s | {:.1} | {:.1} |", r.vx_mps.min, r.vx_mps.max);
    if let Some(acc) = accuracy {
        let _ = writeln!(s, "\n## Accuracy against the reference tyre (held-out grid inside the tested range)\n");
        let _ = writeln!(s, "| channel | grid points | RMS | RMS % of peak | max % of peak |\n|---|---|---|---|---|");
        for a in acc {
            let _ = writeln!(
                s,
                "| {} | {} | {:.2} | {:.2} | {:.2} |",
                a.channel, a.points, a.rms, a.rms_pct_of_peak, a.max_pct_of_peak
            );
        }
    }
    let _ = writeln!(s, "\n## Metrics by load, pressure and camber\n");
    let _ = writeln!(
        s,
        "| stage | channel | group | points | RMSE | NRMSE % | bias | max err | R² |\n|---|---|---|---|---|---|---|---|---|"
    );
    for m in groups {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.4} | {:.2} | {:.4} | {:.4} | {:.4} |",
            m.stage, m.channel, m.group, m.points, m.rmse, m.nrmse_pct, m.bias, m.max_err, m.r2
        );
    }
    let _ = writeln!(s, "\n## Plots\n");
    let _ = writeln!(
        s,
        "Each stage over the slip it sweeps, one panel per held slip angle (combined stages), camber and pressure, \
         one colour per load; the model drawn at each cell's nominal conditions. Residuals against tread temperature \
         and test time show drift the model does not have.\n"
    );
    for p in plots {
        let _ = writeln!(s, "- {}: ![{}]({}.png) ([svg]({}.svg))", p.title, p.stem, p.stem, p.stem);
    }
    s
}

/// The report's "band for a repeat run" section: per cross-validated stage, the half-width that
/// holds 95 % of the held-out errors and what the in-sample ±1.96·RMSE band holds of them.
fn write_repeat_bands(s: &mut String, result: &FitResult, stages: &[StageJson]) {
    let rows: Vec<&StageJson> = stages.iter().filter(|j| j.repeat_band_95.is_some()).collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n## Band for a repeat run\n");
    let _ = writeln!(
        s,
        "A new sweep of this tyre on this plan is predicted to fall within ±band of the model at {:.0} % of its \
         points: the band is the {:.0} % rank of the errors on held-out sweeps (each point predicted by a fit that \
         never saw its sweep: noise, form error and the coefficients' spread together). It is one width per stage, so \
         it is wider than needed where the model is good and narrower where it is poor. A second specimen of the \
         same tyre model is not this tyre (real pairs differ by 10–14 % in peak force): check it with `--validate`. \
         The last column is what the usual in-sample band ±1.96·RMSE holds of the held-out points.\n",
        100.0 * crate::stages::crossval::REPEAT_BAND_LEVEL,
        100.0 * crate::stages::crossval::REPEAT_BAND_LEVEL,
    );
    let _ = writeln!(s, "| stage | channel | band ± | band, % of peak | ±1.96·RMSE holds, % |\n|---|---|---|---|---|");
    for j in rows {
        let band = j.repeat_band_95.unwrap_or(f64::NAN);
        let peak = result
            .stages
            .iter()
            .find(|r| r.stage == j.stage)
            .and_then(|r| r.heldout.as_ref())
            .map_or(f64::NAN, |h| h.peak);
        let _ = writeln!(
            s,
            "| {} | {} | {band:.4} | {:.2} | {} |",
            j.stage,
            j.channel,
            100.0 * band / peak,
            j.fit_band_heldout_pct.map_or_else(|| "–".into(), |p| format!("{p:.1}"))
        );
    }
}
