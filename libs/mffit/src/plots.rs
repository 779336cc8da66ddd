//! The fit report's plots, drawn as an engineer reads them: each stage over the slip it sweeps
//! (slip angle for the pure lateral stages, slip ratio for the longitudinal and combined ones),
//! one panel per held level (slip angle for the combined stages, camber, pressure) and one
//! colour per load in it, so no panel mixes cells; the model as smooth curves evaluated at each
//! cell's nominal conditions, data as dots in the same colour. Besides: the friction ellipse
//! (FX against FY of the combined sweeps, with the model), residuals against tread temperature
//! and test time, loaded radius and stiffness against load.

use plotters::coord::Shift;
use plotters::prelude::*;

use mftyre::{MfInput, TyreParams, UseMode};

use crate::engine::{Channel, Point};
use crate::stages::{FitResult, StageData};

/// One curve or scatter of a panel.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label (empty: none).
    pub label: String,
    /// Index into the palette.
    pub color: usize,
    /// (x, y) pairs.
    pub points: Vec<(f64, f64)>,
    /// Dots (data) rather than a line (model).
    pub scatter: bool,
}

/// One chart of a figure.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Caption.
    pub title: String,
    /// Axis labels.
    pub x_label: String,
    /// Axis labels.
    pub y_label: String,
    /// Its series.
    pub series: Vec<Series>,
}

/// One file (PNG and SVG): panels in a grid.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File name without extension.
    pub stem: String,
    /// Title over the panels.
    pub title: String,
    /// The panels.
    pub panels: Vec<Panel>,
}

impl Figure {
    /// True when nothing would be drawn.
    pub fn is_empty(&self) -> bool {
        self.panels.iter().all(|p| p.series.is_empty())
    }

    /// Pixel size: three panels a row, 560 × 420 each, under a title band.
    pub fn size_px(&self) -> (u32, u32) {
        let n = self.panels.len().max(1) as u32;
        let cols = n.min(3);
        let rows = n.div_ceil(cols);
        (560 * cols, 420 * rows + TITLE_PX)
    }
}

/// Height of a figure's title band, px.
const TITLE_PX: u32 = 40;
/// Most panels a figure holds (the cells with most points); the title says when more exist.
const MAX_PANELS: usize = 12;
/// Points on a model curve.
const CURVE_POINTS: usize = 120;

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

/// Draws `f` on `root`.
pub fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, f: &Figure) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let (title, body) = root.split_vertically(TITLE_PX);
    title.draw(&Text::new(f.title.clone(), (12, 10), ("sans-serif", 20).into_font())).map_err(err)?;
    let n = f.panels.len().max(1);
    let cols = n.min(3);
    let rows = n.div_ceil(cols);
    for (area, p) in body.split_evenly((rows, cols)).into_iter().zip(&f.panels) {
        draw_panel(area, p)?;
    }
    root.present().map_err(err)
}

