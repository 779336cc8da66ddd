//! Plots of the brush tyres' curves and of the shapes that set them apart from a Magic Formula
//! (docs/brush-tyre.md shows them): lateral force and aligning moment against slip angle at
//! four loads, the friction coefficient against load beside the best law MF-Tyre 6.1 can
//! write (linear in dfz), and the lateral force at three belt speeds.
//!
//! ```text
//! cargo run --release -p rigsim --example brush_curves -- docs/img/brush [--png]
//! ```

use std::path::{Path, PathBuf};

use plotters::prelude::*;
use rigsim::{BrushInput, BrushParams};

/// A labelled series of (x, y), drawn as dots (`true`) or a line.
type Series = (String, Vec<(f64, f64)>, bool);

/// One chart: title, axis labels, labelled series.
struct Chart {
    file: String,
    title: String,
    x: &'static str,
    y: &'static str,
    series: Vec<Series>,
}

const COLOURS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

fn draw(dir: &Path, c: &Chart, png: bool) -> Result<PathBuf, Box<dyn std::error::Error>> {
    let path = dir.join(format!("{}.{}", c.file, if png { "png" } else { "svg" }));
    if png {
        plot(BitMapBackend::new(&path, (900, 560)).into_drawing_area(), c)?;
    } else {
        plot(SVGBackend::new(&path, (900, 560)).into_drawing_area(), c)?;
    }
    Ok(path)
}

fn plot<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    c: &Chart,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let pts = c.series.iter().flat_map(|s| s.1.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let pad = 0.05 * (y1 - y0).max(1e-9);
    let mut ch = ChartBuilder::on(&root)
        .caption(&c.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))?;
    ch.configure_mesh().x_desc(c.x).y_desc(c.y).light_line_style(RGBColor(235, 235, 235)).draw()?;
    for (i, (label, points, dots)) in c.series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        if *dots {
            ch.draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))?
                .label(label.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
        } else {
            ch.draw_series(LineSeries::new(points.iter().copied(), colour.stroke_width(2)))?
                .label(label.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
        }
    }
    ch.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK.mix(0.4)).draw()?;
    root.present()?;
    Ok(())
}

fn eval(p: &BrushParams, fz: f64, alpha_deg: f64, vx: f64) -> mftyre::MfOutput {
    p.evaluate(&BrushInput::new(fz, 0.0, alpha_deg.to_radians(), vx))
}

fn charts(tag: &str, p: &BrushParams) -> Vec<Chart> {
    let fz0 = p.nominal.load_n;
    let v0 = p.nominal.speed_mps;
    let loads = [0.2, 0.6, 1.0, 1.4];
    let sweep = |f: &dyn Fn(f64) -> f64| (0..=150).map(|k| 0.1 * f64::from(k)).map(|a| (a, f(a))).collect::<Vec<_>>();
    let fy = Chart {
        file: format!("{tag}_fy"),
        title: format!("{}: FY (ISO-W) vs slip angle, {v0} m/s", p.name),
        x: "slip angle [deg]",
        y: "FY [N]",
        series: loads
            .iter()
            .map(|r| (format!("Fz {:.0} N", r * fz0), sweep(&|a| eval(p, r * fz0, a, v0).fy_n), false))
            .collect(),
    };
    let mz = Chart {
        file: format!("{tag}_mz"),
        title: format!("{}: MZ vs slip angle (sign change before full sliding)", p.name),
        x: "slip angle [deg]",
        y: "MZ [N m]",
        series: loads
            .iter()
            .map(|r| (format!("Fz {:.0} N", r * fz0), sweep(&|a| eval(p, r * fz0, a, v0).mz_nm), false))
            .collect(),
    };
    let speed = Chart {
        file: format!("{tag}_speed"),
        title: format!("{}: FY at Fz0 and three belt speeds (friction falls with sliding speed)", p.name),
        x: "slip angle [deg]",
        y: "FY [N]",
        series: [5.0, 11.1, 25.0]
            .iter()
            .map(|v| (format!("{v} m/s"), sweep(&|a| eval(p, fz0, a, *v).fy_n), false))
            .collect(),
    };
    // Static friction (standstill, full sliding) against load, and the best straight line in
    // dfz through it: MF-Tyre 6.1's μ = PDY1·(1 + PDY2·dfz) at one pressure and zero camber.
    let ratios: Vec<f64> = (0..=12).map(|k| 0.2 + 0.15 * f64::from(k)).collect();
    let mu: Vec<(f64, f64)> = ratios.iter().map(|r| (*r, eval(p, r * fz0, 40.0, 0.0).fy_n.abs() / (r * fz0))).collect();
    let n = mu.len() as f64;
    let (sx, sy) = mu.iter().fold((0.0, 0.0), |a, (x, y)| (a.0 + (x - 1.0), a.1 + y));
    let sxx = mu.iter().map(|(x, _)| (x - 1.0) * (x - 1.0)).sum::<f64>();
    let sxy = mu.iter().map(|(x, y)| (x - 1.0) * y).sum::<f64>();
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let icpt = (sy - slope * sx) / n;
    let line: Vec<(f64, f64)> = ratios.iter().map(|r| (*r, icpt + slope * (r - 1.0))).collect();
    let load = Chart {
        file: format!("{tag}_mu_load"),
        title: format!("{}: friction vs load, power law vs the best MF-form line", p.name),
        x: "Fz / Fz0",
        y: "mu_y (static)",
        series: vec![
            ("brush: mu0 (Fz/Fz0)^-n".to_owned(), mu, true),
            (format!("best PDY1 (1 + PDY2 dfz): PDY1 {icpt:.3}, PDY2 {:.3}", slope / icpt), line, false),
        ],
    };
    vec![fy, mz, speed, load]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/brush_curves".into()));
    // `--png` for bitmaps instead of SVG.
    let png = std::env::args().any(|a| a == "--png");
    std::fs::create_dir_all(&dir)?;
    let tyres = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres");
    for (tag, file) in [("race", "brush_race.toml"), ("road", "brush_road.toml")] {
        let p = BrushParams::load(&tyres.join(file))?;
        for c in charts(tag, &p) {
            eprintln!("wrote {}", draw(&dir, &c, png)?.display());
        }
    }
    Ok(())
}
