//! The laser's flash, fitted out of the quiet tread-temperature readings.
//!
//! The tread lasers read the surface plus a flash temperature that sliding heats and that
//! decays once sliding stops — over tenths of a second after lateral sliding, over seconds
//! after longitudinal sliding (the patch that slid comes round again before it has cooled).
//! Grip follows the surface and bulk, not the flash. When a test leaves only a few seconds
//! between sweeps (TTC runs: a 1.5 s free-rolling reference and a load change; an imported file
//! keeps only the sweeps), every quiet moment still carries tens of kelvin of flash, and a grip
//! temperature read from it follows the last sweep's sliding power, not the tyre's heating.
//!
//! The flash is modelled as the sliding power through a first-order lag, F = k·lag_τ(P) (P in
//! kW; the lag decays through times without samples, when the tyre rolled freely), and the
//! quiet readings as T = S(t) + F with S a slowly varying surface (piecewise linear, a knot
//! every 20 s). Per log, k and S come from linear least squares for each τ of a grid; the τ
//! that fits best wins. The quiet readings then lose k·lag_τ(P). A log without an evident flash
//! (the fit not clearly better than S alone, or k ≤ 0) keeps its readings as they are.

use nalgebra::{DMatrix, DVector};

/// Time constants tried for the flash's decay [s]: flash cools within a few revolutions, so
/// seconds at most; a slower decline of a quiet reading is the surface cooling, not flash.
const TAU_GRID_S: [f64; 14] = [0.15, 0.2, 0.3, 0.4, 0.5, 0.65, 0.8, 1.0, 1.25, 1.6, 2.0, 2.5, 3.2, 4.0];
/// Knot spacing of the surface temperature's piecewise-linear curve [s] (slow against flash).
const KNOT_S: f64 = 20.0;
/// Fewest quiet readings in a log for a flash fit.
const MIN_QUIET: usize = 50;
/// The flash must lower the residual sum of squares by this many noise variances (else the
/// quiet readings only drift: no flash to remove).
const MIN_GAIN: f64 = 100.0;

/// Quiet readings with the flash removed: `(series index, temperature)` in time order, and per
/// tyre (log) the fitted flash decay time constant (`None`: no flash evident, that log's quiet
/// readings as they are). Each log is fitted on its own: a cornering run's lateral flash and a
/// drive/brake run's longitudinal flash decay at different rates.
///
/// `power_w` is the sliding power per sample, `power_lp_w` its peak-following low-pass and
/// `quiet_power_w` the quiet threshold on it; `new_tyre` starts a log.
pub fn deflashed(
    t: &[f64],
    temp: &[f64],
    power_w: &[f64],
    power_lp_w: &[f64],
    quiet_power_w: f64,
    new_tyre: &[bool],
) -> (Vec<(usize, f64)>, Vec<Option<f64>>) {
    let n = t.len().min(temp.len()).min(power_w.len()).min(power_lp_w.len()).min(new_tyre.len());
    let mut starts: Vec<usize> = (0..n).filter(|&i| i == 0 || new_tyre[i]).collect();
    starts.push(n);
    let mut anchors = Vec::new();
    let mut taus = Vec::new();
    for w in starts.windows(2) {
        let quiet: Vec<usize> =
            (w[0]..w[1]).filter(|&i| temp[i].is_finite() && power_lp_w[i] < quiet_power_w).collect();
        match fit_flash(t, temp, power_w, w[0]..w[1], &quiet) {
            Some((tau, k, lag)) => {
                anchors.extend(quiet.iter().map(|&i| (i, temp[i] - k * lag[i - w[0]])));
                taus.push(Some(tau));
            }
            None => {
                anchors.extend(quiet.iter().map(|&i| (i, temp[i])));
                taus.push(None);
            }
        }
    }
    (anchors, taus)
}

/// Sliding power [kW] through a first-order lag of time constant `tau` over `range`; through a
/// time without samples it only decays.
fn lag_kw(t: &[f64], power_w: &[f64], range: std::ops::Range<usize>, tau: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(range.len());
    let mut y = 0.0;
    let first = range.start;
    for i in range {
        if i > first {
            let dt = (t[i] - t[i - 1]).max(0.0);
            let p = if power_w[i].is_finite() { power_w[i] * 1e-3 } else { 0.0 };
            y = y * (-dt / tau).exp() + (1.0 - (-dt.min(0.1) / tau).exp()) * p;
        }
        out.push(y);
    }
    out
}

