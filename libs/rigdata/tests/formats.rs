//! Format round trips and conversions: `.mat` written with every option reads back to the same
//! table; tyrerig's TYDEX export reads back exactly; a folder of foreign TYDEX files (other
//! units, conversion factors, ISO-W) gives the same sweeps as the TTC file they came from; SAE
//! and ISO-W, kPa and psi, N and lbf versions of one run give one dataset; the imported
//! dataset survives the MCAP log with its cells.

use mffit::{DataKind, Dataset};
use rigdata::fixture::{FixtureSpec, ttc_run};
use rigdata::import::{FileFormat, ReadOptions, read_bytes, read_path};
use rigdata::mat::{CharEncoding, MatLayout, MatWriteOptions, parse_mat, to_mat};
use rigdata::table::{ChannelTable, DatLayout, to_dat};
use rigdata::units;

fn import_dat(t: &ChannelTable, name: &str) -> Dataset {
    let text = to_dat(t, DatLayout { decimals: 10, crlf: false });
    read_bytes(text.as_bytes(), name, FileFormat::Dat, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}")).0
}

fn assert_same(a: &Dataset, b: &Dataset, tol: f64) {
    assert_eq!(a.segments.len(), b.segments.len());
    for (x, y) in a.segments.iter().zip(&b.segments) {
        assert_eq!((&x.sweep, x.kind, x.procedure), (&y.sweep, y.kind, y.procedure));
        assert_eq!(x.samples.len(), y.samples.len(), "{}", x.sweep);
        for (p, q) in x.samples.iter().zip(&y.samples) {
            let pairs = [
                (p.fz_n, q.fz_n),
                (p.fy_n, q.fy_n),
                (p.fx_n, q.fx_n),
                (p.alpha_rad, q.alpha_rad),
                (p.kappa, q.kappa),
                (p.p_pa, q.p_pa),
                (p.mz_nm, q.mz_nm),
                (p.mx_nm, q.mx_nm),
                (p.vx_mps, q.vx_mps),
            ];
            for (u, v) in pairs {
                assert!((u - v).abs() <= tol * u.abs().max(1.0), "{}: {u} vs {v}", x.sweep);
            }
        }
    }
}

