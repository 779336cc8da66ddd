//! Every round's quirks from `../shared/real-rig-data.md` ("Differences between rounds and
//! runs"), each read from a synthetic TTC-like run that has it (`rigdata::fixture`): unit
//! spellings, a `.mat` without units, US units, `SR` in cornering/camber tests of older rounds,
//! load wandering during sweeps, camber sweeps, pure longitudinal runs to ±0.65, warm-up sweeps
//! opening a drive/brake run, a run begun on a cold tyre — and `inspect` accounting for every row of each.

use mffit::{DataKind, Dataset, Procedure, SweepKind};
use rigdata::fixture::{CamberSweep, FixtureRun, FixtureSpec, UnitStyle, ttc_run};
use rigdata::import::{CAMBER_SECTION, FileFormat, ReadOptions, read_bytes};
use rigdata::inspect::{FileReport, Inspection};
use rigdata::mat::{MatUnits, MatWriteOptions, to_mat};
use rigdata::sweeps::Conditioning;
use rigdata::table::{DatLayout, to_dat};

fn import(bytes: &[u8], name: &str, format: FileFormat) -> (Dataset, FileReport) {
    read_bytes(bytes, name, format, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn import_dat(run: &FixtureRun, name: &str) -> (Dataset, FileReport) {
    import(to_dat(&run.table, DatLayout::default()).as_bytes(), name, FileFormat::Dat)
}

fn excluded(r: &FileReport, why: &str) -> usize {
    r.excluded.iter().filter(|e| e.0.starts_with(why)).map(|e| e.1).sum()
}

/// Every row in a sweep, a conditioning sweep or excluded with a reason, and the text report
/// says they add up.
fn assert_accounted(r: &FileReport) {
    let total = r.rows_in_sweeps + r.rows_in_conditioning + r.excluded.iter().map(|e| e.1).sum::<usize>();
    assert_eq!(total, r.rows, "{}: rows not accounted for", r.file);
    let text = Inspection { files: vec![r.clone()] }.to_text(true);
    assert!(text.contains(&format!("rows        {} = ", r.rows)) && !text.contains("DO NOT ADD UP"), "{text}");
}

/// Every planned sweep found, in order, with its kind, conditioning flag and cell.
fn assert_found(run: &FixtureRun, d: &Dataset, r: &FileReport) {
    eprintln!("{}", Inspection { files: vec![r.clone()] }.to_text(true));
    let names: Vec<&str> = d.segments.iter().map(|s| s.sweep.as_str()).collect();
    assert_eq!(d.segments.len(), run.sweeps.len(), "sweeps found vs planned: {names:?}");
    for (p, s) in run.sweeps.iter().zip(&d.segments) {
        let c = s.cell.expect("cell");
        assert_eq!(c.kind, p.kind, "{}", s.sweep);
        assert_eq!(s.section == CAMBER_SECTION, p.camber_sweep, "{}: camber sweep", s.sweep);
        assert_eq!(s.kind == DataKind::WarmUp, p.conditioning, "{}: conditioning", s.sweep);
        let fz_tol = if p.camber_sweep || p.kind == SweepKind::Cornering { 0.04 } else { 0.03 };
        assert!((c.fz_n - p.fz_n).abs() < fz_tol * p.fz_n, "{}: FZ {} vs {}", s.sweep, c.fz_n, p.fz_n);
        assert!((c.p_pa / 1e3 - p.p_kpa).abs() < 1.0, "{}: P {} kPa vs {}", s.sweep, c.p_pa / 1e3, p.p_kpa);
        assert!((c.gamma_rad.to_degrees() - p.ia_deg).abs() < 0.15, "{}: IA", s.sweep);
        assert!((c.alpha_rad.to_degrees() - p.sa_deg).abs() < 0.15, "{}: SA {}", s.sweep, c.alpha_rad.to_degrees());
        assert!((c.vx_mps * 3.6 - 40.0).abs() < 1.0, "{}: V {} kph", s.sweep, c.vx_mps * 3.6);
        // Temperatures in °C (a cold start's conditioning sweeps may read below 30 °C).
        let t_min = if s.kind == DataKind::WarmUp { 0.0 } else { 30.0 };
        assert!(s.samples.iter().all(|x| x.fz_n > 0.0 && x.p_pa > 5e4 && x.temp_c > t_min && x.temp_c < 110.0));
    }
    assert_accounted(r);
}

#[test]
fn a_later_rounds_unit_spellings_are_read() {
    // `sec`, `Nm`, `deg C`, `deg F` (AMBTMP) and `SAE` for SL: refused before (`channel SL:
    // unknown unit 'SAE'`).
    let run = ttc_run(&FixtureSpec { units: UnitStyle::LaterRound, ..FixtureSpec::drive_brake() });
    let (d, r) = import_dat(&run, "later_round_db.dat");
    assert_found(&run, &d, &r);
    let used = |n: &str| r.channels.iter().find(|c| c.name == n).map(|c| (c.unit_read.clone(), c.used_as.clone()));
    assert_eq!(used("SL"), Some(("SAE".into(), "LONGSLIP [-]".into())));
    assert_eq!(used("ET").unwrap().0, "sec");
    assert_eq!(used("MZ").unwrap().0, "Nm");
    assert_eq!(used("TSTC").unwrap().0, "deg C");
    assert!(r.slip_ratio_from.starts_with("SL"), "{}", r.slip_ratio_from);
    // The slip-ratio sweeps reach 0.2 (SL read as a plain ratio).
    assert!(r.sweeps.iter().filter(|s| !s.conditioning).all(|s| (s.reach - 0.2).abs() < 0.02), "{:?}", r.sweeps);
    // AMBTMP honestly in °F is converted, not flagged as °F written under a °C label.
    assert!(!r.warnings.iter().any(|w| w.message.contains("surely degF")), "{:?}", r.warnings);
    assert!(r.warnings.iter().all(|w| !w.message.contains("unknown unit")), "{:?}", r.warnings);
}

#[test]
fn a_mat_file_without_units_is_read_in_ttc_units() {
    // `.mat` files carry no units line at all: the TTC units are assumed and checked.
    let run = ttc_run(&FixtureSpec { units: UnitStyle::LaterRound, ..FixtureSpec::cornering() });
    let mat = to_mat(&run.table, &MatWriteOptions::default()).unwrap();
    let (d, r) = import(&mat, "later_round_cornering.mat", FileFormat::Mat);
    assert_found(&run, &d, &r);
    assert!(r.channels.iter().all(|c| c.unit_written.is_empty()));
    assert!(r.warnings.iter().any(|w| w.message.contains("TTC units assumed")), "{:?}", r.warnings);
    assert!(!r.warnings.iter().any(|w| w.message.contains("US customary")), "{:?}", r.warnings);
}

#[test]
fn ttc_uscs_runs_read_in_si_with_their_units_list_or_without_any() {
    // TTC distributes every run in SI and in "USCS" (lb, psi, in, mph, ft-lb, deg F); its `.mat`
    // files list the units in a struct `channel` (`name`, `units`: cells of strings), and a run
    // saved without that list must be told from its magnitudes. Read either way, the run is the
    // SI run: the same sweeps and the same values.
    for spec in [FixtureSpec::cornering(), FixtureSpec::drive_brake()] {
        let si_run = ttc_run(&spec);
        let (si, _) = import(&to_mat(&si_run.table, &MatWriteOptions::default()).unwrap(), "si.mat", FileFormat::Mat);
        let run = ttc_run(&FixtureSpec { units: UnitStyle::Uscs, ..spec });
        for units in [MatUnits::ChannelStruct, MatUnits::Unlisted] {
            let mat = to_mat(&run.table, &MatWriteOptions { units, ..Default::default() }).unwrap();
            let (d, r) = import(&mat, "uscs.mat", FileFormat::Mat);
            assert_found(&run, &d, &r);
            assert_eq!(d.segments.len(), si.segments.len());
            for (a, b) in si.segments.iter().zip(&d.segments) {
                assert_eq!(a.sweep, b.sweep);
                for (p, q) in a.samples.iter().zip(&b.samples) {
                    for (what, u, v) in [
                        ("FZ", p.fz_n, q.fz_n),
                        ("FX", p.fx_n, q.fx_n),
                        ("FY", p.fy_n, q.fy_n),
                        ("MZ", p.mz_nm, q.mz_nm),
                        ("RL", p.rl_m, q.rl_m),
                        ("P", p.p_pa, q.p_pa),
                        ("V", p.vx_mps, q.vx_mps),
                        ("T", p.temp_c, q.temp_c),
                    ] {
                        assert!((u - v).abs() <= 1e-6 * u.abs().max(1.0), "{units:?} {}: {what} {u} vs {v}", a.sweep);
                    }
                }
            }
            let unit = |n: &str| r.channels.iter().find(|c| c.name == n).unwrap().clone();
            match units {
                MatUnits::ChannelStruct => {
                    assert_eq!(unit("FZ").unit_written, "lb");
                    assert_eq!(unit("MZ").unit_written, "ft-lb");
                    assert!(r.layout.as_deref().unwrap_or("").contains("units of 22 channels from `channel`"), "{r:?}");
                    assert!(!r.warnings.iter().any(|w| w.message.contains("assumed")), "{:?}", r.warnings);
                }
                _ => {
                    assert!(unit("FZ").unit_written.is_empty());
                    assert_eq!(
                        [unit("FZ").unit_read, unit("MZ").unit_read, unit("V").unit_read],
                        ["lbf", "lbf-ft", "mph"]
                    );
                    let w = r.warnings.iter().find(|w| w.message.contains("read as US customary")).expect("warning");
                    assert!(w.message.contains("as mph and inches"), "{w:?}");
                }
            }
        }
    }
}

#[test]
fn us_units_are_converted_where_the_file_says_so() {
    // mph, in, psi, lbf, degF: the cells come out in N, kPa, kph as planned (checked in
    // `assert_found`), the radius in metres and the tread temperature in °C.
    for spec in [FixtureSpec::cornering(), FixtureSpec::drive_brake()] {
        let run = ttc_run(&FixtureSpec { units: UnitStyle::Imperial, ..spec });
        let (d, r) = import_dat(&run, "imperial.dat");
        assert_found(&run, &d, &r);
        let s = &d.segments[1].samples;
        let rl = s.iter().map(|x| x.rl_m).sum::<f64>() / s.len() as f64;
        assert!((0.24..0.26).contains(&rl), "RL {rl} m");
        let unit = |n: &str| r.channels.iter().find(|c| c.name == n).unwrap().unit_read.clone();
        assert_eq!([unit("V"), unit("P"), unit("FZ"), unit("RL"), unit("TSTC")], ["mph", "psi", "lbf", "in", "degF"]);
    }
}

#[test]
fn an_older_rounds_cornering_and_camber_run_reads_sr_as_no_slip_ratio() {
    // No SL, no NFX, no testid, a title without a tyre name; SR grows with slip angle and load
    // while the wheel rolls free; the load wanders ±15 % during the sweeps; a camber sweep at
    // 1.8° slip angle ends each pressure.
    let spec = FixtureSpec {
        older_round: true,
        fz_wander: 0.15,
        camber_sweep: Some(CamberSweep { sa_deg: 1.8, cambers_deg: vec![0.0, 1.0, 2.0, 3.0, 4.0] }),
        ..FixtureSpec::cornering()
    };
    let run = ttc_run(&spec);
    assert!(run.table.column("SL").is_none() && run.table.column("NFX").is_none() && run.table.test_id.is_none());
    let (d, r) = import_dat(&run, "older_round_cornering.dat");
    assert_found(&run, &d, &r);
    assert!(r.slip_ratio_from.starts_with("SR"), "{}", r.slip_ratio_from);
    assert!(d.segments.iter().all(|s| s.procedure == Procedure::FreeRolling));
    assert!(d.segments.iter().flat_map(|s| &s.samples).all(|x| x.kappa == 0.0));
    // SR reached well beyond the slip-ratio threshold inside the sweeps, and none of it became
    // a slip ratio.
    let sr_min = run.table.column("SR").unwrap().values.iter().filter(|v| **v > -0.5).fold(0.0_f64, |m, v| m.min(*v));
    assert!(sr_min < -0.05, "SR reaches {sr_min}");
}

#[test]
fn a_load_wandering_during_sweeps_stays_one_sweep_at_one_cell() {
    // With a rest at the cell after each sweep, and with the next load set right as a sweep
    // comes back to zero.
    for settle in [true, false] {
        let base = FixtureSpec { no_settle_after_sweeps: !settle, ..FixtureSpec::cornering() };
        let clean = ttc_run(&base);
        let (_, rc) = import_dat(&clean, "clean.dat");
        let run = ttc_run(&FixtureSpec { fz_wander: 0.2, ..base });
        let (d, r) = import_dat(&run, "wander.dat");
        // Every sweep found, its cell at its setpoint (medians), conditioning ones included.
        assert_found(&run, &d, &r);
        // Each point keeps its measured load: the sweep at 1,100 N holds points below 1,000 and
        // above 1,250 N.
        let s = d.segments.iter().find(|s| s.kind == DataKind::Sweep && (s.cell.unwrap().fz_n - 1100.0).abs() < 50.0);
        let fz: Vec<f64> = s.unwrap().samples.iter().map(|x| x.fz_n).collect();
        assert!(fz.iter().any(|f| *f < 1000.0) && fz.iter().any(|f| *f > 1250.0), "settle {settle}");
        // No more rows lost to "load ramp" or "slip angle set" than in the same run with a
        // steady load (the ramps between cells), and as many rows in sweeps within 3 %.
        let what = format!("settle {settle}: {:?} vs {:?}", r.excluded, rc.excluded);
        assert!(excluded(&r, "load ramp") <= excluded(&rc, "load ramp") + 20, "{what}");
        assert!(excluded(&r, "slip angle set") <= excluded(&rc, "slip angle set") + 20, "{what}");
        assert!(excluded(&r, "incomplete") <= excluded(&rc, "incomplete") + 20, "{what}");
        let in_sweeps = |r: &FileReport| (r.rows_in_sweeps + r.rows_in_conditioning) as f64;
        assert!((in_sweeps(&r) / in_sweeps(&rc) - 1.0).abs() < 0.03, "{} vs {}: {what}", in_sweeps(&r), in_sweeps(&rc));
    }
}

#[test]
fn camber_sweeps_at_a_held_slip_angle_are_their_own_kind() {
    let spec = FixtureSpec {
        cambers_deg: vec![0.0, 2.0],
        camber_sweep: Some(CamberSweep { sa_deg: 1.8, cambers_deg: vec![0.0, 1.0, 2.0, 3.0, 4.0] }),
        ..FixtureSpec::cornering()
    };
    let run = ttc_run(&spec);
    let (d, r) = import_dat(&run, "camber.dat");
    assert_found(&run, &d, &r);
    let camber: Vec<_> = d.segments.iter().filter(|s| s.section == CAMBER_SECTION).collect();
    assert_eq!(camber.len(), 2, "one per pressure");
    for s in camber {
        // Free-rolling force & moment data at five cambers: the fitter's cornering stages take
        // it (its camber terms).
        assert_eq!((s.procedure, s.kind), (Procedure::FreeRolling, DataKind::Sweep), "{}", s.sweep);
        let (lo, hi) = s
            .samples
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(x.gamma_rad.to_degrees()), h.max(x.gamma_rad.to_degrees())));
        assert!(lo < 0.2 && hi > 3.8, "{}: camber {lo}..{hi}", s.sweep);
        assert!(s.sweep.starts_with("camber P"), "{}", s.sweep);
    }
    assert_eq!(Inspection { files: vec![r.clone()] }.camber_sweeps(), 2);
    assert!(r.sweeps.iter().filter(|s| s.kind == "camber").all(|s| (s.reach - 4.0).abs() < 0.2), "{:?}", r.sweeps);
    // The camber changes between the slip-angle sweeps are still changes of cell.
    assert!(excluded(&r, "camber change") > 0, "{:?}", r.excluded);
}

