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
