//! `tyrerig model`: evaluate an MF-Tyre 6.1 `.tir` model over a CSV of operating points
//! (MFeval's input and output columns) and plot its characteristic curves.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand, ValueEnum};
use mftyre::{MfInput, MfOutput, TyreParams, UseMode, evaluate};
use plotters::coord::Shift;
use plotters::prelude::*;

/// MF-Tyre 6.1 model commands.
#[derive(Debug, Subcommand)]
pub enum ModelCmd {
    /// Evaluate a .tir model at the operating points of a CSV file (MFeval's column names)
    Eval(EvalArgs),
    /// Plot Fy–α, Fx–κ, Mz–α curve families and the combined-slip envelope
    Plot(PlotArgs),
}

/// Arguments of `tyrerig model eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// MF-Tyre 6.1 property file
    #[arg(long)]
    tir: PathBuf,
    /// Input CSV with columns Fz,kappa,alpha,gamma,phit,Vx,P,omega (SI; others ignored;
    /// P = 0 means the file's INFLPRES, omega = 0 means estimate it)
    #[arg(long)]
    input: PathBuf,
    /// Output CSV, MFeval's columns: Fx Fy Fz Mx My Mz kappa alpha gamma phit Vx P Re rho 2a t
    /// mux muy omega Rl 2b Mzr Cx Cy Cz Kya sigmax sigmay instKya Kxk
    #[arg(long)]
    output: PathBuf,
    /// MFeval use mode: 111 (limit checks, TNO form) or 121 (α* = tan α, γ* = sin γ); also
    /// 112/122/211/212/221/222
    #[arg(long, default_value = "111")]
    use_mode: UseMode,
}

/// Image formats `model plot` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ImageFormat {
    /// PNG only
    Png,
    /// SVG only
    Svg,
    /// Both PNG and SVG
    Both,
}

/// Arguments of `tyrerig model plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// MF-Tyre 6.1 property file
    #[arg(long)]
    tir: PathBuf,
    /// Directory for the images (created if missing)
    #[arg(long)]
    out: PathBuf,
    /// Image format
    #[arg(long, value_enum, default_value = "png")]
    format: ImageFormat,
    /// MFeval use mode
    #[arg(long, default_value = "111")]
    use_mode: UseMode,
}

/// Runs a `model` subcommand.
pub fn run(cmd: ModelCmd) -> Result<()> {
    match cmd {
        ModelCmd::Eval(args) => run_eval(&args),
        ModelCmd::Plot(args) => run_plot(&args),
    }
}

/// Input columns, in MFeval's order.
const INPUT_COLUMNS: [&str; 8] = ["Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega"];

/// Output columns, exactly as MFeval names them.
const OUTPUT_COLUMNS: [&str; 30] = [
    "Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "Re", "rho", "2a", "t", "mux",
    "muy", "omega", "Rl", "2b", "Mzr", "Cx", "Cy", "Cz", "Kya", "sigmax", "sigmay", "instKya", "Kxk",
];

fn read_params(path: &Path) -> Result<TyreParams> {
    TyreParams::read_tir(path).map_err(|e| anyhow!(e))
}

/// Reads the operating points; errors name the file, line and column.
fn read_inputs(path: &Path) -> Result<Vec<MfInput>> {
    let file = path.display();
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(false)
        .from_path(path)
        .with_context(|| format!("{file}: cannot open input CSV"))?;
    let headers = reader.headers().with_context(|| format!("{file}:1: cannot read the header line"))?.clone();
    let index: HashMap<&str, usize> = headers.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let mut cols = [0usize; 8];
    for (slot, name) in cols.iter_mut().zip(INPUT_COLUMNS) {
        *slot = *index.get(name).ok_or_else(|| {
            anyhow!("{file}:1: missing column `{name}` (expected columns {})", INPUT_COLUMNS.join(","))
        })?;
    }
    let mut points = Vec::new();
    for record in reader.records() {
        let record = record.with_context(|| format!("{file}: malformed CSV record"))?;
        let line = record.position().map_or(0, |p| p.line());
        let mut v = [0.0; 8];
        for ((value, &col), name) in v.iter_mut().zip(&cols).zip(INPUT_COLUMNS) {
            let text = record.get(col).unwrap_or("");
            *value = text
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| anyhow!("{file}:{line}: column `{name}`: `{text}` is not a finite number"))?;
        }
        points.push(MfInput {
            fz_n: v[0],
            kappa: v[1],
            alpha_rad: v[2],
            gamma_rad: v[3],
            phit_per_m: v[4],
            vx_mps: v[5],
            p_pa: v[6],
            omega_radps: v[7],
        });
    }
    Ok(points)
}