#[test]
fn pure_longitudinal_runs_to_large_slip_ratios_are_drive_brake_sweeps() {
    let spec = FixtureSpec {
        loads_n: vec![1100.0, 660.0, 1540.0],
        cambers_deg: vec![0.0],
        slip_angles_deg: vec![0.0],
        kappa_reach: 0.65,
        sweep_s: 8.0,
        ..FixtureSpec::drive_brake()
    };
    // With SL, and in an older round's file with only SR (the wheel driven and braked: SR is
    // the slip ratio there).
    for (older, name) in [(false, "long_065.dat"), (true, "long_065_sr.dat")] {
        let mut run = ttc_run(&FixtureSpec { older_round: older, ..spec.clone() });
        let (mut d, r) = import_dat(&run, name);
        if older {
            // SR's offset and noise hide the short 0.04 conditioning sweeps (excluded either way).
            run.sweeps.retain(|s| !s.conditioning);
            d.segments.retain(|s| s.kind != DataKind::WarmUp);
            assert!(r.slip_ratio_from.starts_with("SR"));
        }
        assert_found(&run, &d, &r);
        assert!(d.segments.iter().all(|s| s.cell.unwrap().kind == SweepKind::DriveBrake));
        let reach: Vec<f64> = r.sweeps.iter().filter(|s| !s.conditioning).map(|s| s.reach).collect();
        assert!(reach.iter().all(|k| (0.6..0.72).contains(k)), "{name}: {reach:?}");
    }
}

