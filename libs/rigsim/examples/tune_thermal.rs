//! How the thermal parameters in `launch-config/virtual_rig.toml` were found: a Nelder–Mead
//! search (log-parameters, fractions through a logistic) minimising the squared, tolerance-
//! normalised misses of the six peak temperatures (±10 %), six sweep + cool-down times (±20 %)
//! of Tables 3.6.2-H/I and the warm-up (31 °C after block 1, 42 °C after block 2), plus a
//! penalty for every rank the thesis's columns do not share.
//!
//! `cargo run --release -p rigsim --example tune_thermal [evaluations] [longitudinal]`
//!
//! The figures are the mean over seeds 0–2 ([`SEEDS`]) and a miss is penalised steeply beyond
//! [`MARGIN`] of its tolerance, leaving room for the seed-to-seed spread (the acceptance test
//! requires every seed 0..=9 to pass). With `longitudinal` only the four parameters of the
//! longitudinal (PX) heat path are searched, against the BrkDrv figures alone: no FreeRolling
//! sweep and no warm-up uses them. History: the full search was run once (single seed, hinge at
//! 90 %, cool-downs ended by a 0.1 s mean, the BrkDrv variable time left out); after the
//! calibration switched to the thermal gate's release rule and to all seeds, the
//! `longitudinal` search (120 evaluations) set the four longitudinal values the config holds.

use std::path::PathBuf;

use rigsim::calibration::{
    SweepKind, THESIS_BRKDRV, THESIS_FREEROLLING, brkdrv_setup, comparison_sweep, freerolling_setup,
    preconditioned_rig, run_warmup,
};
use rigsim::{RigConfig, TyreParams, VirtualRig};

const NAMES: [&str; 16] = [
    "surface_heat_capacity_j_per_k",
    "bulk_heat_capacity_j_per_k",
    "surface_bulk_conductance_w_per_k",
    "convection_w_per_k",
    "convection_speed_w_per_k",
    "belt_contact_w_per_k",
    "bulk_to_air_w_per_k",
    "surface_fraction_lateral",
    "surface_fraction_longitudinal",
    "rolling_loss_coefficient",
    "flash_lateral_k_per_kw",
    "flash_longitudinal_k_per_kw",
    "flash_time_constant_s",
    "flash_longitudinal_time_constant_s",
    "tyre_fraction_lateral (surface + bulk)",
    "tyre_fraction_longitudinal (surface + bulk)",
];

/// The longitudinal heat path: surface share, flash gain and time constant, tyre share.
const LONGITUDINAL: [usize; 4] = [8, 11, 13, 15];

/// Indices 7/8 are the surface's share of the heat entering the tyre, 14/15 the share of the
/// sliding power entering the tyre at all (the rest heats the belt).
fn is_fraction(i: usize) -> bool {
    i == 7 || i == 8 || i == 14 || i == 15
}

fn get(cfg: &RigConfig) -> Vec<f64> {
    let t = &cfg.thermal;
    vec![
        t.surface_heat_capacity_j_per_k,
        t.bulk_heat_capacity_j_per_k,
        t.surface_bulk_conductance_w_per_k,
        t.convection_w_per_k,
        t.convection_speed_w_per_k,
        t.belt_contact_w_per_k,
        t.bulk_to_air_w_per_k,
        t.surface_fraction_lateral / (t.surface_fraction_lateral + t.bulk_fraction_lateral),
        t.surface_fraction_longitudinal / (t.surface_fraction_longitudinal + t.bulk_fraction_longitudinal),
        t.rolling_loss_coefficient,
        t.flash_lateral_k_per_kw,
        t.flash_longitudinal_k_per_kw,
        t.flash_time_constant_s,
        t.flash_longitudinal_time_constant_s,
        t.surface_fraction_lateral + t.bulk_fraction_lateral,
        t.surface_fraction_longitudinal + t.bulk_fraction_longitudinal,
    ]
}

fn set(cfg: &mut RigConfig, v: &[f64]) {
    let t = &mut cfg.thermal;
    t.surface_heat_capacity_j_per_k = v[0];
    t.bulk_heat_capacity_j_per_k = v[1];
    t.surface_bulk_conductance_w_per_k = v[2];
    t.convection_w_per_k = v[3];
    t.convection_speed_w_per_k = v[4];
    t.belt_contact_w_per_k = v[5];
    t.bulk_to_air_w_per_k = v[6];
    t.surface_fraction_lateral = v[7] * v[14];
    t.bulk_fraction_lateral = (1.0 - v[7]) * v[14];
    t.surface_fraction_longitudinal = v[8] * v[15];
    t.bulk_fraction_longitudinal = (1.0 - v[8]) * v[15];
    t.rolling_loss_coefficient = v[9];
    t.flash_lateral_k_per_kw = v[10];
    t.flash_longitudinal_k_per_kw = v[11];
    t.flash_time_constant_s = v[12];
    t.flash_longitudinal_time_constant_s = v[13];
}

