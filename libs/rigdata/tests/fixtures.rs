//! The readers on synthetic TTC-like runs (standstill, ramps, conditioning sweeps, repeats,
//! SR ≠ SL, SAE, 50 Hz): every sweep found with its kind and cell, exclusions counted, and the
//! same dataset from `.dat`, `.mat` and a folder of TYDEX files.

use mffit::{DataKind, Dataset, Procedure, SweepKind};
use rigdata::fixture::{FixtureRun, FixtureSpec, PlannedSweep, ttc_run};
use rigdata::import::{FileFormat, ReadOptions, read_bytes};
use rigdata::inspect::FileReport;
use rigdata::mat::{MatLayout, MatWriteOptions, to_mat};
use rigdata::table::{DatLayout, to_dat};

fn import(bytes: &[u8], name: &str, format: FileFormat) -> (Dataset, FileReport) {
    read_bytes(bytes, name, format, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// Every planned sweep found, in order, with its kind, conditioning flag and cell.
fn assert_found(run: &FixtureRun, d: &Dataset, r: &FileReport) {
    let planned: Vec<&PlannedSweep> = run.sweeps.iter().collect();
    let found: Vec<_> = d.segments.iter().collect();
    eprintln!("{}", rigdata::inspect::Inspection { files: vec![r.clone()] }.to_text(true));
    assert_eq!(found.len(), planned.len(), "sweeps found vs planned");
    for (p, s) in planned.iter().zip(&found) {
        let c = s.cell.expect("cell");
        assert_eq!(c.kind, p.kind, "{}", s.sweep);
        assert_eq!(s.kind == DataKind::WarmUp, p.conditioning, "{}", s.sweep);
        assert_eq!(
            s.procedure,
            if p.kind == SweepKind::Cornering { Procedure::FreeRolling } else { Procedure::BrkDrv }
        );
        assert!((c.fz_n - p.fz_n).abs() < 0.03 * p.fz_n, "{}: FZ {} vs {}", s.sweep, c.fz_n, p.fz_n);
        assert!((c.p_pa / 1e3 - p.p_kpa).abs() < 1.0, "{}: P {} vs {}", s.sweep, c.p_pa, p.p_kpa);
        assert!((c.gamma_rad.to_degrees() - p.ia_deg).abs() < 0.1, "{}", s.sweep);
        assert!((c.alpha_rad.to_degrees() - p.sa_deg).abs() < 0.1, "{}: SA {}", s.sweep, c.alpha_rad.to_degrees());
        assert!((c.vx_mps * 3.6 - 40.0).abs() < 1.0);
        let o = s.origin.as_ref().expect("origin");
        assert!(o.first_row < o.last_row);
        // ISO-W, SI: load positive, FY opposing the slip angle at small slip.
        assert!(s.samples.iter().all(|x| x.fz_n > 0.0 && x.p_pa > 5e4));
    }
    let excluded = |why: &str| r.excluded.iter().find(|e| e.0.starts_with(why)).map(|e| e.1).unwrap_or(0);
    assert!(excluded("standstill") > 0 && excluded("load ramp") > 0 && excluded("unloaded") > 0, "{:?}", r.excluded);
    let total = r.rows_in_sweeps + r.rows_in_conditioning + r.excluded.iter().map(|e| e.1).sum::<usize>();
    assert_eq!(total, r.rows, "every row in a sweep or excluded");
}

#[test]
fn cornering_run_every_sweep_found_with_its_cell() {
    let run = ttc_run(&FixtureSpec::cornering());
    let text = to_dat(&run.table, DatLayout::default());
    let (d, r) = import(text.as_bytes(), "cornering.dat", FileFormat::Dat);
    assert_found(&run, &d, &r);
    assert!(r.excluded.iter().any(|e| e.0 == "pressure ramp"), "{:?}", r.excluded);
    assert_eq!(r.convention, "SAE");
    // SL is exactly 0 in cornering, and that is what the samples carry (not SR).
    assert!(d.segments.iter().flat_map(|s| &s.samples).all(|x| x.kappa == 0.0));
    // Repeats at one cell are kept apart and numbered.
    assert!(
        d.segments.iter().any(|s| s.sweep == "cornering P83kPa FZ1100N IA0 #2"),
        "{:?}",
        d.segments.iter().map(|s| &s.sweep).collect::<Vec<_>>()
    );
    // ISO-W: a positive slip angle gives a negative FY at small slip.
    let s = d.segments[1]
        .samples
        .iter()
        .find(|x| x.alpha_rad > 2f64.to_radians() && x.alpha_rad < 4f64.to_radians())
        .unwrap();
    assert!(s.fy_n < 0.0 && s.mz_nm > 0.0, "{s:?}");
    // The ambient temperature in °F labelled °C is caught.
    assert!(r.warnings.iter().any(|w| w.message.contains("surely degF")), "{:?}", r.warnings);
}

#[test]
fn drive_brake_run_every_sweep_found_with_its_cell() {
    let run = ttc_run(&FixtureSpec::drive_brake());
    let text = to_dat(&run.table, DatLayout::default());
    let (d, r) = import(text.as_bytes(), "db.dat", FileFormat::Dat);
    assert_found(&run, &d, &r);
    assert!(d.segments.iter().any(|s| s.cell.unwrap().kind == SweepKind::Combined));
    assert!(r.excluded.iter().any(|e| e.0 == "camber change"), "{:?}", r.excluded);
    assert!(r.warnings.iter().all(|w| !w.message.contains("says")), "{:?}", r.warnings);
}

#[test]
fn sr_is_used_only_without_sl_and_never_where_the_wheel_rolls_free() {
    // Cornering with only SR: no slip-ratio sweeps, slip ratio 0.
    let run = ttc_run(&FixtureSpec { with_sl: false, ..FixtureSpec::cornering() });
    let text = to_dat(&run.table, DatLayout::default());
    let (d, r) = import(text.as_bytes(), "c_sr.dat", FileFormat::Dat);
    assert_found(&run, &d, &r);
    assert!(d.segments.iter().flat_map(|s| &s.samples).all(|x| x.kappa == 0.0));
    // Without the test id the cornering sweeps are still cornering, SR zeroed in them.
    let mut t = run.table.clone();
    t.test_id = None;
    t.title = None;
    let text = to_dat(&t, DatLayout::default());
    let (d, r) = import(text.as_bytes(), "c_sr_noid.dat", FileFormat::Dat);
    assert_found(&run, &d, &r);
    assert!(d.segments.iter().flat_map(|s| &s.samples).all(|x| x.kappa == 0.0));
    // Drive/brake with only SR: SR is the slip ratio. Its offset and noise hide the 0.04
    // conditioning sweeps (they are excluded either way); every measuring sweep is found.
    let mut run = ttc_run(&FixtureSpec { with_sl: false, ..FixtureSpec::drive_brake() });
    let (mut d, r) = import(to_dat(&run.table, DatLayout::default()).as_bytes(), "db_sr.dat", FileFormat::Dat);
    run.sweeps.retain(|s| !s.conditioning);
    d.segments.retain(|s| s.kind != DataKind::WarmUp);
    assert_found(&run, &d, &r);
    assert!(r.slip_ratio_from.starts_with("SR"));
}

fn assert_same(a: &Dataset, b: &Dataset, tol: f64) {
    assert_eq!(a.segments.len(), b.segments.len());
    for (x, y) in a.segments.iter().zip(&b.segments) {
        assert_eq!((&x.sweep, x.kind, x.procedure), (&y.sweep, y.kind, y.procedure));
        assert_eq!(x.samples.len(), y.samples.len(), "{}", x.sweep);
        for (p, q) in x.samples.iter().zip(&y.samples) {
            for (u, v) in [
                (p.fz_n, q.fz_n),
                (p.fy_n, q.fy_n),
                (p.alpha_rad, q.alpha_rad),
                (p.kappa, q.kappa),
                (p.p_pa, q.p_pa),
                (p.mz_nm, q.mz_nm),
                (p.rl_m, q.rl_m),
                (p.temp_c, q.temp_c),
            ] {
                assert!((u - v).abs() <= tol * u.abs().max(1.0), "{}: {u} vs {v}", x.sweep);
            }
        }
    }
}

#[test]
fn dat_and_mat_of_one_run_give_the_same_dataset() {
    for spec in [FixtureSpec::cornering(), FixtureSpec::drive_brake()] {
        let run = ttc_run(&spec);
        // Full precision in the text so both files hold the same numbers.
        let dat = to_dat(&run.table, DatLayout { decimals: 10, crlf: true });
        let (a, _) = import(dat.as_bytes(), "run.dat", FileFormat::Dat);
        for opt in [
            MatWriteOptions::default(),
            MatWriteOptions { compress: false, big_endian: true, ..Default::default() },
            MatWriteOptions { layout: MatLayout::Struct("run".into()), ..Default::default() },
        ] {
            let mat = to_mat(&run.table, &opt).unwrap();
            let (b, r) = import(&mat, "run.mat", FileFormat::Mat);
            assert_eq!(r.tire_id.as_deref(), Some("Fixture 20.5x7.0-13, R25B"));
            assert_same(&a, &b, 1e-9);
        }
    }
}

#[test]
fn unknown_units_and_test_kind_disagreements_are_named() {
    let run = ttc_run(&FixtureSpec::cornering());
    let mut t = run.table.clone();
    t.columns.iter_mut().find(|c| c.name == "P").unwrap().unit = "furlong".into();
    // An unknown spelling does not refuse the run: the TTC unit is assumed, loudly.
    let (d, r) = import(to_dat(&t, DatLayout::default()).as_bytes(), "u.dat", FileFormat::Dat);
    let w = r.warnings.iter().find(|w| w.message.contains("unknown unit `furlong`")).expect("warning");
    assert_eq!(w.place.to_string(), "u.dat: channel P", "{w:?}");
    assert!(w.message.contains("read as kPa"), "{w:?}");
    let (clean, _) = import(to_dat(&run.table, DatLayout::default()).as_bytes(), "c.dat", FileFormat::Dat);
    assert_same(&clean, &d, 1e-9);
    let mut t = run.table.clone();
    t.columns.iter_mut().find(|c| c.name == "FZ").unwrap().unit = "deg".into();
    let e = read_bytes(to_dat(&t, DatLayout::default()).as_bytes(), "w.dat", FileFormat::Dat, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("channel FZ: unit `deg` is a unit of angle; FZ needs a unit of force"), "{e}");
    // A title (a .dat has no testid) that says drive/brake on a cornering run: a warning, the
    // data decides.
    let mut t = run.table.clone();
    t.title = Some("TIRF Data File: Run 7; Drive/Brake/Combined, 12psi".into());
    let (d, r) = import(to_dat(&t, DatLayout::default()).as_bytes(), "k.dat", FileFormat::Dat);
    assert!(d.segments.iter().all(|s| s.cell.unwrap().kind == SweepKind::Cornering));
    assert!(
        r.warnings.iter().any(|w| w.message.contains("drive/brake/combined) but 10 slip-angle sweeps")),
        "{:?}",
        r.warnings
    );
    // An ISO-W reading forced on an SAE file flips the load negative: nothing is loaded.
    let opt = ReadOptions { convention: rigdata::Convention::IsoW, ..ReadOptions::default() };
    let (d, r) =
        read_bytes(to_dat(&run.table, DatLayout::default()).as_bytes(), "iso.dat", FileFormat::Dat, &opt).unwrap();
    assert!(d.segments.is_empty() && r.convention == "ISO-W" && r.convention_basis == "given");
}
