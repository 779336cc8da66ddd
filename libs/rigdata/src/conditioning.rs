//! Conditioning (warm-up) sweeps, left out of the fit by default and reported by `inspect`:
//! sweeps reaching only a fraction of their kind's typical reach (the rig's short conditioning
//! sweeps), and — in every kind of run — the sweeps opening a run or a pressure at one cell
//! that is swept again later (the tyre brought to temperature before the measurement proper;
//! a real drive/brake run opened with five full sweeps at 1,100 N), and the sweeps a run opens
//! with on a cold tyre whose cells are swept again once the tread temperature has settled.

use mffit::Cell;

use crate::interpret::Signals;
use crate::sweeps::{Conditioning, Exclusion, FoundSweep, Swept, median_of};

/// Two sweeps were run at the same cell (within what a rig holds between repeats).
pub fn same_cell(a: &Cell, b: &Cell) -> bool {
    let near = |x: f64, y: f64, tol: f64| (x - y).abs() <= tol || (x.is_nan() && y.is_nan());
    a.kind == b.kind
        && near(a.fz_n, b.fz_n, (0.05 * a.fz_n.abs()).max(50.0))
        && near(a.p_pa, b.p_pa, 5_000.0)
        && near(a.gamma_rad, b.gamma_rad, 0.5_f64.to_radians())
        && near(a.alpha_rad, b.alpha_rad, 0.5_f64.to_radians())
        && near(a.vx_mps, b.vx_mps, 1.0)
}

/// The typical reach of a family of sweeps: the 75th percentile; `None` with fewer than two.
pub fn typical_reach(mut reach: Vec<f64>) -> Option<f64> {
    if reach.len() < 2 {
        return None;
    }
    reach.sort_by(f64::total_cmp);
    Some(reach[(reach.len() - 1) * 3 / 4])
}

/// Sweeps reaching less than `fraction` of their family's typical reach (slip-angle sweeps
/// among themselves, slip-ratio sweeps among themselves; camber sweeps never) are conditioning.
pub fn mark_short_reach(sweeps: &mut [FoundSweep], fraction: f64) {
    for family in [Swept::SlipAngle, Swept::SlipRatio] {
        let reach: Vec<f64> = sweeps.iter().filter(|s| s.swept == family).map(|s| s.cell.slip_reach).collect();
        let Some(typical) = typical_reach(reach) else { continue };
        for s in sweeps.iter_mut().filter(|s| s.swept == family) {
            s.conditioning = (s.cell.slip_reach < fraction * typical).then_some(Conditioning::ShortReach);
        }
    }
}

/// Conditioning sweeps that follow each other at one cell, with only rolling (or the slip angle
/// settling) between them, are one warm-up.
pub fn merge_conditioning(sweeps: Vec<FoundSweep>, why: &[Option<Exclusion>]) -> Vec<FoundSweep> {
    let mut out: Vec<FoundSweep> = Vec::with_capacity(sweeps.len());
    for s in sweeps {
        if let Some(p) = out.last_mut()
            && p.conditioning.is_some()
            && s.conditioning.is_some()
            && p.swept == s.swept
            && p.cell.kind == s.cell.kind
            && (p.cell.fz_n - s.cell.fz_n).abs() <= (0.05 * p.cell.fz_n.abs()).max(50.0)
            && (p.cell.p_pa - s.cell.p_pa).abs() <= 5_000.0
            && (p.cell.gamma_rad - s.cell.gamma_rad).abs() <= 0.5_f64.to_radians()
            && why.get(p.last + 1..s.first).is_some_and(|gap| {
                gap.iter().all(|w| matches!(w, None | Some(Exclusion::Idle | Exclusion::SlipAngleChange)))
            })
        {
            p.last = s.last;
            p.cell.slip_reach = p.cell.slip_reach.max(s.cell.slip_reach);
            continue;
        }
        out.push(s);
    }
    out
}

/// Fewest full sweeps at the opening cell that make a warm-up: one sweep at a cell repeated at
/// the end of a run is the plan's first measurement and its repeat, not a warm-up.
const MIN_LEADING: usize = 2;

/// In each block of one pressure (a run, or each pressure of a cornering run), the sweeps that
/// open it at one cell — at least [`MIN_LEADING`] of them besides short conditioning ones — are
/// conditioning when that cell is swept again after a sweep at another cell.
pub fn mark_leading_repeats(sweeps: &mut [FoundSweep]) {
    let mut start = 0;
    while start < sweeps.len() {
        let p0 = sweeps[start].cell.p_pa;
        let mut end = start;
        while end < sweeps.len() && ((sweeps[end].cell.p_pa - p0).abs() <= 5_000.0 || p0.is_nan()) {
            end += 1;
        }
        mark_block(&mut sweeps[start..end]);
        start = end.max(start + 1);
    }
}

