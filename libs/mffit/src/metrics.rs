//! Goodness of fit per stage and channel, overall and grouped by load, pressure and camber.

use mftyre::TyreParams;
use serde::Serialize;

use crate::engine::Point;
use crate::stages::StageData;

/// Fit statistics of one channel over one group of points.
#[derive(Debug, Clone, Serialize)]
pub struct Metrics {
    /// Stage name.
    pub stage: String,
    /// Channel (`FY`, `MZ`, …).
    pub channel: String,
    /// Group: `all`, `Fz 1.00·Fz0`, `p 2.6 bar`, `IA 0 deg`.
    pub group: String,
    /// Points.
    pub points: usize,
    /// Root-mean-square error, channel units.
    pub rmse: f64,
    /// RMSE in % of the group's peak |measured|.
    pub nrmse_pct: f64,
    /// Mean error (model − measured).
    pub bias: f64,
    /// Largest |error|.
    pub max_err: f64,
    /// Coefficient of determination.
    pub r2: f64,
}

/// Statistics of `model` against `points` of the stage's channel.
pub fn compute(
    stage: &str,
    channel: &str,
    group: &str,
    params: &TyreParams,
    data: &StageData,
    points: &[&Point],
) -> Metrics {
    let n = points.len();
    let mut se = 0.0;
    let mut sum_e = 0.0;
    let mut max_e: f64 = 0.0;
    let mut peak: f64 = 0.0;
    let mean = points.iter().map(|p| p.measured).sum::<f64>() / n.max(1) as f64;
    let mut ss_tot = 0.0;
    for p in points {
        let e = data.channel.eval(params, &p.input) - p.measured;
        se += e * e;
        sum_e += e;
        max_e = max_e.max(e.abs());
        peak = peak.max(p.measured.abs());
        ss_tot += (p.measured - mean) * (p.measured - mean);
    }
    let rmse = (se / n.max(1) as f64).sqrt();
    Metrics {
        stage: stage.to_owned(),
        channel: channel.to_owned(),
        group: group.to_owned(),
        points: n,
        rmse,
        nrmse_pct: 100.0 * rmse / peak.max(1e-12),
        bias: sum_e / n.max(1) as f64,
        max_err: max_e,
        r2: if ss_tot > 0.0 { 1.0 - se / ss_tot } else { f64::NAN },
    }
}

/// Load group label of a point: the load factor to the nearest 0.25·Fz0.
pub fn load_group(p: &Point, fz0: f64) -> String {
    format!("Fz {:.2}·Fz0", (p.input.fz_n / fz0 * 4.0).round() / 4.0)
}

/// Pressure group label: to the nearest 0.1 bar.
pub fn pressure_group(p: &Point) -> String {
    format!("p {:.1} bar", (p.input.p_pa / 1e4).round() / 10.0)
}

/// Camber group label: to the nearest degree.
pub fn camber_group(p: &Point) -> String {
    let g = p.input.gamma_rad.to_degrees().round();
    format!("IA {} deg", if g == 0.0 { 0.0 } else { g })
}

/// Every stage's statistics: overall first, then by load, pressure and camber.
pub fn all(params: &TyreParams, data: &[StageData], fz0: f64) -> Vec<Metrics> {
    let mut out = Vec::new();
    for d in data.iter().filter(|d| !d.points.is_empty()) {
        let ch = d.channel.name();
        let refs: Vec<&Point> = d.points.iter().collect();
        out.push(compute(&d.stage, ch, "all", params, d, &refs));
        type Grouper<'a> = Box<dyn Fn(&Point) -> String + 'a>;
        let groupers: [Grouper; 3] =
            [Box::new(|p| load_group(p, fz0)), Box::new(pressure_group), Box::new(camber_group)];
        for g in groupers.iter() {
            let mut labels: Vec<String> = d.points.iter().map(g).collect();
            labels.sort();
            labels.dedup();
            if labels.len() < 2 {
                continue;
            }
            for l in labels {
                let pts: Vec<&Point> = d.points.iter().filter(|p| g(p) == l).collect();
                if pts.len() >= 5 {
                    out.push(compute(&d.stage, ch, &l, params, d, &pts));
                }
            }
        }
    }
    out
}
