//! The TTC-style export of a virtual rig run has every quirk of real run files: channels and
//! units, SAE signs against the ISO-W samples, 50 Hz, the title line, SL exactly 0 unless
//! coupled, SR noisy and off zero in cornering and ≈ −0.9 at standstill, RE nonsense near
//! standstill, AMBTMP in degF labelled degC, the options to drop channels.

use std::path::PathBuf;

use rigdata::import::{FileFormat, ReadOptions, read_bytes};
use rigdata::virtual_export::{
    ForceUnit, PressureUnit, TtcExportOptions, UnitSpelling, VirtualRun, export_ttc, to_dat_compact,
};
use rigdata::{ChannelTable, Column};
use rigsim::{Effects, RigConfig, RigSample, RigSetpoint, VirtualRig, VirtualTyre};
use tyre_msgs::ProcedureState;
use tyre_msgs::builtin_interfaces::Time;
use tyre_msgs::std_msgs::Header;

const FZ: f64 = 1100.0;
const P_PA: f64 = 84_000.0;
const V: f64 = 11.1;

/// Which part of the hand-made programme a sample belongs to.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Part {
    Standstill,
    Ramp,
    Cornering,
    DriveBrake,
}

/// A short TTC-like programme on the brush race tyre, driven directly: standstill with load,
/// roll up, two slip-angle sweeps to ±13°, a slip-ratio sweep to ±0.2 at 3°, stop, standstill.
fn programme() -> (VirtualRun, Vec<(f64, Part)>) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../launch-config/virtual_rig_brush_race.toml");
    let mut cfg = RigConfig::load(&path).expect("race rig config");
    cfg.effects = Effects::parse("transient,thermal,noise").unwrap();
    let tyre = VirtualTyre::load(&cfg).expect("brush tyre");
    let mut rig = VirtualRig::new(cfg, tyre, 7).expect("rig");
    let mut samples: Vec<RigSample> = Vec::new();
    let mut parts: Vec<(f64, Part)> = Vec::new();
    let mut drive = |rig: &mut VirtualRig, until: f64, part: Part, sp: &dyn Fn(f64) -> RigSetpoint| {
        while rig.time_s() < until - 1e-9 {
            let t = rig.time_s();
            let _ = rig.apply_setpoint(&sp(t));
            rig.run_until(t + 0.01, &mut |s| {
                samples.push(s.clone());
                parts.push((s.runtime_s, part));
            });
        }
    };
    let base = |mode: u8, sa: f64, sr: f64, speed: f64| RigSetpoint {
        mode,
        slip_angle_deg: sa,
        slip_ratio: sr,
        fz_n: FZ,
        pressure_pa: P_PA,
        speed_mps: speed,
        ..RigSetpoint::default()
    };
    let fr = RigSetpoint::MODE_FREE_ROLLING;
    drive(&mut rig, 1.0, Part::Ramp, &|_| base(fr, 0.0, 0.0, 0.0));
    drive(&mut rig, 6.0, Part::Standstill, &|_| base(fr, 0.0, 0.0, 0.0));
    drive(&mut rig, 14.0, Part::Ramp, &|_| base(fr, 0.0, 0.0, V));
    // Triangle 0 → −13 → +13 → 0 at 3.5 °/s, twice.
    let tri = |t: f64| {
        let u = (t * 3.5) % 52.0;
        if u < 13.0 {
            -u
        } else if u < 39.0 {
            u - 26.0
        } else {
            52.0 - u
        }
    };
    let t0 = 14.0;
    drive(&mut rig, t0 + 2.0 * 52.0 / 3.5, Part::Cornering, &|t| base(fr, tri(t - t0), 0.0, V));
    drive(&mut rig, 46.0, Part::Ramp, &|_| base(RigSetpoint::MODE_COUPLED, 3.0, 0.0, V));
    let t1 = 46.0;
    let sr = |t: f64| {
        let u = ((t - t1) * 0.15) % 0.8;
        if u < 0.2 {
            -u
        } else if u < 0.6 {
            u - 0.4
        } else {
            0.8 - u
        }
    };
    drive(&mut rig, t1 + 0.8 / 0.15, Part::DriveBrake, &|t| base(RigSetpoint::MODE_COUPLED, 3.0, sr(t), V));
    drive(&mut rig, 62.0, Part::Ramp, &|_| base(fr, 0.0, 0.0, 0.0));
    drive(&mut rig, 68.0, Part::Standstill, &|_| base(fr, 0.0, 0.0, 0.0));
    let state = |t: f64, phase: u8| ProcedureState {
        header: Header { stamp: Time::from_secs_f64(t), frame_id: String::new() },
        phase,
        procedure: "ttc_test".into(),
        ..ProcedureState::default()
    };
    let mut run = VirtualRun {
        source: "test programme".into(),
        samples,
        states: vec![state(0.995, ProcedureState::PHASE_SETTLE), state(68.0, ProcedureState::PHASE_COMPLETE)],
        ..VirtualRun::default()
    };
    let md = |pairs: &[(&str, &str)]| pairs.iter().map(|(k, v)| ((*k).to_owned(), (*v).to_owned())).collect();
    run.metadata
        .insert("tyre".into(), md(&[("name", "tyrerig brush race 20.5x7.0-13 (virtual)"), ("rim_width_in", "7")]));
    run.metadata.insert("procedure".into(), md(&[("title", "Cornering, Various pressures")]));
    run.metadata.insert("rig".into(), md(&[("ambient_temp_c", "30"), ("belt_temp_c", "32")]));
    (run, parts)
}

