//! The fit report: `report.md` (stages, metrics, valid range, findings), `fit.json` (per-stage
//! `{"stage", "channel", "rmse", "nrmse_pct", "r2"}` and the total wall time) and plots in the
//! style of the thesis's Fig. 5.2.x (model over data coloured by load, camber and pressure;
//! friction ellipse; radius against load; stiffness against load), as PNG and SVG.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use mftyre::{MfInput, TyreParams, UseMode};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use crate::accuracy::AccuracyRow;
use crate::engine::{Channel, Point};
use crate::error::FitError;
use crate::metrics::{self, Metrics};
use crate::stages::{FitResult, StageData};

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

    let mut plots = Vec::new();
    for d in &result.data {
        plots.extend(stage_plots(params, d, result.nominal.fz0_n));
    }
    plots.push(ellipse_plot(params, result));
    plots.push(radius_plot(params, result));
    plots.push(stiffness_plot(params, result));
    for p in plots.iter().filter(|p| !p.series.is_empty()) {
        for ext in ["png", "svg"] {
            let path = dir.join(format!("{}.{ext}", p.stem));
            let r = if ext == "png" {
                draw(BitMapBackend::new(&path, (1000, 700)).into_drawing_area(), p)
            } else {
                draw(SVGBackend::new(&path, (1000, 700)).into_drawing_area(), p)
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
    plots: &[Plot],
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
         residuals; it describes repeatability, not model-form error (see the held-out column above).\n"
    );
    for st in result.stages.iter().filter(|st| !st.estimates.is_empty() || !st.held.is_empty()) {
        let _ = writeln!(s, "### {}\n", st.stage);
        if !st.estimates.is_empty() {
            let _ = writeln!(s, "| key | value | ±1σ |\n|---|---|---|");
            for e in &st.estimates {
                let _ = writeln!(s, "| {} | {:.6} | {:.3e} |", e.key, e.value, e.std);
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
        let _ = writeln!(s, "The fitted model as it is, on the same stage selections of another run.\n");
        for (src, rows) in &result.validation {
            let _ = writeln!(
                s,
                "**{src}**\n\n| stage | channel | points | RMSE | NRMSE % | bias |\n|---|---|---|---|---|---|"
            );
            for r in rows {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {:.4} | {:.2} | {:.4} |",
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
    for p in plots.iter().filter(|p| !p.series.is_empty()) {
        let _ = writeln!(s, "- {}: ![{}]({}.png) ([svg]({}.svg))", p.title, p.stem, p.stem, p.stem);
    }
    s
}

struct Series {
    label: String,
    color: usize,
    points: Vec<(f64, f64)>,
    /// Scatter (data) rather than a line (model).
    scatter: bool,
}

struct Plot {
    stem: String,
    title: String,
    x_label: String,
    y_label: String,
    series: Vec<Series>,
}

const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, p: &Plot) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let all = p.series.iter().flat_map(|s| s.points.iter()).filter(|q| q.0.is_finite() && q.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for q in all {
        x0 = x0.min(q.0);
        x1 = x1.max(q.0);
        y0 = y0.min(q.1);
        y1 = y1.max(q.1);
    }
    if x1.is_nan() || x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1.is_nan() || y1 <= y0 {
        y1 = y0 + 1.0;
    }
    let (dx, dy) = (0.04 * (x1 - x0), 0.06 * (y1 - y0));
    let mut chart = ChartBuilder::on(&root)
        .caption(&p.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(80)
        .build_cartesian_2d((x0 - dx)..(x1 + dx), (y0 - dy)..(y1 + dy))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for s in &p.series {
        let c = COLORS[s.color % COLORS.len()];
        if s.scatter {
            let drawn = chart
                .draw_series(s.points.iter().map(|&q| Circle::new(q, 2, ShapeStyle::from(&c.mix(0.35)).filled())))
                .map_err(err)?;
            if !s.label.is_empty() {
                drawn
                    .label(s.label.clone())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, ShapeStyle::from(&c).filled()));
            }
        } else {
            let drawn = chart
                .draw_series(LineSeries::new(s.points.iter().copied(), ShapeStyle::from(&c).stroke_width(2)))
                .map_err(err)?;
            if !s.label.is_empty() {
                drawn.label(s.label.clone()).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], ShapeStyle::from(&c).stroke_width(2))
                });
            }
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Model over data for one stage, coloured by load, by camber and by pressure: data as dots,
/// the model at the same inputs as lines per group (sorted along the slip axis).
fn stage_plots(params: &TyreParams, d: &StageData, fz0: f64) -> Vec<Plot> {
    let (x_of, x_label): (fn(&Point) -> f64, &str) = match d.channel {
        Channel::Fx0 | Channel::Fx => (|p| p.input.kappa, "LONGSLIP [-]"),
        Channel::Rl | Channel::Re => (|p| p.input.fz_n, "FZW [N]"),
        Channel::Cx | Channel::SigmaY => return Vec::new(),
        _ => (|p| p.input.alpha_rad.to_degrees(), "SLIPANGL [deg]"),
    };
    let unit = match d.channel {
        Channel::Mz0 | Channel::Mz | Channel::Mx => "N·m",
        Channel::Rl | Channel::Re => "m",
        _ => "N",
    };
    let fz0c = fz0;
    type Grouper = Box<dyn Fn(&Point) -> String>;
    let groupers: [(&str, Grouper); 3] = [
        ("load", Box::new(move |p: &Point| metrics::load_group(p, fz0c))),
        ("camber", Box::new(metrics::camber_group)),
        ("pressure", Box::new(metrics::pressure_group)),
    ];
    let mut out = Vec::new();
    for (by, g) in groupers.iter() {
        let mut labels: Vec<String> = d.points.iter().map(g).collect();
        labels.sort();
        labels.dedup();
        if labels.len() < 2 && *by != "load" {
            continue;
        }
        let mut series = Vec::new();
        for (i, l) in labels.iter().enumerate().take(10) {
            let pts: Vec<&Point> = d.points.iter().filter(|p| &g(p) == l).collect();
            series.push(Series {
                label: l.clone(),
                color: i,
                points: pts.iter().map(|p| (x_of(p), p.measured)).collect(),
                scatter: true,
            });
            let mut model: Vec<(f64, f64)> = pts.iter().map(|p| (x_of(p), d.channel.eval(params, &p.input))).collect();
            model.sort_by(|a, b| a.0.total_cmp(&b.0));
            // Thin the line to a running median so mixed loads in a group do not zigzag.
            let model = smooth(&model, 7);
            series.push(Series { label: String::new(), color: i, points: model, scatter: false });
        }
        out.push(Plot {
            stem: format!("{}_{}_by_{by}", d.stage, d.channel.name().to_lowercase()),
            title: format!("{} — {} [{unit}], model (lines) over data (dots), by {by}", d.stage, d.channel.name()),
            x_label: x_label.into(),
            y_label: format!("{} [{unit}]", d.channel.name()),
            series,
        });
    }
    out
}

fn smooth(v: &[(f64, f64)], w: usize) -> Vec<(f64, f64)> {
    if v.len() <= w {
        return v.to_vec();
    }
    v.windows(w)
        .step_by((v.len() / 200).max(1))
        .map(|win| {
            let mut ys: Vec<f64> = win.iter().map(|q| q.1).collect();
            ys.sort_by(f64::total_cmp);
            (win[w / 2].0, ys[w / 2])
        })
        .collect()
}

fn input(params: &TyreParams, fz: f64, kappa: f64, alpha: f64, p: f64) -> MfInput {
    MfInput {
        fz_n: fz,
        kappa,
        alpha_rad: alpha,
        gamma_rad: 0.0,
        phit_per_m: 0.0,
        vx_mps: params.longvl_mps(),
        p_pa: p,
        omega_radps: 0.0,
    }
}

fn ellipse_plot(params: &TyreParams, result: &FitResult) -> Plot {
    let fz0 = result.nominal.fz0_n;
    let p0 = result.nominal.p0_pa;
    let mut series = Vec::new();
    if let Some(d) = result.data.iter().find(|d| d.stage == "fx_combined") {
        let fy = result.data.iter().find(|d| d.stage == "fy_combined");
        if let Some(fy) = fy {
            let pts: Vec<(f64, f64)> = d
                .points
                .iter()
                .zip(&fy.points)
                .filter(|(a, _)| (a.input.fz_n - fz0).abs() < 0.25 * fz0)
                .map(|(a, b)| (a.measured, b.measured))
                .collect();
            series.push(Series { label: "data near Fz0".into(), color: 7, points: pts, scatter: true });
        }
    }
    for (i, a) in [1.0_f64, 2.0, 4.0, 6.0, 8.0].iter().enumerate() {
        for side in [1.0, -1.0] {
            let pts: Vec<(f64, f64)> = (0..=80)
                .map(|k| {
                    let kap = -0.4 + 0.8 * k as f64 / 80.0;
                    let o =
                        mftyre::evaluate(params, UseMode::M111, &input(params, fz0, kap, side * a.to_radians(), p0));
                    (o.fx_n, o.fy_n)
                })
                .collect();
            let label = if side > 0.0 { format!("SA ±{a} deg") } else { String::new() };
            series.push(Series { label, color: i, points: pts, scatter: false });
        }
    }
    Plot {
        stem: "friction_ellipse".into(),
        title: format!("Friction ellipse at Fz0 = {fz0:.0} N, P0 (SR −0.4…0.4)"),
        x_label: "FX [N]".into(),
        y_label: "FYW [N]".into(),
        series,
    }
}

fn pressures(result: &FitResult) -> Vec<f64> {
    let r = &result.range.p_pa;
    let p0 = result.nominal.p0_pa;
    if r.is_empty() || r.max - r.min < 1e4 { vec![p0] } else { vec![r.min, p0, r.max] }
}

fn radius_plot(params: &TyreParams, result: &FitResult) -> Plot {
    let mut series = Vec::new();
    if let Some(d) = result.data.iter().find(|d| d.stage == "radius_stiffness") {
        series.push(Series {
            label: "DSTWOWHC data".into(),
            color: 7,
            points: d.points.iter().map(|p| (p.input.fz_n, p.measured)).collect(),
            scatter: true,
        });
    }
    let fz_max = result.range.fz_n.max.max(2.0 * result.nominal.fz0_n);
    for (i, p) in pressures(result).into_iter().enumerate() {
        let pts: Vec<(f64, f64)> = (1..=40)
            .map(|k| {
                let fz = fz_max * k as f64 / 40.0;
                let mut inp = input(params, fz, 0.0, 0.0, p);
                inp.omega_radps = params.longvl_mps() / params.unloaded_radius_m();
                (fz, mftyre::evaluate(params, UseMode::M111, &inp).rl_m)
            })
            .collect();
        series.push(Series { label: format!("model {:.1} bar", p / 1e5), color: i, points: pts, scatter: false });
    }
    Plot {
        stem: "radius_vs_load".into(),
        title: "Loaded radius against load (model at V0, data all speeds)".into(),
        x_label: "FZW [N]".into(),
        y_label: "loaded radius [m]".into(),
        series,
    }
}

fn stiffness_plot(params: &TyreParams, result: &FitResult) -> Plot {
    let mut series = Vec::new();
    let fz_max = result.range.fz_n.max.max(2.0 * result.nominal.fz0_n);
    for (i, p) in pressures(result).into_iter().enumerate() {
        let mut ky = Vec::new();
        let mut kx = Vec::new();
        for k in 1..=40 {
            let fz = fz_max * k as f64 / 40.0;
            let o = mftyre::evaluate(params, UseMode::M111, &input(params, fz, 0.0, 0.0, p));
            ky.push((fz, o.kya_nprad.abs() * std::f64::consts::PI / 180.0));
            kx.push((fz, o.kxk_n / 100.0));
        }
        series.push(Series {
            label: format!("cornering stiffness N/deg, {:.1} bar", p / 1e5),
            color: i,
            points: ky,
            scatter: false,
        });
        series.push(Series {
            label: format!("slip stiffness N/% , {:.1} bar", p / 1e5),
            color: i + 4,
            points: kx,
            scatter: false,
        });
    }
    Plot {
        stem: "stiffness_vs_load".into(),
        title: "Cornering and slip stiffness against load (fitted model)".into(),
        x_label: "FZW [N]".into(),
        y_label: "stiffness [N/deg, N/%]".into(),
        series,
    }
}