fn draw_panel<DB: DrawingBackend>(area: DrawingArea<DB, Shift>, p: &Panel) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let all = p.series.iter().flat_map(|s| s.points.iter()).filter(|q| q.0.is_finite() && q.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for q in all {
        x0 = x0.min(q.0);
        x1 = x1.max(q.0);
        y0 = y0.min(q.1);
        y1 = y1.max(q.1);
    }
    if !(x0.is_finite() && x1.is_finite()) {
        (x0, x1) = (0.0, 1.0);
    }
    if !(y0.is_finite() && y1.is_finite()) {
        (y0, y1) = (0.0, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1.0;
    }
    let (dx, dy) = (0.04 * (x1 - x0), 0.06 * (y1 - y0));
    let mut chart = ChartBuilder::on(&area)
        .caption(&p.title, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(62)
        .build_cartesian_2d((x0 - dx)..(x1 + dx), (y0 - dy)..(y1 + dy))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    let finite = |q: &&(f64, f64)| q.0.is_finite() && q.1.is_finite();
    let mut labelled = false;
    for s in &p.series {
        let c = COLORS[s.color % COLORS.len()];
        let drawn = if s.scatter {
            chart
                .draw_series(
                    s.points.iter().filter(finite).map(|&q| Circle::new(q, 2, ShapeStyle::from(&c.mix(0.45)).filled())),
                )
                .map_err(err)?
        } else {
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().filter(finite).copied(),
                    ShapeStyle::from(&c).stroke_width(2),
                ))
                .map_err(err)?
        };
        if !s.label.is_empty() {
            labelled = true;
            drawn
                .label(s.label.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], ShapeStyle::from(&c).stroke_width(3)));
        }
    }
    if labelled {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .label_font(("sans-serif", 11))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// Values clustered into levels: sorted, split where the gap exceeds `gap`; returns each value's
/// level index and the levels' medians.
fn levels(values: &[f64], gap: f64) -> (Vec<usize>, Vec<f64>) {
    let mut order: Vec<usize> = (0..values.len()).filter(|&i| values[i].is_finite()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut level_of = vec![usize::MAX; values.len()];
    let mut members: Vec<Vec<f64>> = Vec::new();
    let mut last = f64::NEG_INFINITY;
    for i in order {
        let v = values[i];
        if members.is_empty() || v - last > gap {
            members.push(Vec::new());
        }
        last = v;
        if let Some(m) = members.last_mut() {
            m.push(v);
        }
        level_of[i] = members.len() - 1;
    }
    (level_of, members.iter().map(|m| median(m)).collect())
}

fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// The slip a stage sweeps: slip ratio for the longitudinal and combined stages, slip angle
/// otherwise; `None` for stages not swept in slip (radius, relaxation).
fn swept_by_slip_ratio(channel: Channel) -> Option<bool> {
    match channel {
        Channel::Fx0 | Channel::Fx | Channel::Fy | Channel::Mz => Some(true),
        Channel::Fy0 | Channel::Mz0 | Channel::Mx => Some(false),
        Channel::Rl | Channel::Re | Channel::Cx | Channel::SigmaY => None,
    }
}

fn unit(channel: Channel) -> &'static str {
    match channel {
        Channel::Mz0 | Channel::Mz | Channel::Mx => "N·m",
        Channel::Rl | Channel::Re => "m",
        _ => "N",
    }
}

/// Held levels of a stage's points: per point, its panel (slip angle when swept in slip ratio,
/// camber, pressure) and its load level; with the levels' values.
struct Cells {
    panel_of: Vec<usize>,
    load_of: Vec<usize>,
    /// Per panel: (held slip angle rad if any, camber rad, pressure Pa).
    panels: Vec<(Option<f64>, f64, f64)>,
    loads_n: Vec<f64>,
}

impl Cells {
    fn of(points: &[Point], by_slip_ratio: bool, fz0: f64) -> Self {
        let col = |f: fn(&MfInput) -> f64| points.iter().map(|p| f(&p.input)).collect::<Vec<f64>>();
        // Gaps: loads of one setpoint wander (±15 % on older rounds), setpoints sit ≥ 25 % apart.
        let (load_of, loads_n) = levels(&col(|i| i.fz_n), 0.1 * fz0);
        let (camber_of, cambers) = levels(&col(|i| i.gamma_rad), 0.5f64.to_radians());
        let (pressure_of, pressures) = levels(&col(|i| i.p_pa), 5e3);
        let (alpha_of, alphas) = if by_slip_ratio {
            levels(&col(|i| i.alpha_rad), 0.5f64.to_radians())
        } else {
            (vec![0; points.len()], vec![f64::NAN])
        };
        let mut panels: Vec<(usize, usize, usize)> = Vec::new();
        let mut panel_of = Vec::with_capacity(points.len());
        for i in 0..points.len() {
            let key = (alpha_of[i], camber_of[i], pressure_of[i]);
            let at = match panels.iter().position(|k| *k == key) {
                Some(at) => at,
                None => {
                    panels.push(key);
                    panels.len() - 1
                }
            };
            panel_of.push(at);
        }
        let value = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(f64::NAN);
        let panels = panels
            .iter()
            .map(|&(a, g, p)| (by_slip_ratio.then(|| value(&alphas, a)), value(&cambers, g), value(&pressures, p)))
            .collect();
        Cells { panel_of, load_of, panels, loads_n }
    }
}

fn panel_title(held: (Option<f64>, f64, f64)) -> String {
    let (alpha, gamma, p) = held;
    let mut t = String::new();
    if let Some(a) = alpha {
        t.push_str(&format!("SA {:.1}°, ", a.to_degrees()));
    }
    t.push_str(&format!("IA {:.1}°, P {:.2} bar", gamma.to_degrees(), p / 1e5));
    t
}

/// The model input at a cell's nominal conditions (medians of its points) with the swept slip
/// set to `slip`.
fn nominal_input(cell: &[&Point], by_slip_ratio: bool, slip: f64) -> MfInput {
    let m = |f: fn(&MfInput) -> f64| median(&cell.iter().map(|p| f(&p.input)).collect::<Vec<f64>>());
    let mut input = MfInput {
        fz_n: m(|i| i.fz_n),
        kappa: m(|i| i.kappa),
        alpha_rad: m(|i| i.alpha_rad),
        gamma_rad: m(|i| i.gamma_rad),
        phit_per_m: 0.0,
        vx_mps: m(|i| i.vx_mps),
        p_pa: m(|i| i.p_pa),
        omega_radps: m(|i| i.omega_radps),
    };
    if by_slip_ratio {
        input.kappa = slip;
    } else {
        input.alpha_rad = slip;
    }
    input
}

/// A model curve over the cell's slip range at its nominal conditions.
fn model_curve(
    params: &TyreParams,
    channel: Channel,
    cell: &[&Point],
    by_slip_ratio: bool,
    x: impl Fn(&Point) -> f64,
) -> Vec<(f64, f64)> {
    let slip = |p: &&Point| if by_slip_ratio { p.input.kappa } else { p.input.alpha_rad };
    let lo = cell.iter().map(slip).fold(f64::INFINITY, f64::min);
    let hi = cell.iter().map(slip).fold(f64::NEG_INFINITY, f64::max);
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return Vec::new();
    }
    (0..CURVE_POINTS)
        .map(|k| {
            let s = lo + (hi - lo) * k as f64 / (CURVE_POINTS - 1) as f64;
            let input = nominal_input(cell, by_slip_ratio, s);
            let at = Point { input, measured: f64::NAN };
            (x(&at), channel.eval(params, &input))
        })
        .collect()
}