#[test]
fn warm_up_sweeps_opening_a_drive_brake_run_are_conditioning() {
    // Five full sweeps at 1,100 N open the run; 1,100 N is swept again after 660 N.
    let spec = FixtureSpec { loads_n: vec![660.0, 1100.0], warmup_sweeps: 5, ..FixtureSpec::drive_brake() };
    let run = ttc_run(&spec);
    assert_eq!(run.sweeps.iter().filter(|s| s.conditioning).count(), 5);
    let (d, r) = import_dat(&run, "warmup_db.dat");
    assert_found(&run, &d, &r);
    assert_eq!(r.conditioning_sweeps, 5, "{:?}", r.sweeps);
    assert!(
        r.sweeps
            .iter()
            .filter(|s| s.conditioning)
            .all(|s| s.conditioning_reason.as_deref() == Some("leading sweeps at a cell swept again later")),
        "{:?}",
        r.sweeps
    );
    let text = Inspection { files: vec![r.clone()] }.to_text(false);
    assert!(text.contains("conditioning 5 sweeps open the run at a cell swept again later"), "{text}");
    // Left out of the fit: warm-up segments are not force & moment data.
    assert_eq!(d.segments.iter().filter(|s| s.kind == DataKind::WarmUp).count(), 5);
    // The same run without the warm-up: nothing marked beyond the short conditioning sweeps.
    let plain = ttc_run(&FixtureSpec { loads_n: vec![660.0, 1100.0], ..FixtureSpec::drive_brake() });
    let (_, rp) = import_dat(&plain, "plain_db.dat");
    assert!(
        rp.sweeps
            .iter()
            .all(|s| s.conditioning_reason.as_deref() != Some("leading sweeps at a cell swept again later"))
    );
}