fn output_row(o: &MfOutput) -> [Option<f64>; 30] {
    [
        Some(o.fx_n),
        Some(o.fy_n),
        Some(o.fz_n),
        Some(o.mx_nm),
        Some(o.my_nm),
        Some(o.mz_nm),
        Some(o.kappa),
        Some(o.alpha_rad),
        Some(o.gamma_rad),
        Some(o.phit_per_m),
        Some(o.vx_mps),
        Some(o.p_pa),
        Some(o.re_m),
        Some(o.rho_m),
        Some(o.contact_length_m),
        Some(o.trail_m),
        Some(o.mux),
        Some(o.muy),
        Some(o.omega_radps),
        Some(o.rl_m),
        Some(o.contact_width_m),
        Some(o.mzr_nm),
        Some(o.cx_npm),
        Some(o.cy_npm),
        Some(o.cz_npm),
        Some(o.kya_nprad),
        Some(o.sigmax_m),
        Some(o.sigmay_m),
        // instKya is MFeval's finite difference between rows, not a model value.
        None,
        Some(o.kxk_n),
    ]
}

fn run_eval(args: &EvalArgs) -> Result<()> {
    let params = read_params(&args.tir)?;
    let points = read_inputs(&args.input)?;
    let out = args.output.display();
    let mut writer = csv::Writer::from_path(&args.output).with_context(|| format!("{out}: cannot create"))?;
    writer.write_record(OUTPUT_COLUMNS).with_context(|| format!("{out}: write failed"))?;
    let mut fields: Vec<String> = Vec::with_capacity(OUTPUT_COLUMNS.len());
    for x in &points {
        let o = evaluate(&params, args.use_mode, x);
        fields.clear();
        // `{:?}` is Rust's shortest round-trip form: reading the CSV back gives identical f64s.
        fields.extend(output_row(&o).iter().map(|v| v.map_or_else(String::new, |v| format!("{v:?}"))));
        writer.write_record(&fields).with_context(|| format!("{out}: write failed"))?;
    }
    writer.flush().with_context(|| format!("{out}: write failed"))?;
    eprintln!("evaluated {} points (use mode {}) -> {out}", points.len(), args.use_mode);
    Ok(())
}

/// One curve of a chart.
struct Series {
    /// Legend text; empty for the mirrored twin of a labelled curve.
    label: String,
    /// Index into [`PALETTE`].
    color: usize,
    points: Vec<(f64, f64)>,
}

/// Distinct, print-safe colours (Okabe–Ito, yellow replaced by a darker gold).
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(180, 140, 0),
    RGBColor(0, 0, 0),
    RGBColor(120, 60, 160),
];

/// One chart: title, axis labels, curves.
struct Chart {
    file_stem: &'static str,
    title: String,
    x_label: &'static str,
    y_label: &'static str,
    series: Vec<Series>,
    /// Equal axis scaling (for the Fx–Fy envelope).
    square: bool,
    /// Where the legend sits (chosen where the curves leave room).
    legend: SeriesLabelPosition,
    /// Decimals of the x tick labels.
    x_decimals: usize,
}

