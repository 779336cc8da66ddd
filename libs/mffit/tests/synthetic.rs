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
    let data = synth::gs2mf(&tyre, SynthOptions { rate_hz: 20.0, ..SynthOptions::default() });
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
#[ignore]
fn debug_fx() {
    let tyre = truth();
    let data = synth::gs2mf(&tyre, SynthOptions { rate_hz: 20.0, ..SynthOptions::default() });
    let opts = FitOptions { max_points: 1500, ..FitOptions::default() };
    let result = fit(&data, &opts).expect("fit");
    for k in [
        "PCX1", "PDX1", "PDX2", "PDX3", "PEX1", "PEX2", "PEX3", "PEX4", "PKX1", "PKX2", "PKX3", "PHX1", "PHX2", "PVX1",
        "PVX2", "PPX1", "PPX2", "PPX3", "PPX4", "RBX1", "RBX2", "RCX1", "RBY1", "RBY2", "RCY1",
    ] {
        eprintln!("{k:6} true {:>10.4} fit {:>10.4}", tyre.get(k).unwrap(), result.params.get(k).unwrap());
    }
    eprintln!("true squareness {:.3}", mffit::checks::ellipse_squareness(&tyre, 6752.0, 2.6e5));
    // worst MZ point
    let mut worst = (0.0, None);
    for fz in [3000.0, 6752.0, 10000.0, 13000.0] {
        for a in -20..=20 {
            for g in [-3.0, 0.0, 3.0] {
                for p in [2.1e5, 2.6e5, 3.3e5] {
                    let i = mftyre::MfInput {
                        fz_n: fz,
                        kappa: 0.0,
                        alpha_rad: (a as f64).to_radians(),
                        gamma_rad: (g as f64).to_radians(),
                        phit_per_m: 0.0,
                        vx_mps: 16.6,
                        p_pa: p,
                        omega_radps: 0.0,
                    };
                    let e = (mftyre::evaluate(&tyre, mftyre::UseMode::M111, &i).mz_nm
                        - mftyre::evaluate(&result.params, mftyre::UseMode::M111, &i).mz_nm)
                        .abs();
                    if e > worst.0 {
                        worst = (e, Some((fz, a, g, p)));
                    }
                }
            }
        }
    }
    eprintln!("worst MZ {:?}", worst);
}
