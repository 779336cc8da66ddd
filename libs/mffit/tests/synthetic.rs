//! The full staged fit on synthetic GS2MF-like data from the project's default tyre recovers
//! the tyre's curves (the acceptance grid: FY, FX, MZ within 2 % of peak RMS, MX within 5 %).

use mffit::synth::{self, SynthOptions};
use mffit::{FitOptions, fit};
use mftyre::TyreParams;

fn truth() -> TyreParams {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../launch-config/tyres/MagicFormula61_Paramerters.tir");
    TyreParams::read_tir(std::path::Path::new(path)).expect("default tyre")
}

#[test]
fn full_fit_recovers_the_true_tyre() {
    let tyre = truth();
    let data = synth::gs2mf(&tyre, SynthOptions::default());
    let opts = FitOptions { max_points: 1500, ..FitOptions::default() };
    let result = fit(&data, &opts).expect("fit");
    for s in &result.stages {
        eprintln!(
            "{:<18} {:>6} pts  rmse {:>10.4} (start {:>10.4})  {:>5.2} s  it {:>4} {} {:?} {:?}",
            s.stage, s.points, s.rmse, s.initial_rmse, s.wall_s, s.iterations, s.termination, s.notes, s.skipped
        );
    }
    eprintln!("warnings: {:?}", result.warnings);
    let support = mffit::accuracy::Support::of_fit(&result);
    let acc = mffit::accuracy::compare(&tyre, &result.params, &result.range, &support);
    for a in &acc {
        eprintln!(
            "{:<12} rms {:>8.2}  {:>6.2} % of peak (max {:>6.2} %)",
            a.channel, a.rms, a.rms_pct_of_peak, a.max_pct_of_peak
        );
    }
    eprintln!("total {:.2} s", result.wall_s);
    let get = |c: &str| acc.iter().find(|a| a.channel == c).unwrap().rms_pct_of_peak;
    assert!(get("FY pure") < 2.0);
    assert!(get("FX pure") < 2.0);
    assert!(get("MZ pure") < 2.0);
    assert!(get("MX pure") < 5.0);
}

#[test]
fn every_stage_recovers_noise_free_data() {
    let tyre = truth();
    let data = synth::gs2mf(&tyre, SynthOptions { rate_hz: 20.0, noise: synth::Noise::OFF, ..SynthOptions::default() });
    let result = fit(&data, &FitOptions { max_points: 1500, ..FitOptions::default() }).expect("fit");
    let m = mffit::metrics::all(&result.params, &result.data, result.nominal.fz0_n);
    for s in m.iter().filter(|m| m.group == "all") {
        eprintln!("{:<18} {:>8.3} % of peak", s.stage, s.nrmse_pct);
        // Each stage reproduces its own (noise-free) data to within what 10 Hz averaging of
        // the fast (30 °/s) sweep parts leaves; relaxation to the step-steer sampling. The
        // combined FY/MZ stages carry the pure fits into ±5° camber the free-rolling data did
        // not reach (and MZ combined has only SSZ1–4 of its own), so they get more room.
        let limit = match s.stage.as_str() {
            "relaxation" => 3.0,
            "mz_combined" => 6.0,
            "fy_combined" => 2.0,
            _ => 1.0,
        };
        assert!(s.nrmse_pct < limit, "{}: {:.3} %", s.stage, s.nrmse_pct);
    }
    // Well-identified coefficients come back close to the true ones.
    for (k, tol) in [("PDY1", 0.03), ("PDX1", 0.03), ("QDZ1", 0.05), ("PCX1", 0.05), ("VERTICAL_STIFFNESS", 0.02)] {
        let (t, f) = (tyre.get(k).unwrap(), result.params.get(k).unwrap());
        assert!(((f - t) / t).abs() < tol, "{k}: true {t}, fitted {f}");
    }
}