fn linspace(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
    (0..n).map(move |i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
}

fn base_input(params: &TyreParams) -> MfInput {
    MfInput {
        fz_n: params.fnomin_n(),
        vx_mps: params.longvl_mps(),
        p_pa: params.nominal_pressure_pa(),
        ..MfInput::default()
    }
}

fn sweep(
    params: &TyreParams,
    mode: UseMode,
    base: MfInput,
    xs: impl Iterator<Item = f64>,
    set: impl Fn(&mut MfInput, f64),
    get: impl Fn(&MfOutput) -> (f64, f64),
) -> Vec<(f64, f64)> {
    xs.map(|x| {
        let mut input = base;
        set(&mut input, x);
        get(&evaluate(params, mode, &input))
    })
    .collect()
}

/// The load, camber and pressure values the families use, kept inside the file's ranges.
struct Families {
    loads_n: Vec<f64>,
    cambers_rad: Vec<f64>,
    pressures_pa: Vec<f64>,
}

fn families(params: &TyreParams) -> Families {
    let fz0 = params.fnomin_n();
    let l = &params.limits;
    let loads_n = [0.5, 1.0, 1.5, 2.0].iter().map(|f| f * fz0).filter(|fz| *fz <= l.fzmax && *fz >= l.fzmin).collect();
    let cambers_rad = [-6.0_f64, -3.0, 0.0, 3.0, 6.0]
        .iter()
        .map(|d| d.to_radians())
        .filter(|g| *g >= l.cammin && *g <= l.cammax)
        .collect();
    let p0 = params.nominal_pressure_pa();
    let mut pressures_pa: Vec<f64> =
        [0.8, 1.0, 1.25].iter().map(|f| f * p0).filter(|p| *p >= l.presmin && *p <= l.presmax).collect();
    if pressures_pa.is_empty() {
        pressures_pa.push(p0);
    }
    Families { loads_n, cambers_rad, pressures_pa }
}

fn charts(params: &TyreParams, mode: UseMode) -> Vec<Chart> {
    let fam = families(params);
    let base = base_input(params);
    let l = &params.limits;
    let alpha_max_deg = l.alpmax.to_degrees().min(15.0);
    let alpha_min_deg = l.alpmin.to_degrees().max(-15.0);
    let kappa_max = l.kpumax.min(0.5);
    let kappa_min = l.kpumin.max(-0.5);
    let n = 241;
    let alphas = move || linspace(alpha_min_deg, alpha_max_deg, n);
    let kappas = move || linspace(kappa_min, kappa_max, n);
    let set_alpha = |i: &mut MfInput, a_deg: f64| i.alpha_rad = a_deg.to_radians();
    let set_kappa = |i: &mut MfInput, k: f64| i.kappa = k;
    let fy = |o: &MfOutput| (o.alpha_rad.to_degrees(), o.fy_n);
    let fx = |o: &MfOutput| (o.kappa, o.fx_n);
    let mz = |o: &MfOutput| (o.alpha_rad.to_degrees(), o.mz_nm);

    let load_label = |fz: f64| format!("Fz = {:.0} N", fz);
    let camber_label = |g: f64| format!("γ = {:+.0}°", g.to_degrees());
    let pressure_label = |p: f64| format!("p = {:.0} kPa", p / 1000.0);
    let fz0 = params.fnomin_n();
    let p0_kpa = params.nominal_pressure_pa() / 1000.0;

    let family = |values: &[f64],
                  label: &dyn Fn(f64) -> String,
                  apply: &dyn Fn(&mut MfInput, f64),
                  xs: &dyn Fn() -> Box<dyn Iterator<Item = f64>>,
                  set: &dyn Fn(&mut MfInput, f64),
                  get: &dyn Fn(&MfOutput) -> (f64, f64)| {
        values
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                let mut b = base;
                apply(&mut b, v);
                Series { label: label(v), color: i, points: sweep(params, mode, b, xs(), set, get) }
            })
            .collect::<Vec<_>>()
    };
    let set_fz = |i: &mut MfInput, v: f64| i.fz_n = v;
    let set_gamma = |i: &mut MfInput, v: f64| i.gamma_rad = v;
    let set_p = |i: &mut MfInput, v: f64| i.p_pa = v;
    let alphas_box = move || -> Box<dyn Iterator<Item = f64>> { Box::new(alphas()) };
    let kappas_box = move || -> Box<dyn Iterator<Item = f64>> { Box::new(kappas()) };

    let mut out = vec![
        Chart {
            file_stem: "fy_alpha_load",
            title: format!("Pure lateral force over load (γ = 0, p = {p0_kpa:.0} kPa)"),
            x_label: "slip angle α [deg]",
            y_label: "Fy [N]",
            series: family(&fam.loads_n, &load_label, &set_fz, &alphas_box, &set_alpha, &fy),
            square: false,
            legend: SeriesLabelPosition::UpperRight,
            x_decimals: 0,
        },
        Chart {
            file_stem: "fy_alpha_camber",
            title: format!("Pure lateral force over camber (Fz = {fz0:.0} N)"),
            x_label: "slip angle α [deg]",
            y_label: "Fy [N]",
            series: family(&fam.cambers_rad, &camber_label, &set_gamma, &alphas_box, &set_alpha, &fy),
            square: false,
            legend: SeriesLabelPosition::UpperRight,
            x_decimals: 0,
        },
        Chart {
            file_stem: "fy_alpha_pressure",
            title: format!("Pure lateral force over inflation pressure (Fz = {fz0:.0} N)"),
            x_label: "slip angle α [deg]",
            y_label: "Fy [N]",
            series: family(&fam.pressures_pa, &pressure_label, &set_p, &alphas_box, &set_alpha, &fy),
            square: false,
            legend: SeriesLabelPosition::UpperRight,
            x_decimals: 0,
        },
        Chart {
            file_stem: "fx_kappa_load",
            title: format!("Pure longitudinal force over load (γ = 0, p = {p0_kpa:.0} kPa)"),
            x_label: "longitudinal slip κ [-]",
            y_label: "Fx [N]",
            series: family(&fam.loads_n, &load_label, &set_fz, &kappas_box, &set_kappa, &fx),
            square: false,
            legend: SeriesLabelPosition::LowerRight,
            x_decimals: 1,
        },
        Chart {
            file_stem: "fx_kappa_camber",
            title: format!("Pure longitudinal force over camber (Fz = {fz0:.0} N)"),
            x_label: "longitudinal slip κ [-]",
            y_label: "Fx [N]",
            series: family(&fam.cambers_rad, &camber_label, &set_gamma, &kappas_box, &set_kappa, &fx),
            square: false,
            legend: SeriesLabelPosition::LowerRight,
            x_decimals: 1,
        },
        Chart {
            file_stem: "fx_kappa_pressure",
            title: format!("Pure longitudinal force over inflation pressure (Fz = {fz0:.0} N)"),
            x_label: "longitudinal slip κ [-]",
            y_label: "Fx [N]",
            series: family(&fam.pressures_pa, &pressure_label, &set_p, &kappas_box, &set_kappa, &fx),
            square: false,
            legend: SeriesLabelPosition::LowerRight,
            x_decimals: 1,
        },
        Chart {
            file_stem: "mz_alpha_load",
            title: format!("Aligning moment over load (γ = 0, p = {p0_kpa:.0} kPa)"),
            x_label: "slip angle α [deg]",
            y_label: "Mz [N·m]",
            series: family(&fam.loads_n, &load_label, &set_fz, &alphas_box, &set_alpha, &mz),
            square: false,
            legend: SeriesLabelPosition::UpperLeft,
            x_decimals: 0,
        },
        Chart {
            file_stem: "mz_alpha_camber",
            title: format!("Aligning moment over camber (Fz = {fz0:.0} N)"),
            x_label: "slip angle α [deg]",
            y_label: "Mz [N·m]",
            series: family(&fam.cambers_rad, &camber_label, &set_gamma, &alphas_box, &set_alpha, &mz),
            square: false,
            legend: SeriesLabelPosition::UpperLeft,
            x_decimals: 0,
        },
    ];

    // Combined slip. The Fx–Fy envelope: κ swept at constant ±α (mirrored pairs share a
    // colour); then the usual Fy–α at constant κ and Fx–κ at constant α.
    let k_lo = l.kpumin.max(-1.0);
    let k_hi = l.kpumax.min(1.0);
    let mut envelope = Vec::new();
    for (i, a_deg) in [1.0_f64, 2.0, 4.0, 8.0].into_iter().enumerate() {
        for sign in [1.0, -1.0] {
            let mut b = base;
            b.alpha_rad = (sign * a_deg).to_radians();
            envelope.push(Series {
                label: if sign > 0.0 { format!("α = ±{a_deg:.0}°") } else { String::new() },
                color: i,
                points: sweep(params, mode, b, linspace(k_lo, k_hi, 801), set_kappa, |o| (o.fx_n, o.fy_n)),
            });
        }
    }
    out.push(Chart {
        file_stem: "combined_fx_fy",
        title: format!("Combined slip: Fy against Fx, κ {k_lo}…{k_hi} (Fz = {fz0:.0} N)"),
        x_label: "Fx [N]",
        y_label: "Fy [N]",
        series: envelope,
        square: true,
        legend: SeriesLabelPosition::UpperRight,
        x_decimals: 0,
    });
    let kappa_values = [0.0, 0.05, 0.1, 0.2, 0.5];
    out.push(Chart {
        file_stem: "combined_fy_alpha_kappa",
        title: format!("Combined slip: Fy at constant κ (Fz = {fz0:.0} N)"),
        x_label: "slip angle α [deg]",
        y_label: "Fy [N]",
        series: family(&kappa_values, &|k| format!("κ = {k}"), &set_kappa, &alphas_box, &set_alpha, &fy),
        square: false,
        legend: SeriesLabelPosition::UpperRight,
        x_decimals: 0,
    });
    let alpha_values: Vec<f64> = [0.0_f64, 2.0, 4.0, 8.0].iter().map(|d| d.to_radians()).collect();
    out.push(Chart {
        file_stem: "combined_fx_kappa_alpha",
        title: format!("Combined slip: Fx at constant α (Fz = {fz0:.0} N)"),
        x_label: "longitudinal slip κ [-]",
        y_label: "Fx [N]",
        series: family(
            &alpha_values,
            &|a| format!("α = {:.0}°", a.to_degrees()),
            &|i: &mut MfInput, v| i.alpha_rad = v,
            &kappas_box,
            &set_kappa,
            &fx,
        ),
        square: false,
        legend: SeriesLabelPosition::LowerRight,
        x_decimals: 1,
    });
    out
}

