//! The laser's flash, fitted out of the quiet tread-temperature readings.
//!
//! The tread lasers read the surface plus a flash temperature that sliding heats and that
//! decays once sliding stops — over tenths of a second after lateral sliding, over seconds
//! after longitudinal sliding (the patch that slid comes round again before it has cooled).
//! Grip follows the surface and bulk, not the flash. When a test leaves only a few seconds
//! between sweeps (TTC runs: a 1.5 s free-rolling reference and a load change), every quiet
//! moment still carries tens of kelvin of flash, and a grip temperature read from it follows
//! the last sweep's sliding power instead of the tyre's heating.
//!
//! After sliding stops the reading is T(t) = Ts + A·exp(−(t − t0)/τ): the surface Ts (which
//! drifts slowly) plus the flash decaying. τ is one per log and found from the data: the value
//! on a grid that fits the first seconds of every quiet stretch best. Each stretch then gets
//! its own Ts and A (linear least squares) and its readings lose A·exp(−(t − t0)/τ).
//!
//! Only *strictly* quiet readings are used for this (sliding power below a third of the quiet
//! threshold: at a few hundred watts sliding still feeds the flash, and the decay model has no
//! source term). A stretch continues across a stretch of time without samples (an imported
//! measured file keeps only its sweeps; between them the tyre rolled freely), so the decay
//! after one sweep is seen at its end and at the start of the next. Without an evident decay
//! the quiet readings (the looser threshold) are used as they are.

/// Time constants tried for the flash's decay [s]: flash cools within a few revolutions, so
/// seconds at most; a slower decline of a quiet reading is the surface cooling, not flash.
const TAU_GRID_S: [f64; 14] = [0.15, 0.2, 0.3, 0.4, 0.5, 0.65, 0.8, 1.0, 1.25, 1.6, 2.0, 2.5, 3.2, 4.0];
/// Only the first seconds of a quiet stretch are fitted (later the surface's own cooling
/// dominates the reading) [s].
const FIT_WINDOW_S: f64 = 6.0;
/// Stretches shorter than this take no part in finding τ [s].
const MIN_STRETCH_FOR_TAU_S: f64 = 1.0;
/// Fewest stretches for a τ to be trusted.
const MIN_STRETCHES: usize = 3;
/// The decay must leave at most (1 − this) of what a straight line through each stretch's
/// window leaves for a correction to be made (else the readings only drift: no flash).
const MIN_EXPLAINED: f64 = 0.5;
/// A time without samples longer than this ends a stretch [s]; shorter ones (an imported
/// file's free rolling between sweeps) do not.
const MAX_GAP_S: f64 = 30.0;
/// Strictly quiet: sliding power below this share of the quiet threshold.
const STRICT_SHARE: f64 = 1.0 / 3.0;

/// One quiet stretch: indices into the series, consecutive in time.
struct Stretch<'a> {
    idx: &'a [usize],
}

/// Least-squares (Ts, A) of T = Ts + A·exp(−x/τ) over `x`, `y`; with the residual sum of squares.
fn fit_decay(x: &[f64], y: &[f64], tau: f64) -> Option<(f64, f64, f64)> {
    let n = x.len() as f64;
    if x.len() < 3 {
        return None;
    }
    let e: Vec<f64> = x.iter().map(|&v| (-v / tau).exp()).collect();
    let (se, see, sy, sey) = e.iter().zip(y).fold((0.0, 0.0, 0.0, 0.0), |(a, b, c, d), (&ei, &yi)| {
        (a + ei, b + ei * ei, c + yi, d + ei * yi)
    });
    let det = n * see - se * se;
    if det.abs() < 1e-12 * n * n {
        return None;
    }
    let amp = (n * sey - se * sy) / det;
    let ts = (sy - amp * se) / n;
    let sse = e.iter().zip(y).map(|(&ei, &yi)| (yi - ts - amp * ei).powi(2)).sum();
    Some((ts, amp, sse))
}

/// Residual sum of squares of the least-squares line through `x`, `y`.
fn line_sse(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (sxx, sxy) = x.iter().zip(y).fold((0.0, 0.0), |(a, b), (&xi, &yi)| (a + (xi - mx).powi(2), b + (xi - mx) * (yi - my)));
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    x.iter().zip(y).map(|(&xi, &yi)| (yi - my - slope * (xi - mx)).powi(2)).sum()
}

impl Stretch<'_> {
    fn duration(&self, t: &[f64]) -> f64 {
        t[self.idx[self.idx.len() - 1]] - t[self.idx[0]]
    }

    /// Offsets from the stretch's start and readings over the fit window.
    fn window(&self, t: &[f64], temp: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let t0 = t[self.idx[0]];
        self.idx.iter().map(|&i| (t[i] - t0, temp[i])).take_while(|(x, _)| *x <= FIT_WINDOW_S).unzip()
    }
}