fn col<'a>(t: &'a ChannelTable, name: &str) -> &'a [f64] {
    &t.column(name).unwrap_or_else(|| panic!("channel {name}")).values
}

/// Rows of one part: both samples of the row's block belong to it.
fn rows_of(t: &ChannelTable, parts: &[(f64, Part)], run: &VirtualRun, part: Part) -> Vec<usize> {
    let t0 = run.samples.iter().find(|s| s.runtime_s >= 0.995).unwrap().runtime_s;
    let start = parts.iter().position(|p| p.0 >= t0).unwrap();
    let is = |k: usize| parts.get(k).is_some_and(|p| p.1 == part);
    (0..t.rows()).filter(|i| is(start + 2 * i) && is(start + 2 * i + 1)).collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn channels_units_rate_and_title_are_those_of_a_ttc_file() {
    let (run, _) = programme();
    let t = export_ttc(&run, &TtcExportOptions::default()).unwrap();
    let names: Vec<&str> = t.columns.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        "ET V N SA IA RL RE P FX FY FZ MX MZ NFX NFY RST TSTI TSTC TSTO AMBTMP SR SL".split(' ').collect::<Vec<_>>()
    );
    let units: Vec<&str> = t.columns.iter().map(|c| c.unit.as_str()).collect();
    assert_eq!(
        units,
        "s kph rpm deg deg cm cm kPa N N N N-m N-m none none degC degC degC degC degC none none"
            .split(' ')
            .collect::<Vec<_>>()
    );
    // 50 Hz from the rig's 100 Hz, starting at 0 when the procedure starts.
    let et = col(&t, "ET");
    assert!(et[0].abs() < 1e-9);
    assert!(et.windows(2).all(|w| (w[1] - w[0] - 0.02).abs() < 1e-9));
    assert!((t.rows() as f64 - 67.0 * 50.0).abs() <= 2.0, "{}", t.rows());
    let title = t.title.as_deref().unwrap();
    assert!(title.starts_with("TIRF Data File: Project 2356; Run 004;"), "{title}");
    assert!(title.contains("Tire_Name=tyrerig brush race 20.5x7.0-13 (virtual)") && title.ends_with("Rim_Width=7.0"));
    assert_eq!(t.tire_id.as_deref(), Some("tyrerig brush race 20.5x7.0-13 (virtual) on 7.0 in. wide rim -- Tire 1"));
    assert_eq!(t.test_id.as_deref(), Some("Cornering, Various pressures"));
    // AMBTMP: degF values (30 °C → 86 °F) under a degC label.
    let amb = col(&t, "AMBTMP");
    assert!(amb.iter().all(|v| (84.0..88.0).contains(v)), "{:?}", &amb[..3]);
    assert_eq!(t.column("AMBTMP").unwrap().unit, "degC");
}