fn to_x(v: &[f64]) -> Vec<f64> {
    v.iter()
        .enumerate()
        .map(
            |(i, &p)| {
                if is_fraction(i) {
                    (p.clamp(1e-4, 1.0 - 1e-4) / (1.0 - p.clamp(1e-4, 1.0 - 1e-4))).ln()
                } else {
                    p.ln()
                }
            },
        )
        .collect()
}

fn from_x(x: &[f64]) -> Vec<f64> {
    x.iter().enumerate().map(|(i, &y)| if is_fraction(i) { 1.0 / (1.0 + (-y).exp()) } else { y.exp() }).collect()
}

/// (peak, sweep+cool) of the six comparison sweeps and the warm-up temperatures.
/// (peak, sweep + cool) per comparison sweep, and the warm-up temperatures.
type Simulated = (Vec<(f64, f64)>, Vec<f64>);

fn simulate_seed(cfg: &RigConfig, params: &TyreParams, long_only: bool) -> Option<Simulated> {
    let mut out = Vec::new();
    let pre = preconditioned_rig(cfg, params).ok()?;
    for fr in [true, false] {
        for kind in SweepKind::ALL {
            if fr && long_only {
                out.push((f64::NAN, f64::NAN));
                continue;
            }
            let s = if fr { freerolling_setup(kind) } else { brkdrv_setup(kind) };
            let o = comparison_sweep(&pre, &s).ok()?;
            out.push((o.peak_temp_c, o.sweep_plus_cool_s()));
        }
    }
    if long_only {
        return Some((out, vec![f64::NAN, f64::NAN]));
    }
    let mut wcfg = cfg.clone();
    wcfg.environment.initial_tyre_temp_c = 20.0;
    let mut rig = VirtualRig::new(wcfg, params.clone(), cfg.seed).ok()?;
    let w = run_warmup(&mut rig, 2).ok()?;
    Some((out, w))
}

/// The figures averaged over `SEEDS` (noise moves cool-down ends and BrkDrv sliding energy).
fn simulate(cfg: &RigConfig, params: &TyreParams, long_only: bool) -> Option<Simulated> {
    let mut sum: Option<Simulated> = None;
    for seed in SEEDS {
        let mut c = cfg.clone();
        c.seed = seed;
        let (o, w) = simulate_seed(&c, params, long_only)?;
        if std::env::var_os("TUNE_VERBOSE").is_some() {
            eprintln!("seed {seed}: {o:.2?} {w:.1?}");
        }
        sum = Some(match sum {
            None => (o, w),
            Some((so, sw)) => (
                so.iter().zip(&o).map(|(a, b)| (a.0 + b.0, a.1 + b.1)).collect(),
                sw.iter().zip(&w).map(|(a, b)| a + b).collect(),
            ),
        });
    }
    let n = SEEDS.len() as f64;
    sum.map(|(o, w)| (o.iter().map(|a| (a.0 / n, a.1 / n)).collect(), w.iter().map(|a| a / n).collect()))
}

/// Seeds whose mean figures the search fits.
const SEEDS: [u64; 3] = [0, 1, 2];
/// Fraction of each tolerance the mean figure may use before the penalty steepens: the rest is
/// left for the seed-to-seed spread (every seed 0..=9 must pass).
const MARGIN: f64 = 0.6;