/// Quiet readings with the flash's decay removed: `(series index, temperature)` in time order,
/// and the fitted decay time constant (`None`: no decay evident, quiet readings as they are).
///
/// `power_lp_w` is the peak-following low-passed sliding power per sample, `quiet_power_w` the
/// quiet threshold on it; a stretch also ends at a new tyre.
pub fn deflashed(
    t: &[f64],
    temp: &[f64],
    power_lp_w: &[f64],
    quiet_power_w: f64,
    new_tyre: &[bool],
) -> (Vec<(usize, f64)>, Option<f64>) {
    let n = t.len().min(temp.len()).min(power_lp_w.len()).min(new_tyre.len());
    let quiet_below = |i: usize, p: f64| temp[i].is_finite() && power_lp_w[i] < p;
    let raw = || (0..n).filter(|&i| quiet_below(i, quiet_power_w)).map(|i| (i, temp[i])).collect::<Vec<_>>();
    let strict: Vec<usize> = (0..n).filter(|&i| quiet_below(i, STRICT_SHARE * quiet_power_w)).collect();
    let mut stretches = Vec::new();
    let mut start = 0usize;
    for j in 1..=strict.len() {
        let ends = j == strict.len()
            || strict[j] != strict[j - 1] + 1
            || t[strict[j]] - t[strict[j - 1]] > MAX_GAP_S
            || new_tyre[strict[j]];
        if ends {
            stretches.push(Stretch { idx: &strict[start..j] });
            start = j;
        }
    }
    // τ: the grid value with the least residual over the long-enough stretches' windows.
    let long: Vec<(Vec<f64>, Vec<f64>)> = stretches
        .iter()
        .filter(|s| s.duration(t) >= MIN_STRETCH_FOR_TAU_S)
        .map(|s| s.window(t, temp))
        .filter(|(x, _)| x.len() >= 5)
        .collect();
    if long.len() < MIN_STRETCHES {
        return (raw(), None);
    }
    // What a straight line (the surface drifting) leaves: the decay must do much better.
    let drift: f64 = long.iter().map(|(x, y)| line_sse(x, y)).sum();
    let best = TAU_GRID_S
        .iter()
        .map(|&tau| {
            let sse: f64 = long.iter().map(|(x, y)| fit_decay(x, y, tau).map_or(f64::INFINITY, |f| f.2)).sum();
            (tau, sse)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let Some((tau, sse)) = best else { return (raw(), None) };
    if !sse.is_finite() || sse > (1.0 - MIN_EXPLAINED) * drift {
        return (raw(), None);
    }
    // Each stretch: its own surface and flash amplitude. A stretch too short to tell the two
    // apart is dropped (its readings are mostly flash); a negative amplitude (the reading
    // rises while quiet) is no flash and is left alone.
    let mut out = Vec::with_capacity(strict.len());
    for s in &stretches {
        let (x, y) = s.window(t, temp);
        if x.len() < 5 || x[x.len() - 1] < 0.5 * tau {
            continue;
        }
        let amp = fit_decay(&x, &y, tau).map_or(0.0, |f| f.1.max(0.0));
        let t0 = t[s.idx[0]];
        out.extend(s.idx.iter().map(|&i| (i, temp[i] - amp * (-(t[i] - t0) / tau).exp())));
    }
    if out.is_empty() { (raw(), None) } else { (out, Some(tau)) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Surface heating slowly; after each of 12 sweeps the flash (20–40 K) decays with τ = 2 s
    /// over a 3 s pause; then sliding again.
    fn readings(tau: f64, flash: bool) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<usize>, Vec<f64>) {
        let dt = 0.02;
        let (mut t, mut temp, mut power, mut quiet, mut surface) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for k in 0..12 {
            let amp = if flash { 20.0 + 20.0 * ((k % 4) as f64 / 3.0) } else { 0.0 };
            for j in 0..400 {
                let time = (k * 400 + j) as f64 * dt;
                let ts = 40.0 + 0.5 * time;
                let in_pause = j >= 250;
                let x = (j as f64 - 250.0) * dt;
                let f = if in_pause { amp * (-x / tau).exp() } else { amp };
                // Deterministic "noise" of ±0.2 K.
                let noise = 0.2 * ((k * 400 + j) as f64 * 1.7).sin();
                if in_pause {
                    quiet.push(t.len());
                }
                power.push(if in_pause { 0.0 } else { 5000.0 });
                t.push(time);
                temp.push(ts + f + noise);
                surface.push(ts);
            }
        }
        (t, temp, power, quiet, surface)
    }

    #[test]
    fn flash_decay_is_found_and_removed() {
        let (t, temp, power, quiet, surface) = readings(2.0, true);
        let nt = vec![false; t.len()];
        let (out, tau) = deflashed(&t, &temp, &power, 1500.0, &nt);
        let tau = tau.expect("a decay is found");
        assert!((tau - 2.0).abs() <= 0.3, "τ {tau}");
        let worst_raw = quiet.iter().map(|&i| (temp[i] - surface[i]).abs()).fold(0.0, f64::max);
        let worst = out.iter().map(|&(i, v)| (v - surface[i]).abs()).fold(0.0, f64::max);
        assert!(worst_raw > 20.0 && worst < 3.0, "flash left: {worst} K (raw {worst_raw} K)");
    }

    #[test]
    fn readings_without_flash_are_left_alone() {
        let (t, temp, power, quiet, _) = readings(2.0, false);
        let nt = vec![false; t.len()];
        let (out, tau) = deflashed(&t, &temp, &power, 1500.0, &nt);
        assert!(tau.is_none(), "τ {tau:?} found in flash-free readings");
        assert_eq!(out.len(), quiet.len());
        assert!(out.iter().all(|&(i, v)| v == temp[i]));
    }
}