#[test]
fn signs_are_sae_against_the_iso_w_samples() {
    let (run, parts) = programme();
    let t = export_ttc(&run, &TtcExportOptions::default()).unwrap();
    // Block means of the ISO-W samples the rows came from.
    let t0 = run.samples.iter().position(|s| s.runtime_s >= 0.995).unwrap();
    let iso =
        |i: usize, f: &dyn Fn(&RigSample) -> f64| 0.5 * (f(&run.samples[t0 + 2 * i]) + f(&run.samples[t0 + 2 * i + 1]));
    let mut checked = 0;
    for i in rows_of(&t, &parts, &run, Part::Cornering).into_iter().chain(rows_of(&t, &parts, &run, Part::DriveBrake)) {
        let close = |a: f64, b: f64, tol: f64| assert!((a - b).abs() <= tol, "row {i}: {a} vs {b}");
        close(col(&t, "SA")[i], -iso(i, &|s| s.slipangl_deg), 1e-9);
        close(col(&t, "FY")[i], -iso(i, &|s| s.fyw_n), 1e-9);
        close(col(&t, "FZ")[i], -iso(i, &|s| s.fzw_n), 1e-9);
        close(col(&t, "MZ")[i], -iso(i, &|s| s.mzw_nm), 1e-9);
        close(col(&t, "FX")[i], iso(i, &|s| s.fx_n), 1e-9);
        close(col(&t, "MX")[i], iso(i, &|s| s.mxw_nm), 1e-9);
        close(col(&t, "IA")[i], iso(i, &|s| s.inclangl_deg), 1e-9);
        close(col(&t, "RL")[i], 100.0 * iso(i, &|s| s.dstwowhc_m), 1e-9);
        close(col(&t, "V")[i], 3.6 * iso(i, &|s| s.trajvelw_mps), 1e-9);
        close(col(&t, "P")[i], 1e-3 * iso(i, &|s| s.inflpres_pa), 1e-9);
        close(col(&t, "TSTC")[i], iso(i, &|s| s.trdtempc_c), 1e-9);
        close(col(&t, "NFY")[i], col(&t, "FY")[i] / col(&t, "FZ")[i], 1e-12);
        checked += 1;
    }
    assert!(checked > 1000, "{checked}");
    // SAE physics: FZ negative under load; a positive SA gives a negative FY and a positive MZ.
    let corner = rows_of(&t, &parts, &run, Part::Cornering);
    assert!(corner.iter().all(|&i| col(&t, "FZ")[i] < -500.0));
    let (sa, fy, mz) = (col(&t, "SA"), col(&t, "FY"), col(&t, "MZ"));
    let at_sa = |lo: f64, hi: f64| corner.iter().copied().filter(move |&i| (lo..hi).contains(&sa[i]));
    assert!(at_sa(1.0, 2.0).count() > 20 && at_sa(1.0, 2.0).all(|i| fy[i] < 0.0 && mz[i] > 0.0));
    assert!(at_sa(-2.0, -1.0).count() > 20 && at_sa(-2.0, -1.0).all(|i| fy[i] > 0.0 && mz[i] < 0.0));
}

#[test]
fn sl_is_the_rig_slip_ratio_and_exactly_zero_unless_coupled() {
    let (run, parts) = programme();
    let t = export_ttc(&run, &TtcExportOptions::default()).unwrap();
    let sl = col(&t, "SL");
    for part in [Part::Standstill, Part::Cornering] {
        assert!(rows_of(&t, &parts, &run, part).iter().all(|&i| sl[i] == 0.0), "{part:?}");
    }
    let db = rows_of(&t, &parts, &run, Part::DriveBrake);
    let peak = db.iter().map(|&i| sl[i]).fold(0.0, f64::max);
    let low = db.iter().map(|&i| sl[i]).fold(0.0, f64::min);
    assert!(peak > 0.18 && low < -0.18, "{low} .. {peak}");
    // Positive SL drives.
    assert!(db.iter().filter(|&&i| sl[i] > 0.05).all(|&i| col(&t, "FX")[i] > 0.0));
}