#[test]
fn mat_written_with_every_option_reads_back_identically() {
    let mut t = ttc_run(&FixtureSpec::drive_brake()).table;
    let n = t.rows();
    // Integer channels MATLAB would store narrow: uint8, int8, int16, uint32.
    t.push("CNT8", "", (0..n).map(|i| (i % 200) as f64).collect());
    t.push("NEG8", "", (0..n).map(|i| (i % 100) as f64 - 50.0).collect());
    t.push("CNT16", "", (0..n).map(|i| i as f64 - 3000.0).collect());
    t.push("BIG", "", (0..n).map(|i| i as f64 * 70_000.0).collect());
    t.test_id = Some("Drive/Brake/Combined, 12psi — ü".into());
    for compress in [false, true] {
        for big_endian in [false, true] {
            for layout in [MatLayout::Variables, MatLayout::Struct("data".into())] {
                for narrow_integers in [false, true] {
                    for chars in [CharEncoding::Utf16, CharEncoding::Utf8] {
                        let opt = MatWriteOptions {
                            compress,
                            big_endian,
                            layout: layout.clone(),
                            narrow_integers,
                            chars,
                            ..Default::default()
                        };
                        let bytes = to_mat(&t, &opt).unwrap();
                        let m = parse_mat(&bytes, "x.mat").unwrap_or_else(|e| panic!("{opt:?}: {e}"));
                        assert!(m.warnings.is_empty(), "{opt:?}: {:?}", m.warnings);
                        assert_eq!(m.table.tire_id, t.tire_id);
                        assert_eq!(m.table.test_id, t.test_id);
                        assert_eq!(m.table.columns.len(), t.columns.len());
                        for (a, b) in t.columns.iter().zip(&m.table.columns) {
                            assert_eq!(a.name, b.name);
                            assert!(
                                a.values.iter().zip(&b.values).all(|(x, y)| x.to_bits() == y.to_bits()),
                                "{opt:?}: {}",
                                a.name
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn mat_oddities_are_clear_errors() {
    let t = ttc_run(&FixtureSpec::cornering()).table;
    let good = to_mat(&t, &MatWriteOptions::default()).unwrap();
    // v7.3 is HDF5: a clear request to re-save.
    let mut h5 = vec![0u8; 1024];
    h5[..19].copy_from_slice(b"MATLAB 7.3 MAT-file");
    h5[512..520].copy_from_slice(b"\x89HDF\r\n\x1a\n");
    let e = parse_mat(&h5, "new.mat").unwrap_err().to_string();
    assert!(e.contains("v7.3") && e.contains("-v7"), "{e}");
    let e = parse_mat(b"hello world, not a mat file at all", "t.mat").unwrap_err().to_string();
    assert!(e.contains("not a MATLAB .mat file"), "{e}");
    // Truncated: what was complete is read, the rest is named in a warning.
    let m = parse_mat(&good[..good.len() * 2 / 3], "cut.mat").unwrap();
    assert!(m.warnings.iter().any(|w| w.message.contains("the rest of the file ignored")), "{:?}", m.warnings);
    assert!(m.table.columns.len() < t.columns.len());
    // No units in a .mat: P in psi is recognised from its magnitude, with a warning.
    let mut psi = t.clone();
    let p = psi.columns.iter_mut().find(|c| c.name == "P").unwrap();
    p.values.iter_mut().for_each(|v| *v /= 6.894_757);
    p.unit.clear();
    let bytes = to_mat(&psi, &MatWriteOptions::default()).unwrap();
    let (d, r) = read_bytes(&bytes, "psi.mat", FileFormat::Mat, &ReadOptions::default()).unwrap();
    assert!(r.warnings.iter().any(|w| w.message.contains("looks like psi")), "{:?}", r.warnings);
    let p0 = d.segments[1].samples[0].p_pa;
    assert!((p0 - 83_000.0).abs() < 1_000.0, "{p0}");
}

/// The table in other units and axes: ISO-W signs, psi, lbf, lbf-ft, m/s, rad.
fn converted(t: &ChannelTable, iso: bool) -> ChannelTable {
    let mut o = t.clone();
    for c in &mut o.columns {
        let to = match c.name.as_str() {
            "P" => Some("psi"),
            "FX" | "FY" | "FZ" => Some("lbf"),
            "MX" | "MZ" => Some("lbf-ft"),
            "V" => Some("m/s"),
            "SA" | "IA" => Some("rad"),
            _ => None,
        };
        if let Some(to) = to {
            let (a, b) = (units::parse(&c.unit).unwrap(), units::parse(to).unwrap());
            c.values.iter_mut().for_each(|v| *v = b.from_target(a.to_target(*v)));
            c.unit = to.into();
        }
        if iso && ["FY", "FZ", "SA", "MZ"].contains(&c.name.as_str()) {
            c.values.iter_mut().for_each(|v| *v = -*v);
        }
    }
    o
}

#[test]
fn one_run_in_other_units_and_axes_gives_one_dataset() {
    let t = ttc_run(&FixtureSpec::cornering()).table;
    let a = import_dat(&t, "sae.dat");
    assert_same(&a, &import_dat(&converted(&t, false), "units.dat"), 1e-9);
    let iso = import_dat(&converted(&t, true), "iso.dat");
    assert_same(&a, &iso, 1e-9);
}

#[test]
fn own_tydex_export_reads_back_exactly() {
    let truth = mftyre::TyreParams::read_tir(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../launch-config/tyres/MagicFormula61_Paramerters.tir"
    )))
    .unwrap();
    let d = mffit::synth::gs2mf(
        &truth,
        mffit::synth::SynthOptions { rate_hz: 10.0, noise: mffit::synth::Noise::RIG, ..Default::default() },
    );
    let text = rigdata::tydex::to_tydex(&d, "x");
    let (back, r) = read_bytes(text.as_bytes(), "x.tdx", FileFormat::Tdx, &ReadOptions::default()).unwrap();
    assert!(r.format.contains("tyrerig export"));
    assert_eq!(back.segments.len(), d.segments.len());
    assert_eq!(back.fnomin_n, d.fnomin_n);
    for (a, b) in d.segments.iter().zip(&back.segments) {
        assert_eq!((a.procedure, a.kind, &a.section, &a.sweep), (b.procedure, b.kind, &b.section, &b.sweep));
        assert_eq!(a.samples.len(), b.samples.len());
        for (x, y) in a.samples.iter().zip(&b.samples) {
            let pairs = [
                (x.time_s, y.time_s),
                (x.fz_n, y.fz_n),
                (x.kappa, y.kappa),
                (x.alpha_rad, y.alpha_rad),
                (x.gamma_rad, y.gamma_rad),
                (x.p_pa, y.p_pa),
                (x.vx_mps, y.vx_mps),
                (x.omega_radps, y.omega_radps),
                (x.fx_n, y.fx_n),
                (x.fy_n, y.fy_n),
                (x.mx_nm, y.mx_nm),
                (x.my_nm, y.my_nm),
                (x.mz_nm, y.mz_nm),
                (x.rl_m, y.rl_m),
                (x.temp_c, y.temp_c),
                (x.dist_m, y.dist_m),
            ];
            for (i, (u, v)) in pairs.iter().enumerate() {
                assert!(
                    (u - v).abs() <= 1e-10 * u.abs().max(1.0) || (u.is_nan() && v.is_nan()),
                    "channel {i}: {u} vs {v}"
                );
            }
        }
    }
}

/// A foreign TYDEX measurement file: TYDEX names, ISO-W, kN / bar / km/h / rad with their
/// conversion factors, constants for nominal load and test kind.
fn foreign_tdx(t: &ChannelTable, rows: std::ops::Range<usize>, id: usize) -> String {
    use std::fmt::Write as _;
    let map = [
        ("ET", "RUNTIME", "s", 1.0, 1.0, 1.0),
        ("V", "TRAJVELW", "km/h", 1.0, 1.0 / 3.6, 1.0),
        ("SA", "SLIPANGL", "rad", std::f64::consts::PI / 180.0, 1.0, -1.0),
        ("IA", "INCLANGL", "deg", 1.0, std::f64::consts::PI / 180.0, 1.0),
        ("P", "INFLPRES", "bar", 0.01, 1e5, 1.0),
        ("FX", "FX", "kN", 1e-3, 1e3, 1.0),
        ("FY", "FYW", "kN", 1e-3, 1e3, -1.0),
        ("FZ", "FZW", "kN", 1e-3, 1e3, -1.0),
        ("MZ", "MZW", "Nm", 1.0, 1.0, -1.0),
        ("SL", "LONGSLIP", "-", 1.0, 1.0, 1.0),
        ("TSTC", "TRDTEMPC", "degC", 1.0, 1.0, 1.0),
    ];
    let mut s = format!(
        "**HEADER\nRELEASE   1.3\nMEASID    m{id}\nMANUFACT  Fixture\nTYRESIZE  20.5x7.0-13\n\n**COMMENTS\nforeign file\n\n**CONSTANTS\n"
    );
    let _ = writeln!(s, "{:<10}{:<30}{:<10}1.1", "FNOMIN", "Nominal load", "kN");
    let _ = writeln!(s, "{:<10}{:<30}{:<10}Drive/Brake/Combined", "TESTMETH", "Test method", "-");
    s.push_str("\n**MEASURCHNLS\n");
    for (_, name, unit, _, factor, _) in &map {
        let offset = if *unit == "degC" { " 273.15" } else { "" };
        let _ = writeln!(s, "{name:<10}{:<30}{unit:<10}{factor}{offset}", "channel");
    }
    s.push_str("\n**MEASURDATA\n");
    for r in rows {
        for (ttc, _, _, scale, _, sign) in &map {
            let v = t.column(ttc).unwrap().values[r];
            let _ = write!(s, "{:.10e} ", v * scale * sign);
        }
        s.push('\n');
    }
    s.push_str("**END\n");
    s
}

#[test]
fn folder_of_foreign_tydex_files_gives_the_ttc_sweeps() {
    let run = ttc_run(&FixtureSpec::drive_brake());
    let t = &run.table;
    let (d, r) =
        read_bytes(to_dat(t, DatLayout::default()).as_bytes(), "db.dat", FileFormat::Dat, &ReadOptions::default())
            .unwrap();
    let dir = tempfile::tempdir().unwrap();
    // One file per sweep, 1 s of rolling either side, as a rig writes one measurement.
    for (i, s) in d.segments.iter().enumerate() {
        let o = s.origin.as_ref().unwrap();
        let (a, b) = (o.first_row - 4, o.last_row - 4 + 1);
        let rows = a.saturating_sub(50)..(b + 50).min(t.rows());
        std::fs::write(dir.path().join(format!("m{i:02}.tdx")), foreign_tdx(t, rows, i)).unwrap();
    }
    let imp = read_path(dir.path(), &ReadOptions::default()).unwrap();
    eprintln!("{}", imp.inspection.to_text(false));
    assert_eq!(imp.inspection.files.len(), d.segments.len());
    assert!(imp.dataset.fnomin_n.is_some_and(|f| (f - 1100.0).abs() < 1e-6), "{:?}", imp.dataset.fnomin_n);
    // The warm-up file holds two back-to-back conditioning sweeps: judged across the folder,
    // both are conditioning (the .dat merged them into one warm-up).
    let warm = |d: &Dataset| d.segments.iter().filter(|s| s.kind == DataKind::WarmUp).count();
    assert_eq!((warm(&imp.dataset), warm(&d)), (2, 1));
    let fitted = |d: &Dataset| d.segments.iter().filter(|s| s.kind == DataKind::Sweep).cloned().collect::<Vec<_>>();
    let (got, want) = (fitted(&imp.dataset), fitted(&d));
    assert_eq!(
        got.iter().map(|s| s.cell.unwrap().kind).collect::<Vec<_>>(),
        want.iter().map(|s| s.cell.unwrap().kind).collect::<Vec<_>>()
    );
    for (x, y) in got.iter().zip(&want) {
        assert_eq!(x.sweep, y.sweep);
        let (cx, cy) = (x.cell.unwrap(), y.cell.unwrap());
        assert!(
            (cx.fz_n - cy.fz_n).abs() < 5.0
                && (cx.p_pa - cy.p_pa).abs() < 300.0
                && (cx.alpha_rad - cy.alpha_rad).abs() < 1e-3,
            "{} vs {}",
            x.sweep,
            y.sweep
        );
    }
    let f = &imp.inspection.files[0];
    assert_eq!(f.convention, "ISO-W");
    assert_eq!(f.tire_id.as_deref(), Some("Fixture 20.5x7.0-13"));
    assert_eq!(f.test_kind_stated.as_deref(), Some("drive/brake/combined"));
    assert!(r.rows > 0);
}

#[test]
fn imported_dataset_survives_the_mcap_log_with_its_cells() {
    let run = ttc_run(&FixtureSpec::cornering());
    let d = import_dat(&run.table, "c.dat");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("c.mcap");
    mffit::logs::write_log(&p, &d).unwrap();
    let back = mffit::logs::read_log(&p).unwrap();
    assert_eq!(back.segments.len(), d.segments.len());
    for (a, b) in d.segments.iter().zip(&back.segments) {
        assert_eq!((a.kind, a.procedure, &a.sweep, &a.origin), (b.kind, b.procedure, &b.sweep, &b.origin));
        // Through JSON the cell keeps its values to the last digit or two.
        let (x, y) = (a.cell.unwrap(), b.cell.unwrap());
        assert_eq!(x.kind, y.kind);
        for (u, v) in [
            (x.fz_n, y.fz_n),
            (x.p_pa, y.p_pa),
            (x.gamma_rad, y.gamma_rad),
            (x.alpha_rad, y.alpha_rad),
            (x.vx_mps, y.vx_mps),
            (x.slip_reach, y.slip_reach),
        ] {
            assert!((u - v).abs() <= 1e-12 * u.abs().max(1e-9), "{u} vs {v}");
        }
        assert_eq!(a.samples.len(), b.samples.len());
    }
}