fn mark_block(block: &mut [FoundSweep]) {
    let Some(first) = block.iter().position(|s| s.swept != Swept::Camber) else { return };
    let cell = block[first].cell;
    let lead_end =
        block[first..].iter().position(|s| !same_cell(&s.cell, &cell)).map(|k| first + k).unwrap_or(block.len());
    let full = block[first..lead_end].iter().filter(|s| s.conditioning.is_none()).count();
    let again = block[lead_end..].iter().any(|s| same_cell(&s.cell, &cell) && s.conditioning.is_none());
    if full >= MIN_LEADING && again {
        for s in &mut block[first..lead_end] {
            s.conditioning.get_or_insert(Conditioning::LeadingRepeat);
        }
    }
}

/// The tread has settled when the temperature at a sweep's start is less than this above the
/// previous sweep's, K: a cold tyre gains tens of kelvin over its first sweeps, a settled one a
/// few (a drive/brake run climbing 38 → 90 °C over some sixty sweeps gains about one a sweep).
pub const SETTLED_RISE_K: f64 = 5.0;

/// A sweep begun this far below its run's typical start temperature is cold, K; a smaller gap is
/// the ordinary spread between cells (a sweep after a 1,540 N one starts a few kelvin warmer).
pub const COLD_BELOW_RUN_K: f64 = 8.0;

/// Most sweeps a cold start may take: beyond them the run is heating up, not settling.
const MAX_COLD_START: usize = 6;

/// The tread temperature as each sweep begins, °C: the median over its first rows (a twentieth
/// of the sweep, at least five) of the mean of the inner, centre and outer readings present;
/// NaN where the file has none.
pub fn start_tread_temps(sig: &Signals, sweeps: &[FoundSweep]) -> Vec<f64> {
    let tread = |r: usize| {
        let t: Vec<f64> = [&sig.temp_inner_c, &sig.temp_centre_c, &sig.temp_outer_c]
            .iter()
            .filter_map(|c| c.get(r).copied())
            .filter(|x| x.is_finite())
            .collect();
        if t.is_empty() { f64::NAN } else { t.iter().sum::<f64>() / t.len() as f64 }
    };
    sweeps
        .iter()
        .map(|s| {
            let rows = (s.last + 1 - s.first).div_ceil(20).max(5);
            median_of((s.first..=s.last.min(s.first + rows - 1)).map(tread))
        })
        .collect()
}

/// The sweeps a run opens with while the tread is still warming fast — each starting more than
/// [`SETTLED_RISE_K`] below the next and more than [`COLD_BELOW_RUN_K`] below the run's median
/// start, the warming then settling within [`MAX_COLD_START`] sweeps — are conditioning where
/// their cell is swept again after the tread settled: nothing of the plan is lost, and what a
/// cold tyre measured is not fitted as the tyre.
pub fn mark_cold_start(sweeps: &mut [FoundSweep]) {
    let start_c: Vec<f64> = sweeps.iter().map(|s| s.tread_start_c).collect();
    let order: Vec<usize> =
        (0..sweeps.len()).filter(|&i| sweeps[i].conditioning.is_none() && start_c[i].is_finite()).collect();
    if order.len() < 3 {
        return;
    }
    let run_c = median_of(order.iter().map(|&i| start_c[i]));
    let rise = |w: &[usize]| start_c[w[1]] - start_c[w[0]];
    let cold =
        order.windows(2).take_while(|w| rise(w) > SETTLED_RISE_K && start_c[w[0]] < run_c - COLD_BELOW_RUN_K).count();
    // A cold start settles: the rise after it is small. A run heating at that pace throughout
    // (a pure longitudinal run to large slip gains 7 K a sweep) has no cold start, it runs hot.
    let settles = order.windows(2).nth(cold).is_some_and(|w| rise(w) <= SETTLED_RISE_K);
    if cold > MAX_COLD_START || !settles {
        return;
    }
    for k in 0..cold {
        let i = order[k];
        let settled_again = order[cold..]
            .iter()
            .any(|&m| sweeps[m].swept == sweeps[i].swept && same_cell(&sweeps[m].cell, &sweeps[i].cell));
        if settled_again {
            sweeps[i].conditioning = Some(Conditioning::ColdStart);
        }
    }
}
