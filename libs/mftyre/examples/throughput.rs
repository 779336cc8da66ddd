//! Evaluations per CPU-second, measured with the thread's own CPU time (Linux
//! `/proc/thread-self/schedstat`, falling back to wall time), so that a machine shared with
//! other jobs does not distort the figure the way wall-clock benchmarks are distorted.
//!
//! Run: `cargo run --release -p mftyre --example throughput`

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use mftyre::{BatchInput, BatchOutput, TyreParams, UseMode, evaluate_batch, pure_fy_batch};

const N: usize = 1_000_000;

fn cpu_ns() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

fn timed(f: &mut dyn FnMut()) -> f64 {
    let (c0, w0) = (cpu_ns(), Instant::now());
    f();
    match (c0, cpu_ns()) {
        (Some(a), Some(b)) => b - a,
        _ => w0.elapsed().as_nanos() as f64,
    }
}

fn main() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres/MagicFormula61_Paramerters.tir");
    let params = match TyreParams::read_tir(&path) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let mut seed: u64 = 0x5eed;
    let mut rnd = move |lo: f64, hi: f64| {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((seed >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut random: [Vec<f64>; 6] = Default::default();
    let mut sweeps: [Vec<f64>; 6] = Default::default();
    for i in 0..N {
        let r = [rnd(1000.0, 14000.0), rnd(-0.5, 0.5), rnd(-0.4, 0.4), rnd(-0.1, 0.1), rnd(5.0, 40.0), rnd(2e5, 3.5e5)];
        for (c, v) in random.iter_mut().zip(r) {
            c.push(v);
        }
        let case = i / 1000;
        let t = (i % 1000) as f64 / 999.0;
        let (kappa, alpha) = match case % 3 {
            0 => (0.0, 0.5 * t - 0.25),
            1 => (t - 0.5, 0.0),
            _ => (0.6 * t - 0.3, 0.05),
        };
        let s = [2000.0 + 10.0 * case as f64, kappa, alpha, ((case % 5) as f64 - 2.0) * 0.02, 16.6, 260000.0];
        for (c, v) in sweeps.iter_mut().zip(s) {
            c.push(v);
        }
    }
    for (name, cols) in [("random box", &random), ("sweeps", &sweeps)] {
        let inputs = BatchInput {
            fz_n: &cols[0],
            kappa: &cols[1],
            alpha_rad: &cols[2],
            gamma_rad: &cols[3],
            vx_mps: &cols[4],
            p_pa: &cols[5],
            ..Default::default()
        };
        let mut out = BatchOutput::default();
        let mut fy = Vec::new();
        let mut best_full = f64::MAX;
        let mut best_fy = f64::MAX;
        for _ in 0..5 {
            best_full = best_full.min(timed(&mut || {
                evaluate_batch(&params, UseMode::M111, black_box(&inputs), &mut out).ok();
            }));
            best_fy = best_fy.min(timed(&mut || {
                pure_fy_batch(&params, UseMode::M111, black_box(&inputs), &mut fy).ok();
            }));
        }
        black_box((&out, &fy));
        println!(
            "{name:<11} full combined (111): {:6.1} ns/eval = {:5.2} M evals/s/core | pure Fy: {:6.1} ns/eval = {:5.2} M/s",
            best_full / N as f64,
            1e3 * N as f64 / best_full,
            best_fy / N as f64,
            1e3 * N as f64 / best_fy
        );
    }
}