#[test]
fn inspect_accounts_for_lines_it_could_not_read() {
    let run = ttc_run(&FixtureSpec { pressures_kpa: vec![83.0], ..FixtureSpec::cornering() });
    let text = to_dat(&run.table, DatLayout { decimals: 4, crlf: false });
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    // A comment line and a row missing its last values, mid-file.
    lines.insert(500, "# operator note: belt cleaned".into());
    let short = lines[900].split('\t').take(10).collect::<Vec<_>>().join("\t");
    lines[900] = short;
    let (_, r) = import(lines.join("\n").as_bytes(), "odd.dat", FileFormat::Dat);
    assert_accounted(&r);
    assert_eq!(r.rows + 2, lines.len() - 3, "data lines = rows + lines not read");
    assert_eq!(r.lines_not_read, vec![("not a row of numbers".to_owned(), 1), ("values missing".to_owned(), 1)]);
    let text = Inspection { files: vec![r.clone()] }.to_text(false);
    assert!(text.contains("lines not read as rows"), "{text}");
    assert!(r.warnings.iter().any(|w| w.to_string().starts_with("odd.dat:901")), "{:?}", r.warnings);
}

#[test]
fn sweeps_begun_on_a_cold_tyre_are_conditioning_where_their_cell_is_swept_again() {
    // The tread starts 30 K below its running temperature; the first full sweep (1,100 N) is
    // swept again at the end of the pressure, the second (660 N) only at the other pressure.
    let spec = FixtureSpec { cold_start_k: 30.0, ..FixtureSpec::cornering() };
    let run = ttc_run(&spec);
    let (d, r) = import_dat(&run, "cold_start_cornering.dat");
    assert_found(&run, &d, &r);
    let cold: Vec<&rigdata::inspect::SweepRow> =
        r.sweeps.iter().filter(|s| s.conditioning_reason.as_deref() == Some(Conditioning::ColdStart.name())).collect();
    assert_eq!(cold.len(), 1, "{:#?}", r.sweeps);
    assert!((cold[0].fz_n - 1100.0).abs() < 60.0 && (cold[0].p_kpa - 83.0).abs() < 2.0, "{:?}", cold[0]);
    let first_fitted = r.sweeps.iter().find(|s| !s.conditioning).expect("a fitted sweep");
    let (t_cold, t_next) = (cold[0].tread_start_c.expect("tread"), first_fitted.tread_start_c.expect("tread"));
    assert!(t_next - t_cold > 5.0, "{t_cold} → {t_next}");
    let text = Inspection { files: vec![r.clone()] }.to_text(false);
    assert!(text.contains("conditioning 1 sweep begun before the tread temperature settled (at 34 °C"), "{text}");
    // The same run on a tyre brought to temperature first: no cold start.
    let (_, warm) = import_dat(&ttc_run(&FixtureSpec::cornering()), "warm_cornering.dat");
    assert!(warm.sweeps.iter().all(|s| s.conditioning_reason.as_deref() != Some(Conditioning::ColdStart.name())));
    // Nor in a drive/brake run whose tread climbs tens of kelvin through the run.
    let (_, db) = import_dat(&ttc_run(&FixtureSpec::drive_brake()), "db.dat");
    assert!(db.sweeps.iter().all(|s| s.conditioning_reason.as_deref() != Some(Conditioning::ColdStart.name())));
}