/// Model over data for one stage: one panel per held slip angle (combined stages), camber and
/// pressure, one colour per load level.
pub fn stage_figure(params: &TyreParams, d: &StageData, fz0: f64) -> Option<Figure> {
    let by_slip_ratio = swept_by_slip_ratio(d.channel)?;
    let x = |p: &Point| if by_slip_ratio { p.input.kappa } else { p.input.alpha_rad.to_degrees() };
    let x_label = if by_slip_ratio { "LONGSLIP [-]" } else { "SLIPANGL [deg]" };
    let cells = Cells::of(&d.points, by_slip_ratio, fz0);
    let mut order: Vec<usize> = (0..cells.panels.len()).collect();
    let count = |i: usize| cells.panel_of.iter().filter(|&&p| p == i).count();
    order.sort_by_key(|&i| std::cmp::Reverse(count(i)));
    let shown = order.len().min(MAX_PANELS);
    let mut chosen: Vec<usize> = order[..shown].to_vec();
    chosen.sort_by(|&a, &b| {
        let (pa, pb) = (cells.panels[a], cells.panels[b]);
        (pa.0.unwrap_or(0.0), pa.1, pa.2)
            .partial_cmp(&(pb.0.unwrap_or(0.0), pb.1, pb.2))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut panels = Vec::new();
    for &pi in &chosen {
        let mut series = Vec::new();
        for (li, fz) in cells.loads_n.iter().enumerate() {
            let cell: Vec<&Point> = d
                .points
                .iter()
                .enumerate()
                .filter(|(i, _)| cells.panel_of[*i] == pi && cells.load_of[*i] == li)
                .map(|(_, p)| p)
                .collect();
            if cell.is_empty() {
                continue;
            }
            series.push(Series {
                label: format!("FZ {fz:.0} N"),
                color: li,
                points: cell.iter().map(|p| (x(p), p.measured)).collect(),
                scatter: true,
            });
            series.push(Series {
                label: String::new(),
                color: li,
                points: model_curve(params, d.channel, &cell, by_slip_ratio, x),
                scatter: false,
            });
        }
        panels.push(Panel {
            title: panel_title(cells.panels[pi]),
            x_label: x_label.into(),
            y_label: format!("{} [{}]", d.channel.name(), unit(d.channel)),
            series,
        });
    }
    let more = if order.len() > shown { format!(" ({shown} of {} panels)", order.len()) } else { String::new() };
    Some(Figure {
        stem: format!("{}_{}", d.stage, d.channel.name().to_lowercase()),
        title: format!(
            "{} — {}: model at each cell's nominal conditions (lines), data (dots), colour = load{more}",
            d.stage,
            d.channel.name()
        ),
        panels,
    })
}

/// FX against FY of the combined sweeps, one panel per load level and camber, one colour per held
/// slip angle; the model over each cell's slip-ratio range at its nominal conditions.
pub fn ellipse_figure(params: &TyreParams, result: &FitResult) -> Option<Figure> {
    let fx = result.data.iter().find(|d| d.stage == "fx_combined")?;
    let fy = result.data.iter().find(|d| d.stage == "fy_combined")?;
    // The two stages select the same points (same sweeps, same decimation); pair them only
    // where the inputs agree.
    let pairs: Vec<(Point, f64)> = fx
        .points
        .iter()
        .zip(&fy.points)
        .filter(|(a, b)| {
            a.input.fz_n.to_bits() == b.input.fz_n.to_bits() && a.input.kappa.to_bits() == b.input.kappa.to_bits()
        })
        .map(|(a, b)| (*a, b.measured))
        .collect();
    if pairs.is_empty() {
        return None;
    }
    let points: Vec<Point> = pairs.iter().map(|(p, _)| *p).collect();
    let fz0 = result.nominal.fz0_n;
    let col = |f: fn(&MfInput) -> f64| points.iter().map(|p| f(&p.input)).collect::<Vec<f64>>();
    let (load_of, loads) = levels(&col(|i| i.fz_n), 0.1 * fz0);
    let (camber_of, cambers) = levels(&col(|i| i.gamma_rad), 0.5f64.to_radians());
    let (pressure_of, pressures) = levels(&col(|i| i.p_pa), 5e3);
    let (alpha_of, alphas) = levels(&col(|i| i.alpha_rad), 0.5f64.to_radians());
    let mut keys: Vec<(usize, usize, usize)> =
        (0..points.len()).map(|i| (load_of[i], camber_of[i], pressure_of[i])).collect();
    keys.sort_unstable();
    keys.dedup();
    let total = keys.len();
    keys.truncate(MAX_PANELS);
    let mut panels = Vec::new();
    for key in keys {
        let mut series = Vec::new();
        for (ai, a) in alphas.iter().enumerate() {
            let idx: Vec<usize> = (0..points.len())
                .filter(|&i| (load_of[i], camber_of[i], pressure_of[i]) == key && alpha_of[i] == ai)
                .collect();
            if idx.is_empty() {
                continue;
            }
            let cell: Vec<&Point> = idx.iter().map(|&i| &points[i]).collect();
            series.push(Series {
                label: format!("SA {:.1}°", a.to_degrees()),
                color: ai,
                points: idx.iter().map(|&i| (pairs[i].0.measured, pairs[i].1)).collect(),
                scatter: true,
            });
            let lo = cell.iter().map(|p| p.input.kappa).fold(f64::INFINITY, f64::min);
            let hi = cell.iter().map(|p| p.input.kappa).fold(f64::NEG_INFINITY, f64::max);
            let curve = if hi > lo {
                (0..CURVE_POINTS)
                    .map(|k| {
                        let input = nominal_input(&cell, true, lo + (hi - lo) * k as f64 / (CURVE_POINTS - 1) as f64);
                        (Channel::Fx.eval(params, &input), Channel::Fy.eval(params, &input))
                    })
                    .collect()
            } else {
                Vec::new()
            };
            series.push(Series { label: String::new(), color: ai, points: curve, scatter: false });
        }
        let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(f64::NAN);
        panels.push(Panel {
            title: format!(
                "FZ {:.0} N, IA {:.1}°, P {:.2} bar",
                at(&loads, key.0),
                at(&cambers, key.1).to_degrees(),
                at(&pressures, key.2) / 1e5
            ),
            x_label: "FX [N]".into(),
            y_label: "FYW [N]".into(),
            series,
        });
    }
    let more = if total > MAX_PANELS { format!(" ({MAX_PANELS} of {total} panels)") } else { String::new() };
    Some(Figure {
        stem: "friction_ellipse".into(),
        title: format!(
            "Friction ellipse: combined sweeps (dots) and the model over each cell's slip ratio (lines){more}"
        ),
        panels,
    })
}

/// Residuals (model − measured) of one stage against tread temperature and against test time
/// (segments in the order read, gaps between them left out), one colour per load level.
pub fn residual_figure(params: &TyreParams, d: &StageData, fz0: f64) -> Option<Figure> {
    swept_by_slip_ratio(d.channel)?;
    if d.states.len() != d.points.len() || d.points.is_empty() {
        return None;
    }
    let model = d.channel.values_at(params, &d.points);
    let fz: Vec<f64> = d.points.iter().map(|p| p.input.fz_n).collect();
    let (load_of, loads) = levels(&fz, 0.1 * fz0);
    let y_label = format!("{} residual [{}]", d.channel.name(), unit(d.channel));
    let mut by_temp = Vec::new();
    let mut by_time = Vec::new();
    for (li, l) in loads.iter().enumerate() {
        let idx: Vec<usize> = (0..d.points.len()).filter(|&i| load_of[i] == li).collect();
        let res = |i: usize| model[i] - d.points[i].measured;
        by_temp.push(Series {
            label: format!("FZ {l:.0} N"),
            color: li,
            points: idx.iter().map(|&i| (d.states[i].temp_c, res(i))).filter(|q| q.0.is_finite()).collect(),
            scatter: true,
        });
        by_time.push(Series {
            label: format!("FZ {l:.0} N"),
            color: li,
            points: idx.iter().map(|&i| (d.states[i].test_time_s, res(i))).collect(),
            scatter: true,
        });
    }
    let no_temp = by_temp.iter().all(|s| s.points.is_empty());
    let mut panels = vec![Panel {
        title: "against test time".into(),
        x_label: "test time (segments in order, gaps left out) [s]".into(),
        y_label: y_label.clone(),
        series: by_time,
    }];
    panels.insert(
        0,
        Panel {
            title: if no_temp {
                "against tread temperature (none recorded)".into()
            } else {
                "against tread temperature".into()
            },
            x_label: "tread temperature [°C]".into(),
            y_label,
            series: by_temp,
        },
    );
    Some(Figure {
        stem: format!("{}_{}_residuals", d.stage, d.channel.name().to_lowercase()),
        title: format!("{} — {} residual (model − measured) by temperature and time", d.stage, d.channel.name()),
        panels,
    })
}

fn input(params: &TyreParams, fz: f64, p: f64) -> MfInput {
    MfInput {
        fz_n: fz,
        kappa: 0.0,
        alpha_rad: 0.0,
        gamma_rad: 0.0,
        phit_per_m: 0.0,
        vx_mps: params.longvl_mps(),
        p_pa: p,
        omega_radps: 0.0,
    }
}

fn pressures(result: &FitResult) -> Vec<f64> {
    let r = &result.range.p_pa;
    let p0 = result.nominal.p0_pa;
    if r.is_empty() || r.max - r.min < 1e4 { vec![p0] } else { vec![r.min, p0, r.max] }
}

/// Loaded radius against load: the radius stage's data and the model per pressure.
pub fn radius_figure(params: &TyreParams, result: &FitResult) -> Figure {
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
                let mut inp = input(params, fz, p);
                inp.omega_radps = params.longvl_mps() / params.unloaded_radius_m();
                (fz, mftyre::evaluate(params, UseMode::M111, &inp).rl_m)
            })
            .collect();
        series.push(Series { label: format!("model {:.1} bar", p / 1e5), color: i, points: pts, scatter: false });
    }
    single(
        "radius_vs_load",
        "Loaded radius against load (model at V0, data all speeds)",
        Panel { title: String::new(), x_label: "FZW [N]".into(), y_label: "loaded radius [m]".into(), series },
    )
}

