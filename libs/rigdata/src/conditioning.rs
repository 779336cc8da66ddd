//! Conditioning (warm-up) sweeps, left out of the fit by default and reported by `inspect`:
//! sweeps reaching only a fraction of their kind's typical reach (the rig's short conditioning
//! sweeps), and — in every kind of run — the sweeps opening a run or a pressure at one cell
//! that is swept again later (the tyre brought to temperature before the measurement proper;
//! a real drive/brake run opened with five full sweeps at 1,100 N).

use mffit::Cell;

use crate::sweeps::{Conditioning, Exclusion, FoundSweep, Swept};

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