#[test]
fn runs_sampled_at_100_hz_read_to_the_same_sweeps_as_at_50() {
    // Newer rounds log at 100 Hz. Every planned sweep is found with its cell, kind and
    // conditioning flag, and every row accounted for, as at 50 Hz: the reader's time
    // thresholds are in seconds, not rows.
    let specs = [
        ("cornering", FixtureSpec::cornering()),
        ("drive_brake", FixtureSpec::drive_brake()),
        ("wander_no_settle", FixtureSpec { fz_wander: 0.2, no_settle_after_sweeps: true, ..FixtureSpec::cornering() }),
        (
            "older_round_camber",
            FixtureSpec {
                older_round: true,
                fz_wander: 0.15,
                camber_sweep: Some(CamberSweep { sa_deg: 1.8, cambers_deg: vec![0.0, 1.0, 2.0, 3.0, 4.0] }),
                ..FixtureSpec::cornering()
            },
        ),
        ("warmup", FixtureSpec { loads_n: vec![660.0, 1100.0], warmup_sweeps: 5, ..FixtureSpec::drive_brake() }),
        // Cornering at cambers from −1 to 4°, as some rounds run it.
        ("cambers_minus1_to_4", FixtureSpec { cambers_deg: vec![-1.0, 0.0, 2.0, 4.0], ..FixtureSpec::cornering() }),
    ];
    for (name, spec) in specs {
        let at_50 = ttc_run(&spec);
        let at_100 = ttc_run(&FixtureSpec { rate_hz: 100.0, ..spec });
        assert!(at_100.table.rows() > at_50.table.rows() * 19 / 10, "{name}: {} rows", at_100.table.rows());
        let (d50, r50) = import_dat(&at_50, &format!("{name}_50hz.dat"));
        let (d100, r100) = import_dat(&at_100, &format!("{name}_100hz.dat"));
        assert_found(&at_100, &d100, &r100);
        assert_eq!(r100.conditioning_sweeps, r50.conditioning_sweeps, "{name}");
        assert_eq!(d100.segments.len(), d50.segments.len(), "{name}");
        // Twice the rows in sweeps, within a few per cent (edges are found to a sample).
        let ratio = r100.rows_in_sweeps as f64 / r50.rows_in_sweeps as f64;
        assert!((ratio - 2.0).abs() < 0.06, "{name}: rows in sweeps {} vs {}", r100.rows_in_sweeps, r50.rows_in_sweeps);
    }
}