/// Cornering and slip stiffness of the fitted model against load, per pressure.
pub fn stiffness_figure(params: &TyreParams, result: &FitResult) -> Figure {
    let mut series = Vec::new();
    let fz_max = result.range.fz_n.max.max(2.0 * result.nominal.fz0_n);
    for (i, p) in pressures(result).into_iter().enumerate() {
        let mut ky = Vec::new();
        let mut kx = Vec::new();
        for k in 1..=40 {
            let fz = fz_max * k as f64 / 40.0;
            let o = mftyre::evaluate(params, UseMode::M111, &input(params, fz, p));
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
    single(
        "stiffness_vs_load",
        "Cornering and slip stiffness against load (fitted model)",
        Panel { title: String::new(), x_label: "FZW [N]".into(), y_label: "stiffness [N/deg, N/%]".into(), series },
    )
}

fn single(stem: &str, title: &str, panel: Panel) -> Figure {
    Figure { stem: stem.into(), title: title.into(), panels: vec![panel] }
}

/// Every figure of a fit's report.
pub fn all(result: &FitResult) -> Vec<Figure> {
    let params = &result.params;
    let fz0 = result.nominal.fz0_n;
    let mut out: Vec<Figure> = result.data.iter().filter_map(|d| stage_figure(params, d, fz0)).collect();
    out.extend(ellipse_figure(params, result));
    out.extend(result.data.iter().filter_map(|d| residual_figure(params, d, fz0)));
    out.push(radius_figure(params, result));
    out.push(stiffness_figure(params, result));
    out.retain(|f| !f.is_empty());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_split_at_gaps_and_keep_wandering_values_together() {
        let v = [1000.0, 1150.0, 880.0, 2000.0, 2100.0, f64::NAN];
        let (of, medians) = levels(&v, 300.0);
        assert_eq!(of[..5], [0, 0, 0, 1, 1]);
        assert_eq!(of[5], usize::MAX, "a non-finite value has no level");
        assert_eq!(medians, vec![1000.0, 2100.0]);
    }
}
