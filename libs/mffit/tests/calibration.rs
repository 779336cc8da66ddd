//! The band of the mean against a true tyre the Magic Formula cannot represent: synthetic GS2MF
//! data of the default MF tyre with a lateral-force wiggle added (a 4.2°-period ripple over slip
//! angle, 2 % of the load), which no MF coefficient can follow. The delta-method σ counts only
//! repeatability and holds few of the true values; with the form error it must hold most.

use mffit::accuracy::{ReferenceTyre, Support};
use mffit::calibration::{Calibration, calibrate};
use mffit::prediction::{EnvelopeGrid, MapChannel, PredictionMap, prediction_maps};
use mffit::synth::{self, Noise, SynthOptions};
use mffit::{FitOptions, fit};
use mftyre::{MfInput, TyreParams, UseMode};

fn truth() -> TyreParams {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../launch-config/tyres/MagicFormula61_Paramerters.tir");
    TyreParams::read_tir(std::path::Path::new(path)).expect("default tyre")
}

/// What the MF misses: 2 % of the load, period 4.2° of slip angle.
fn ripple_n(x: &MfInput) -> f64 {
    0.02 * x.fz_n * (1.5 * x.alpha_rad.to_degrees()).sin()
}

fn fyw(rows: &[Calibration]) -> &Calibration {
    rows.iter().find(|r| r.channel == MapChannel::FyPure.tydex_name()).expect("an FYW row")
}

#[test]
fn the_form_error_makes_the_band_hold_a_tyre_the_model_cannot_represent() {
    let t = truth();
    let mut data = synth::gs2mf(&t, SynthOptions { rate_hz: 10.0, noise: Noise::RIG, ..Default::default() });
    for seg in &mut data.segments {
        for s in &mut seg.samples {
            let x = MfInput { fz_n: s.fz_n, alpha_rad: s.alpha_rad, ..MfInput::default() };
            s.fy_n += ripple_n(&x);
        }
    }
    let skip = ["mz_pure", "fx_pure", "fx_combined", "fy_combined", "mz_combined", "mx", "radius", "relaxation"];
    let opts = FitOptions { folds: 0, skip_stages: skip.map(String::from).to_vec(), ..FitOptions::default() };
    let result = fit(&data, &opts).expect("fit");
    let n = &result.nominal;
    let grid = EnvelopeGrid::standard(n.fz0_n, n.p0_pa, n.v0_mps);
    let maps = prediction_maps(&result, &grid);
    let reference = |mode: UseMode, x: &MfInput| {
        let mut o = mftyre::evaluate(&t, mode, x);
        o.fy_n += ripple_n(x);
        o
    };
    let reference: &ReferenceTyre<'_> = &reference;
    let support = Support::of_fit(&result);
    let score = |std: fn(&PredictionMap) -> &Vec<f64>| {
        let band: Vec<PredictionMap> =
            maps.iter().map(|m| PredictionMap { std: std(m).clone(), ..m.clone() }).collect();
        calibrate(&band, &grid, n.r0_m, reference, &support)
    };
    let param = score(|m| &m.std_param);
    let total = score(|m| &m.std);
    let (p, f) = (&fyw(&param).tested, &fyw(&total).tested);
    assert!(f.points > 50, "{} grid points inside the tested envelope", f.points);
    assert!(p.in_band_pct < 50.0, "the delta method alone holds {:.1} % of the true values", p.in_band_pct);
    eprintln!(
        "FYW tested: {} points; without the form error {:.1} % in band, median |error|/σ {:.2}; with it {:.1} %, {:.2}",
        f.points, p.in_band_pct, p.median_error_over_std, f.in_band_pct, f.median_error_over_std
    );
    // Measured: 24.1 % → 72.4 %. The residuals show what the model misses at the data; the
    // error between tested levels (interpolation) they cannot show, hence not 95 %.
    assert!(
        f.in_band_pct >= 60.0 && f.in_band_pct >= p.in_band_pct + 30.0,
        "with the form error {:.1} % (without {:.1} %)",
        f.in_band_pct,
        p.in_band_pct
    );
    assert!(
        (0.3..=1.5).contains(&f.median_error_over_std),
        "median |error|/σ {:.2} with the form error: neither too narrow nor trivially wide",
        f.median_error_over_std
    );
    // Outside the tested envelope (cambers ±4°, the highest load) the band widens to the
    // channel's worst in-envelope form error and says it is extrapolated.
    let m = maps.iter().find(|m| m.channel == MapChannel::FyPure).expect("an FYW map");
    let worst = m.std_form.iter().zip(&m.extrapolated).filter(|(_, x)| !**x).map(|(s, _)| *s).fold(0.0, f64::max);
    let outside: Vec<f64> = m.std_form.iter().zip(&m.extrapolated).filter(|(_, x)| **x).map(|(s, _)| *s).collect();
    assert!(worst > 0.0 && !outside.is_empty());
    assert!(outside.iter().all(|s| *s == worst), "extrapolated points carry the worst in-envelope τ {worst}");
}