#[test]
fn camber_sweeps_free_camber_terms_a_run_at_camber_0_holds() {
    // An older round's cornering run at camber 0 whose only camber data are its camber sweeps
    // (camber stepped 0–4° at 1.8° slip angle): the fitter's lateral stages take those sweeps,
    // fit the camber terms that the same run without them holds for want of camber levels, and
    // predict the tyre's cornering at 2° and 4° camber (a run the fit never saw) better.
    let base = FixtureSpec { cambers_deg: vec![0.0], older_round: true, ..FixtureSpec::cornering() };
    let camber = CamberSweep { sa_deg: 1.8, cambers_deg: vec![0.0, 1.0, 2.0, 3.0, 4.0] };
    let opts = mffit::FitOptions { folds: 0, ..mffit::FitOptions::default() };
    let (at_camber, _) =
        import_dat(&ttc_run(&FixtureSpec { cambers_deg: vec![2.0, 4.0], ..base.clone() }), "cambered.dat");
    let fit = |spec: &FixtureSpec, name: &str| {
        let (d, _) = import_dat(&ttc_run(spec), name);
        let r = mffit::fit(&d, &opts).unwrap();
        assert!(r.nonphysical_stages().is_empty(), "{name}: {:?}", r.warnings);
        let fy = r.stages.iter().find(|s| s.stage == "fy_pure").unwrap();
        let held: Vec<(String, String)> = fy.held.iter().map(|h| (h.key.clone(), h.reason.clone())).collect();
        let fitted: Vec<String> = fy.estimates.iter().map(|e| e.key.clone()).collect();
        let on_camber =
            mffit::stages::validate(&r, &at_camber, &opts).into_iter().find(|v| v.stage == "fy_pure").unwrap();
        (fitted, held, on_camber.nrmse_pct)
    };
    let (_, held_without, camber_nrmse_without) = fit(&base, "camber0.dat");
    let (fitted_with, held_with, camber_nrmse_with) =
        fit(&FixtureSpec { camber_sweep: Some(camber), ..base.clone() }, "camber0_sweeps.dat");
    // Camber thrust at small slip (what a sweep at one slip angle shows): fitted from them.
    for k in ["PKY6", "PKY7"] {
        assert!(held_without.iter().any(|(h, why)| h == k && why.contains("camber level")), "{k}: {held_without:?}");
        assert!(fitted_with.iter().any(|f| f == k), "{k} not fitted from the camber sweeps: {fitted_with:?}");
    }
    // What shapes the slip curve with camber (its peak, curvature, shift) is not: one point of
    // each camber's curve cannot tell those terms apart.
    for k in ["PDY3", "PEY4", "PKY3", "PVY3"] {
        let why =
            held_with.iter().find(|(h, _)| h == k).map(|(_, w)| w.as_str()).unwrap_or_else(|| panic!("{k} fitted"));
        assert!(why.contains("with the slip swept"), "{k}: {why}");
    }
    eprintln!(
        "FY pure at cambers 2 and 4°: {camber_nrmse_without:.2} % without camber sweeps, {camber_nrmse_with:.2} % with"
    );
    assert!(camber_nrmse_with < 0.8 * camber_nrmse_without, "{camber_nrmse_with} vs {camber_nrmse_without}");
}