/// Least squares of the quiet readings on the surface's hat functions (and `extra`, a last
/// column, when given): coefficients and residual sum of squares.
fn surface_fit(
    t: &[f64],
    temp: &[f64],
    quiet: &[usize],
    t0: f64,
    knots: usize,
    extra: Option<&[f64]>,
) -> Option<(DVector<f64>, f64)> {
    let m = knots + usize::from(extra.is_some());
    let mut ata = DMatrix::<f64>::zeros(m, m);
    let mut aty = DVector::<f64>::zeros(m);
    let row = |j: usize, i: usize| -> Vec<(usize, f64)> {
        let u = ((t[i] - t0) / KNOT_S).max(0.0);
        let k = (u.floor() as usize).min(knots - 2);
        let w = (u - k as f64).clamp(0.0, 1.0);
        let mut r = vec![(k, 1.0 - w), (k + 1, w)];
        if let Some(e) = extra {
            r.push((knots, e[j]));
        }
        r
    };
    for (j, &i) in quiet.iter().enumerate() {
        let r = row(j, i);
        for &(a, va) in &r {
            aty[a] += va * temp[i];
            for &(b, vb) in &r {
                ata[(a, b)] += va * vb;
            }
        }
    }
    // A knot with no quiet reading near it would be singular: a tiny ridge keeps it at zero
    // weight without moving the others.
    for d in 0..m {
        ata[(d, d)] += 1e-9 * (1.0 + ata[(d, d)]);
    }
    let c = ata.cholesky()?.solve(&aty);
    let sse = quiet
        .iter()
        .enumerate()
        .map(|(j, &i)| {
            let f: f64 = row(j, i).iter().map(|&(a, v)| c[a] * v).sum();
            (temp[i] - f).powi(2)
        })
        .sum();
    Some((c, sse))
}

/// The flash fit of one log: τ, the gain k [K/kW] and the lagged power over `range`, when a
/// flash is evident.
fn fit_flash(
    t: &[f64],
    temp: &[f64],
    power_w: &[f64],
    range: std::ops::Range<usize>,
    quiet: &[usize],
) -> Option<(f64, f64, Vec<f64>)> {
    if quiet.len() < MIN_QUIET || range.is_empty() {
        return None;
    }
    let t0 = t[range.start];
    let knots = (((t[range.end - 1] - t0) / KNOT_S).ceil() as usize + 1).max(2);
    let (_, sse0) = surface_fit(t, temp, quiet, t0, knots, None)?;
    let mut best: Option<(f64, f64, f64, Vec<f64>)> = None;
    for tau in TAU_GRID_S {
        let lag = lag_kw(t, power_w, range.clone(), tau);
        let at_quiet: Vec<f64> = quiet.iter().map(|&i| lag[i - range.start]).collect();
        let Some((c, sse)) = surface_fit(t, temp, quiet, t0, knots, Some(&at_quiet)) else { continue };
        if best.as_ref().is_none_or(|b| sse < b.1) {
            best = Some((tau, sse, c[knots], lag));
        }
    }
    let (tau, sse, k, lag) = best?;
    let var = sse / (quiet.len().saturating_sub(knots + 1).max(1)) as f64;
    (k > 0.0 && sse0 - sse > MIN_GAIN * var).then_some((tau, k, lag))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 50 Hz: 20 sweeps of 5 s with sliding power 3–6 kW, 3 s of free rolling between; the
    /// surface warms slowly; the lasers add a flash of 10 K/kW lagged by 2 s (or none), and
    /// ±0.2 K of deterministic "noise". Quiet: the free rolling.
    fn readings(flash: bool) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let dt = 0.02;
        let (mut t, mut temp, mut power, mut surface) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut f = 0.0;
        for k in 0..20 {
            for j in 0..400 {
                let time = (k * 400 + j) as f64 * dt;
                let p = if j < 250 { 3000.0 + 1000.0 * (k % 4) as f64 } else { 0.0 };
                f += (10.0 * p * 1e-3 - f) * (1.0 - (-dt / 2.0f64).exp());
                let ts = 40.0 + 30.0 * (1.0 - (-time / 100.0).exp());
                let noise = 0.2 * ((k * 400 + j) as f64 * 1.7).sin();
                t.push(time);
                power.push(p);
                surface.push(ts);
                temp.push(ts + if flash { f } else { 0.0 } + noise);
            }
        }
        (t, temp, power, surface)
    }

    /// Anchors, per-log τ, the readings and the true surface.
    type Run = (Vec<(usize, f64)>, Vec<Option<f64>>, Vec<f64>, Vec<f64>);

    fn run(flash: bool) -> Run {
        let (t, temp, power, surface) = readings(flash);
        // Quiet: no sliding for 0.5 s (the peak-following low-pass, simplified).
        let lp: Vec<f64> =
            (0..t.len()).map(|i| (i.saturating_sub(25)..=i).map(|j| power[j]).fold(0.0, f64::max)).collect();
        let nt = vec![false; t.len()];
        let (out, tau) = deflashed(&t, &temp, &power, &lp, 1500.0, &nt);
        (out, tau, temp, surface)
    }

    #[test]
    fn flash_is_found_and_removed() {
        let (out, tau, temp, surface) = run(true);
        let tau = tau[0].expect("a flash is found");
        assert!((tau - 2.0).abs() <= 0.5, "τ {tau}");
        let worst_raw = out.iter().map(|&(i, _)| (temp[i] - surface[i]).abs()).fold(0.0, f64::max);
        let worst = out.iter().map(|&(i, v)| (v - surface[i]).abs()).fold(0.0, f64::max);
        assert!(worst_raw > 20.0 && worst < 2.0, "flash left: {worst} K (raw {worst_raw} K)");
    }

    #[test]
    fn readings_without_flash_are_left_alone() {
        let (out, tau, temp, _) = run(false);
        assert_eq!(tau, vec![None], "a flash found in flash-free readings");
        assert!(!out.is_empty() && out.iter().all(|&(i, v)| v == temp[i]));
    }
}
