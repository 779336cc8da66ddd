//! The fitter on data shaped like real TTC runs (cornering at four pressures and camber 0; a
//! drive/brake/combined run at one pressure, three cambers, three slip angles): each stage fits
//! what the data identify, holds the rest with the reason, stays physical, and is
//! cross-validated. The data come from an MF tyre (FSAE scale), so this tests the fitter's
//! structure; fidelity to a tyre MF cannot represent is tested on the brush tyre.

use std::path::Path;

use mffit::synth::{self, SynthOptions, TtcShape};
use mffit::{Dataset, FitOptions, fit};
use mftyre::TyreParams;

fn race_tyre() -> TyreParams {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/tyres/FSAE_Defaults.tir");
    TyreParams::read_tir(&p).unwrap()
}

fn runs() -> (Dataset, Dataset) {
    let o = SynthOptions { rate_hz: 25.0, noise: synth::RACE_NOISE, seed: 3, ..Default::default() };
    synth::ttc_runs(&race_tyre(), &TtcShape::race(), o)
}

fn opts() -> FitOptions {
    FitOptions { folds: 4, max_points: 2000, ..FitOptions::default() }
}

fn stage<'a>(r: &'a mffit::FitResult, name: &str) -> &'a mffit::stages::StageReport {
    r.stages.iter().find(|s| s.stage == name).unwrap()
}

#[test]
fn cornering_only_fits_the_lateral_stages_and_holds_camber_terms() {
    let (cornering, _) = runs();
    let r = fit(&cornering, &opts()).unwrap();
    let fy = stage(&r, "fy_pure");
    assert!(fy.skipped.is_none());
    // Camber 0 only: every camber term held, saying so.
    for k in ["PDY3", "PKY3", "PKY6", "PVY3"] {
        let h = fy.held.iter().find(|h| h.key == k).unwrap_or_else(|| panic!("{k} not held: {:?}", fy.held));
        assert!(h.reason.contains("camber"), "{k}: {}", h.reason);
    }
    // Four pressures: the pressure terms are fitted, with finite uncertainties.
    for k in ["PPY1", "PPY3"] {
        let e = fy.estimates.iter().find(|e| e.key == k).unwrap_or_else(|| panic!("{k} not fitted"));
        assert!(e.std.is_finite() && e.std > 0.0, "{k}: {e:?}");
    }
    for s in ["fx_pure", "fx_combined", "fy_combined", "mz_combined"] {
        assert!(stage(&r, s).skipped.is_some(), "{s} should be skipped without slip-ratio sweeps");
    }
    let h = fy.heldout.as_ref().expect("fy_pure cross-validated");
    assert!(h.nrmse_pct < 1.5, "held-out FY {h:?}");
    assert!(r.nonphysical_stages().is_empty(), "{:?}", r.warnings);
}

#[test]
fn drive_brake_only_fits_longitudinal_and_holds_pressure_terms() {
    let (_, drive) = runs();
    let r = fit(&drive, &opts()).unwrap();
    let fx = stage(&r, "fx_pure");
    assert!(fx.skipped.is_none());
    for k in ["PPX1", "PPX3"] {
        let h = fx.held.iter().find(|h| h.key == k).unwrap_or_else(|| panic!("{k} not held"));
        assert!(h.reason.contains("pressure"), "{k}: {}", h.reason);
    }
    assert!(fx.estimates.iter().any(|e| e.key == "PDX3"), "three cambers identify PDX3");
    assert!(fx.heldout.as_ref().is_some_and(|h| h.nrmse_pct < 2.0), "{:?}", fx.heldout);
    assert!(r.nonphysical_stages().is_empty(), "{:?}", r.warnings);
}

#[test]
fn both_runs_fit_every_force_stage_physically() {
    let (mut all, drive) = runs();
    all.extend(drive);
    let r = fit(&all, &opts()).unwrap();
    for (s, limit) in [("fy_pure", 1.5), ("fx_pure", 2.0), ("fx_combined", 3.0), ("fy_combined", 3.0), ("mz_pure", 4.0)]
    {
        let st = stage(&r, s);
        let h = st.heldout.as_ref().unwrap_or_else(|| panic!("{s} not cross-validated: {:?}", st.skipped));
        assert!(h.nrmse_pct < limit, "{s}: held-out {:.2} % (limit {limit})", h.nrmse_pct);
    }
    // The drive run's pure points bring the cambers the cornering run lacks.
    assert!(stage(&r, "fy_pure").estimates.iter().any(|e| e.key == "PKY6"), "camber thrust from the drive run");
    assert!(r.nonphysical_stages().is_empty(), "{:?}", r.warnings);
}
