mod common;
use doctor::{DataOptions, Dataset, DoctorConfig, diagnose};
use std::time::Instant;

#[test]
#[ignore]
fn explore() {
    let case = std::env::var("CASE").unwrap_or_else(|_| "doctor_lateral.toml:noise,thermal".into());
    let mut it = case.split(':');
    let proc_ = it.next().unwrap();
    let effects = it.next().unwrap();
    let wear: Option<f64> = it.next().map(|s| s.parse().unwrap());
    let t0 = Instant::now();
    let log = common::run_log(proc_, effects, wear, 3);
    eprintln!("sim {:.1}s samples {}", t0.elapsed().as_secs_f64(), log.samples.len());
    let t0 = Instant::now();
    let rate: f64 = std::env::var("RATE").ok().and_then(|r| r.parse().ok()).unwrap_or(10.0);
    let ds = Dataset::from_logs(&[log], &DataOptions { point_rate_hz: rate, ..DataOptions::default() }).unwrap();
    eprintln!("data {:.2}s points {} sweeps {}", t0.elapsed().as_secs_f64(), ds.len(), ds.sweeps.len());
    let s = &ds.series;
    let tg: Vec<f64> = ds.points.iter().map(|&i| s.temp_grip_c[i]).collect();
    eprintln!(
        "tgrip {:.1}..{:.1}  E {:.3} MJ",
        tg.iter().cloned().fold(f64::INFINITY, f64::min),
        tg.iter().cloned().fold(0.0, f64::max),
        s.sliding_energy_j.last().unwrap() * 1e-6
    );
    let t0 = Instant::now();
    let mut base = common::base_tir();
    if std::env::var("ZERO_P").is_ok() {
        for k in mftyre::CoefGroup::Pressure.keys() {
            base.set(k, 0.0).unwrap();
        }
    }
    let mut cfg = DoctorConfig::default();
    if let Ok(r) = std::env::var("RATE") {
        let _ = r;
    }
    let dx = diagnose(&ds, &base, &cfg).unwrap();
    cfg.folds = 4;
    eprintln!("diagnose {:.1}s", t0.elapsed().as_secs_f64());
    eprintln!(
        "noise {:?}\nrms base {:?}\nfinal {:?}\nheldout {:?}",
        dx.rms.noise, dx.rms.base, dx.rms.final_fit, dx.rms.final_heldout
    );
    for (r, round) in dx.rounds.iter().enumerate() {
        for c in round {
            eprintln!(
                "round {r} {:10} ev {:8.4} folds {}/{} chi2 {:.0}->{:.0} dch {:?} {}",
                c.effect.name(),
                c.evidence,
                c.folds_improved,
                c.folds,
                c.chi2_before_heldout,
                c.chi2_after_heldout,
                c.delta_chi2_by_channel.map(|x| x.round()),
                c.reason
            );
        }
    }
    for n in &dx.named {
        eprintln!(
            "NAMED {} ev {:.3} ch {} rms {:.2}->{:.2} ho {:.2}->{:.2} region {}\n params {:?} {:?} th {}",
            n.effect.name(),
            n.evidence,
            n.channel,
            n.rms_before,
            n.rms_after,
            n.rms_before_heldout,
            n.rms_after_heldout,
            n.region,
            n.params.keys,
            n.params.values,
            n.params.threshold_w
        );
    }
    eprintln!("stop: {}", dx.stop_reason);
}
