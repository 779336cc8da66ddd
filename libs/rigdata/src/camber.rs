//! Camber sweeps: the camber stepped through several levels (e.g. 0–4° in 1° steps) at a held
//! slip angle, load and pressure, with the wheel rolling free. Real cornering/camber runs of some
//! rounds have them; each is one sweep of free-rolling data at several cambers, which the fitter
//! takes with its cornering data (the camber terms). Anywhere else a camber change is a change
//! of cell, and its rows are excluded as such.

use crate::interpret::{KappaSource, Signals};
use crate::sweeps::{Exclusion, SweepOptions, median_of};

/// Fewest distinct held camber levels that make a camber sweep: two are one change of cell.
const MIN_LEVELS: usize = 3;
/// Held camber levels closer than this are one level, deg.
const LEVEL_STEP_DEG: f64 = 0.5;
/// The slip angle of a camber sweep stays within this range, deg.
const HELD_SA_RANGE_DEG: f64 = 1.0;

/// Row ranges (inclusive) of the camber sweeps: stretches with nothing excluded yet (`why`),
/// the slip angle not sweeping, the wheel not driven or braked, and the camber held at
/// [`MIN_LEVELS`] or more levels spanning at least [`SweepOptions::camber_sweep_min_deg`].
pub fn find_camber_sweeps(
    sig: &Signals,
    why: &[Option<Exclusion>],
    sa_sweeping: &[bool],
    camber_moving: &[bool],
    kappa_source: KappaSource,
    w: usize,
    opt: &SweepOptions,
) -> Vec<(usize, usize)> {
    let n = why.len();
    let free = |i: usize| why[i].is_none() && !sa_sweeping[i];
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        if !free(i) {
            i += 1;
            continue;
        }
        let a = i;
        while i < n && free(i) {
            i += 1;
        }
        if is_camber_sweep(sig, a, i, camber_moving, kappa_source, w, opt) {
            out.push((a, i - 1));
        }
    }
    out
}

fn is_camber_sweep(
    sig: &Signals,
    a: usize,
    b: usize,
    camber_moving: &[bool],
    kappa_source: KappaSource,
    w: usize,
    opt: &SweepOptions,
) -> bool {
    if b - a < 4 * w {
        return false;
    }
    let levels = held_levels(&sig.gamma_rad, a, b, camber_moving, w);
    let (lo, hi) = levels.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), l| (lo.min(*l), hi.max(*l)));
    if levels.len() < MIN_LEVELS || (hi - lo).to_degrees() < opt.camber_sweep_min_deg {
        return false;
    }
    // The slip angle held.
    let mut sa: Vec<f64> = sig.alpha_rad[a..b].iter().map(|x| x.to_degrees()).filter(|x| x.is_finite()).collect();
    sa.sort_by(f64::total_cmp);
    if sa.is_empty() || sa[sa.len() * 95 / 100] - sa[sa.len() * 5 / 100] > HELD_SA_RANGE_DEG {
        return false;
    }
    // The wheel rolling free: no slip-ratio sweep, no drive or brake force.
    let driven = (a..b).filter(|&r| sig.fx_n[r].abs() > opt.sr_driven_fx_fraction * sig.fz_n[r].abs()).count();
    let slipping = kappa_source == KappaSource::LoadedRadius
        && (a..b).filter(|&r| sig.kappa[r].abs() > opt.kappa_on).count() * 20 > b - a;
    driven * 10 < b - a && !slipping
}

/// The distinct camber levels held for at least `w` rows within `a..b`, rad.
fn held_levels(gamma: &[f64], a: usize, b: usize, moving: &[bool], w: usize) -> Vec<f64> {
    let mut levels: Vec<f64> = Vec::new();
    let mut k = a;
    while k < b {
        if moving[k] {
            k += 1;
            continue;
        }
        let s = k;
        while k < b && !moving[k] {
            k += 1;
        }
        if k - s < w {
            continue;
        }
        let m = median_of(gamma[s..k].iter().copied());
        if m.is_finite() && levels.iter().all(|l| (l - m).abs().to_degrees() > LEVEL_STEP_DEG) {
            levels.push(m);
        }
    }
    levels
}