fn loss(cfg: &RigConfig, params: &TyreParams, long_only: bool, verbose: bool) -> f64 {
    let Some((out, w)) = simulate(cfg, params, long_only) else { return 1e9 };
    let thesis: Vec<_> = THESIS_FREEROLLING.iter().chain(THESIS_BRKDRV.iter()).collect();
    let mut l = 0.0;
    let hinge = |err: f64, tol: f64| {
        let r = err / tol;
        r * r + if r.abs() > MARGIN { 10.0 * (r.abs() - MARGIN) } else { 0.0 }
    };
    for (i, (peak, time)) in out.iter().enumerate() {
        let t = thesis[i];
        if peak.is_nan() {
            continue;
        }
        l += hinge(peak - t.peak_temp_c, 0.1 * t.peak_temp_c);
        l += hinge(time - t.sweep_plus_cool_s, 0.2 * t.sweep_plus_cool_s);
        if verbose {
            println!(
                "  sweep {i}: peak {peak:6.1} (thesis {:5.1})  time {time:7.2} (thesis {:6.2})",
                t.peak_temp_c, t.sweep_plus_cool_s
            );
        }
    }
    for table in usize::from(long_only)..2 {
        for i in 0..3 {
            for j in 0..3 {
                let (a, b) = (&out[table * 3 + i], &out[table * 3 + j]);
                let (ta, tb) = (thesis[table * 3 + i], thesis[table * 3 + j]);
                if ta.peak_temp_c < tb.peak_temp_c && a.0 >= b.0 {
                    l += 2.0 + (a.0 - b.0) / 2.0;
                }
                if ta.sweep_plus_cool_s < tb.sweep_plus_cool_s && a.1 >= b.1 {
                    l += 2.0 + (a.1 - b.1) / 2.0;
                }
            }
        }
    }
    if long_only {
        return l;
    }
    l += hinge(w[1] - 42.5, 2.5);
    l += 0.3 * hinge(w[0] - 31.0, 5.0);
    if verbose {
        println!("  warm-up {:.1} / {:.1}", w[0], w[1]);
    }
    l
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let evals: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(300);
    // `longitudinal`: search only the four parameters of the longitudinal (PX) heat path, which
    // no FreeRolling sweep and no warm-up uses, against the BrkDrv figures alone.
    let long_only = std::env::args().nth(2).is_some_and(|a| a == "longitudinal");
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/virtual_rig.toml");
    let cfg0 = RigConfig::load(&path)?;
    let params = TyreParams::read_tir(&cfg0.tyre_file)?;
    let full0 = to_x(&get(&cfg0));
    let free: Vec<usize> = if long_only { LONGITUDINAL.to_vec() } else { (0..full0.len()).collect() };
    let x0: Vec<f64> = free.iter().map(|&i| full0[i]).collect();
    let n = x0.len();
    let expand = |x: &[f64]| -> Vec<f64> {
        let mut full = full0.clone();
        for (k, &i) in free.iter().enumerate() {
            full[i] = x[k];
        }
        from_x(&full)
    };
    let f = |x: &[f64]| {
        let mut c = cfg0.clone();
        set(&mut c, &expand(x));
        if c.validate().is_err() {
            return 1e9;
        }
        loss(&c, &params, long_only, false)
    };
    // Nelder–Mead.
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::new();
    simplex.push((x0.clone(), f(&x0)));
    for i in 0..n {
        let mut x = x0.clone();
        x[i] += 0.4;
        let v = f(&x);
        simplex.push((x, v));
    }
    let mut count = n + 1;
    while count < evals {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        if count % 20 < 2 {
            eprintln!("eval {count}: best {:.3}", simplex[0].1);
        }
        let centroid: Vec<f64> = (0..n).map(|k| simplex[..n].iter().map(|p| p.0[k]).sum::<f64>() / n as f64).collect();
        let worst = simplex[n].clone();
        let pt = |t: f64| -> Vec<f64> { (0..n).map(|k| centroid[k] + t * (worst.0[k] - centroid[k])).collect() };
        let xr = pt(-1.0);
        let fr = f(&xr);
        count += 1;
        if fr < simplex[0].1 {
            let xe = pt(-2.0);
            let fe = f(&xe);
            count += 1;
            simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (xr, fr);
        } else {
            let xc = if fr < worst.1 { pt(-0.5) } else { pt(0.5) };
            let fc = f(&xc);
            count += 1;
            if fc < worst.1.min(fr) {
                simplex[n] = (xc, fc);
            } else {
                let best = simplex[0].0.clone();
                for p in simplex.iter_mut().skip(1) {
                    p.0 = (0..n).map(|k| best[k] + 0.5 * (p.0[k] - best[k])).collect();
                    p.1 = f(&p.0);
                    count += 1;
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let best = expand(&simplex[0].0);
    println!("best loss {:.4}", simplex[0].1);
    let mut c = cfg0.clone();
    set(&mut c, &best);
    for (k, v) in NAMES.iter().zip(&best) {
        println!("# {k} = {v:.6}");
    }
    print!("{}", toml::to_string(&c.thermal).expect("toml"));
    loss(&c, &params, long_only, true);
    Ok(())
}