#[test]
fn sr_is_noisy_and_off_zero_in_cornering_and_about_minus_point_nine_at_standstill() {
    let (run, parts) = programme();
    let t = export_ttc(&run, &TtcExportOptions::default()).unwrap();
    let sr = col(&t, "SR");
    let corner: Vec<f64> = rows_of(&t, &parts, &run, Part::Cornering).iter().map(|&i| sr[i]).collect();
    let m = median(corner.clone());
    assert!((-0.015..=-0.005).contains(&m), "median SR in cornering {m}");
    let beyond = corner.iter().filter(|v| v.abs() > 0.005).count() as f64 / corner.len() as f64;
    assert!(beyond > 0.6, "share beyond ±0.005: {beyond}");
    // Noisy: row-to-row differences well above the 1e-4 the file resolves.
    let diffs: Vec<f64> = corner.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    assert!(median(diffs) > 0.001);
    let still: Vec<f64> = rows_of(&t, &parts, &run, Part::Standstill).iter().map(|&i| sr[i]).collect();
    assert!(still.len() > 400);
    let ms = median(still.clone());
    assert!((ms + 0.9).abs() < 0.03, "standstill SR {ms}");
    // RE: a radius while rolling, nonsense at standstill.
    let re = col(&t, "RE");
    let rl = col(&t, "RL");
    let corner_rows = rows_of(&t, &parts, &run, Part::Cornering);
    assert!(corner_rows.iter().all(|&i| (re[i] - rl[i]).abs() < 2.0), "rolling RE within 2 cm of RL");
    let nonsense = rows_of(&t, &parts, &run, Part::Standstill).iter().filter(|&&i| (re[i] - rl[i]).abs() > 5.0).count();
    assert!(nonsense as f64 > 0.8 * still.len() as f64, "{nonsense} of {}", still.len());
}

#[test]
fn options_drop_channels_and_change_units() {
    let (run, _) = programme();
    let full = export_ttc(&run, &TtcExportOptions::default()).unwrap();
    let opts = TtcExportOptions {
        with_test_id: false,
        with_nfx: false,
        with_sl: false,
        pressure_unit: PressureUnit::Psi,
        force_unit: ForceUnit::Lbf,
        rate_hz: 100,
        ..TtcExportOptions::default()
    };
    let t = export_ttc(&run, &opts).unwrap();
    assert!(t.test_id.is_none() && t.column("NFX").is_none() && t.column("SL").is_none());
    assert_eq!(t.columns.len(), 20);
    assert_eq!(t.column("P").unwrap().unit, "psi");
    assert_eq!(t.column("FZ").unwrap().unit, "lbf");
    assert!((t.rows() as f64 - 2.0 * full.rows() as f64).abs() <= 2.0);
    let fz_n = col(&full, "FZ")[100];
    let fz_lbf = 0.5 * (col(&t, "FZ")[200] + col(&t, "FZ")[201]);
    assert!((fz_lbf * 4.448_221_615_260_5 - fz_n).abs() < 1e-6 * fz_n.abs());
    assert!(export_ttc(&run, &TtcExportOptions { rate_hz: 200, ..TtcExportOptions::default() }).is_err());
}

