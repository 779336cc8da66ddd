//! The overturning-moment stage on data where its first start ends in the wrong basin: an
//! adaptive-plan run of the virtual rig, thinned (`tests/fixtures/fit/README.md`). From the one
//! start the MX stage had until the tenth session, the fit stopped at RMSE 11.1 N·m, 9.9 % of
//! peak from the true tyre; from its other starts it reaches 2.6 N·m and 2.05 %.

use std::io::Read;
use std::path::{Path, PathBuf};

use mffit::{FitOptions, fit};
use mftyre::TyreParams;
use rigdata::import::{FileFormat, ReadOptions, read_bytes};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn mx_fit_leaves_the_basin_its_first_start_falls_into() {
    let gz = std::fs::read(root().join("tests/fixtures/fit/adaptive_mf_seed1.tdx.gz")).expect("fixture");
    let mut text = Vec::new();
    flate2::read::GzDecoder::new(gz.as_slice()).read_to_end(&mut text).expect("gunzip");
    let (data, _) = read_bytes(&text, "adaptive_mf_seed1.tdx", FileFormat::Tdx, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let truth = TyreParams::read_tir(&root().join("launch-config/tyres/MagicFormula61_Paramerters.tir")).expect("tyre");
    let result = fit(&data, &FitOptions::default()).expect("fit");
    let mx = result.stages.iter().find(|s| s.stage == "mx").expect("mx stage");
    eprintln!("mx: rmse {:.3} N·m, notes {:?}", mx.rmse, mx.notes);
    let support = mffit::accuracy::Support::of_fit(&result);
    let acc = mffit::accuracy::compare(&truth, &result.params, &result.range, &support);
    let pct = |c: &str| acc.iter().find(|a| a.channel == c).map(|a| a.rms_pct_of_peak).expect(c);
    eprintln!("MX pure {:.2} % of peak, FY pure {:.2} %", pct("MX pure"), pct("FY pure"));
    // GS2MF's own log gives MX within 1.2 % of peak; the wrong basin is 9.9 %.
    assert!(pct("MX pure") < 3.0, "MX pure {:.2} % of peak from the true tyre", pct("MX pure"));
    assert!(mx.notes.iter().any(|n| n.starts_with("restart")), "the other starts were not tried: {:?}", mx.notes);
}