fn bounds(chart: &Chart) -> (f64, f64, f64, f64) {
    let mut b = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in chart.series.iter().flat_map(|s| s.points.iter()) {
        b.0 = b.0.min(*x);
        b.1 = b.1.max(*x);
        b.2 = b.2.min(*y);
        b.3 = b.3.max(*y);
    }
    let pad = |lo: f64, hi: f64| {
        let span = (hi - lo).abs().max(1e-9);
        (lo - 0.05 * span, hi + 0.05 * span)
    };
    let (x0, x1) = pad(b.0, b.1);
    let (y0, y1) = pad(b.2, b.3);
    if chart.square {
        let m = x0.abs().max(x1.abs()).max(y0.abs()).max(y1.abs());
        return (-m, m, -m, m);
    }
    (x0, x1, y0, y1)
}

fn draw_chart<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, chart: &Chart) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing failed: {e}");
    root.fill(&WHITE).map_err(err)?;
    let (x0, x1, y0, y1) = bounds(chart);
    let mut ctx = ChartBuilder::on(&root)
        .caption(&chart.title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    let x_decimals = chart.x_decimals;
    ctx.configure_mesh()
        .x_label_formatter(&|v| format!("{v:.x_decimals$}"))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .x_desc(chart.x_label)
        .y_desc(chart.y_label)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    // Axes through the origin make signs (ISO-W: α > 0 gives Fy < 0) easy to read.
    let axis = BLACK.mix(0.6);
    if x0 < 0.0 && x1 > 0.0 {
        ctx.draw_series(LineSeries::new([(0.0, y0), (0.0, y1)], axis)).map_err(err)?;
    }
    if y0 < 0.0 && y1 > 0.0 {
        ctx.draw_series(LineSeries::new([(x0, 0.0), (x1, 0.0)], axis)).map_err(err)?;
    }
    for s in &chart.series {
        let color = PALETTE[s.color % PALETTE.len()];
        let style = ShapeStyle::from(&color).stroke_width(2);
        let drawn = ctx.draw_series(LineSeries::new(s.points.iter().copied(), style)).map_err(err)?;
        if !s.label.is_empty() {
            drawn.label(s.label.clone()).legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], ShapeStyle::from(&color).stroke_width(2))
            });
        }
    }
    ctx.configure_series_labels()
        .position(chart.legend.clone())
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

fn run_plot(args: &PlotArgs) -> Result<()> {
    let params = read_params(&args.tir)?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create directory", args.out.display()))?;
    let mut written = Vec::new();
    for chart in charts(&params, args.use_mode) {
        if chart.series.iter().all(|s| s.points.is_empty()) {
            bail!("{}: no points to plot", chart.file_stem);
        }
        let size = if chart.square { (900, 900) } else { (1100, 700) };
        if matches!(args.format, ImageFormat::Png | ImageFormat::Both) {
            let path = args.out.join(format!("{}.png", chart.file_stem));
            draw_chart(BitMapBackend::new(&path, size).into_drawing_area(), &chart)
                .with_context(|| format!("{}", path.display()))?;
            written.push(path);
        }
        if matches!(args.format, ImageFormat::Svg | ImageFormat::Both) {
            let path = args.out.join(format!("{}.svg", chart.file_stem));
            draw_chart(SVGBackend::new(&path, size).into_drawing_area(), &chart)
                .with_context(|| format!("{}", path.display()))?;
            written.push(path);
        }
    }
    for p in &written {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