#[test]
fn unit_spellings_of_other_rounds_read_back_to_the_same_sweeps() {
    // `--units later-round` (sec, Nm, deg C, deg F, SAE) and `--units us` (mph, in, psi, lbf,
    // degF): the reader finds the same sweeps with the same cells and samples.
    let (run, _) = programme();
    let read = |spelling: UnitSpelling| {
        let t = export_ttc(&run, &TtcExportOptions { units: spelling, ..TtcExportOptions::default() }).unwrap();
        let text = rigdata::table::to_dat(&t, rigdata::table::DatLayout { decimals: 9, crlf: true });
        let (d, r) = read_bytes(text.as_bytes(), "spelling.dat", FileFormat::Dat, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{spelling:?}: {e}"));
        (t, d, r)
    };
    let (_, base, _) = read(UnitSpelling::Ttc);
    assert!(!base.segments.is_empty());
    for spelling in [UnitSpelling::LaterRound, UnitSpelling::Us] {
        let (t, d, r) = read(spelling);
        let unit = |n: &str| t.column(n).unwrap().unit.clone();
        match spelling {
            UnitSpelling::LaterRound => {
                assert_eq!(
                    [unit("ET"), unit("MZ"), unit("TSTC"), unit("AMBTMP"), unit("SL")],
                    ["sec", "Nm", "deg C", "deg F", "SAE"]
                )
            }
            _ => assert_eq!(
                [unit("V"), unit("RL"), unit("P"), unit("FZ"), unit("TSTC")],
                ["mph", "in", "psi", "lbf", "degF"]
            ),
        }
        assert!(!r.warnings.iter().any(|w| w.message.contains("surely degF")), "{spelling:?}: {:?}", r.warnings);
        assert_eq!(d.segments.len(), base.segments.len(), "{spelling:?}");
        for (a, b) in d.segments.iter().zip(&base.segments) {
            assert_eq!((&a.sweep, a.samples.len()), (&b.sweep, b.samples.len()), "{spelling:?}");
            for (x, y) in a.samples.iter().zip(&b.samples) {
                for (u, v) in [
                    (x.fz_n, y.fz_n),
                    (x.p_pa, y.p_pa),
                    (x.vx_mps, y.vx_mps),
                    (x.rl_m, y.rl_m),
                    (x.temp_c, y.temp_c),
                    (x.kappa, y.kappa),
                ] {
                    assert!((u - v).abs() <= 1e-6 * v.abs().max(1.0), "{spelling:?} {}: {u} vs {v}", a.sweep);
                }
            }
        }
    }
}

#[test]
fn dat_text_has_the_three_header_lines_and_values_at_channel_resolution() {
    let (run, _) = programme();
    let t = export_ttc(&run, &TtcExportOptions::default()).unwrap();
    let text = to_dat_compact(&t);
    let lines: Vec<&str> = text.split("\r\n").collect();
    assert_eq!(lines[0], t.title.as_deref().unwrap());
    assert_eq!(lines[1].split('\t').count(), 22);
    assert_eq!(lines[2].split('\t').nth(1), Some("kph"));
    assert_eq!(lines.len(), t.rows() + 4, "3 header lines, the rows, and the empty piece after the last CRLF");
    for (r, line) in lines[3..3 + t.rows()].iter().enumerate().step_by(97) {
        for (c, cell) in t.columns.iter().zip(line.split('\t')) {
            let v: f64 = cell.parse().unwrap_or_else(|e| panic!("row {r} {}: {cell:?}: {e}", c.name));
            let tol = match c.name.as_str() {
                "FX" | "FY" | "FZ" => 0.05,
                "NFX" | "NFY" | "SR" | "SL" => 5e-5,
                "ET" | "SA" | "IA" | "RL" => 5e-4,
                "V" | "MX" | "MZ" => 5e-3,
                _ => 0.05,
            } + 1e-9;
            assert!((v - c.values[r]).abs() <= tol, "row {r} {}: {v} vs {}", c.name, c.values[r]);
        }
    }
    // Free-rolling SL is written as a bare 0.
    assert!(lines[3].ends_with("\t0"), "{}", lines[3]);
}

#[test]
fn an_empty_run_is_a_clear_error() {
    let e = export_ttc(
        &VirtualRun { source: "nothing.mcap".into(), ..VirtualRun::default() },
        &TtcExportOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("nothing.mcap"), "{e}");
    // A table with no rows still writes its header.
    let t = ChannelTable {
        columns: vec![Column { name: "ET".into(), unit: "s".into(), values: vec![] }],
        ..Default::default()
    };
    assert_eq!(to_dat_compact(&t), "tyrerig export\r\nET\r\ns\r\n");
}
