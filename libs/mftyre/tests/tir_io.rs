//! `.tir` reader and writer: round trips over every project tyre file and error reporting.

mod common;

use mftyre::{CoefGroup, TirError, TirValue, TyreParams};

fn all_tyre_files() -> Vec<std::path::PathBuf> {
    let mut files: Vec<_> = std::fs::read_dir(common::tyres_dir())
        .expect("launch-config/tyres")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "tir"))
        .collect();
    files.sort();
    files
}

fn sample_text() -> String {
    std::fs::read_to_string(common::tyres_dir().join("MagicFormula61_Paramerters.tir")).expect("sample tyre")
}

fn read(text: &str) -> Result<TyreParams, TirError> {
    TyreParams::from_tir_str(text, "test.tir")
}

#[test]
fn every_project_file_round_trips_exactly() {
    let files = all_tyre_files();
    assert!(files.len() >= 4, "expected the four MFeval sample files");
    for path in files {
        let first = TyreParams::read_tir(&path).unwrap_or_else(|e| panic!("{e}"));
        let text = first.to_tir_string();
        let second = TyreParams::from_tir_str(&text, &path.display().to_string())
            .unwrap_or_else(|e| panic!("re-reading {}: {e}\n{text}", path.display()));
        for group in CoefGroup::ALL {
            for key in group.keys() {
                let (a, b) = (first.get(key), second.get(key));
                assert_eq!(
                    a.map(f64::to_bits),
                    b.map(f64::to_bits),
                    "{}: {key} changed: {a:?} -> {b:?}",
                    path.display()
                );
            }
        }
        assert_eq!(first, second, "{}: parameter sets differ after a round trip", path.display());
        // Writing again gives the same text: the writer is deterministic.
        assert_eq!(text, second.to_tir_string());
    }
}

#[test]
fn awkward_values_round_trip_bit_exactly() {
    let mut p = common::sample_tyre();
    let values = [0.1 + 0.2, -1.0e-300, 6.02214076e23, f64::MIN_POSITIVE, -0.0, 1.0 / 3.0, 123456789.12345679, 4e-05];
    for (i, v) in values.into_iter().enumerate() {
        let key = CoefGroup::PureFy.keys()[i];
        p.set(key, v).expect("set");
    }
    let back = read(&p.to_tir_string()).expect("re-read");
    for (i, v) in values.into_iter().enumerate() {
        let key = CoefGroup::PureFy.keys()[i];
        assert_eq!(back.get(key).map(f64::to_bits), Some(v.to_bits()), "{key}");
    }
}

#[test]
fn sample_values_and_nominals() {
    let p = common::sample_tyre();
    assert_eq!(p.fnomin_n(), 6752.0);
    assert_eq!(p.unloaded_radius_m(), 0.393581);
    assert_eq!(p.width_m(), 0.255);
    assert_eq!(p.nominal_pressure_pa(), 260000.0);
    assert_eq!(p.longvl_mps(), 16.6);
    assert_eq!(p.get("PKY1"), Some(27.42326));
    assert_eq!(p.get("pky1"), Some(27.42326), "keys are case-insensitive");
    assert_eq!(p.get("QSY4"), Some(4e-05));
    assert_eq!(p.mass_kg(), 10.0, "MASS from [INERTIA], not the unit name in [UNITS]");
    assert_eq!(p.other_value("UNITS", "MASS"), Some(&TirValue::Text("kg".into())));
    assert_eq!(p.other_value("MODEL", "TYRESIDE"), Some(&TirValue::Text("RIGHT".into())));
    assert!(CoefGroup::PureFy.keys().contains(&"PKY1"));
    assert!(CoefGroup::Scaling.keys().contains(&"LMUY"));
    assert_eq!(CoefGroup::of_key("RVY6"), Some(CoefGroup::Combined));
}

#[test]
fn get_and_set_by_key() {
    let mut p = common::sample_tyre();
    p.set("PKY1", -20.0).expect("set");
    assert_eq!(p.pure_fy.pky1, -20.0);
    assert_eq!(p.get("PKY1"), Some(-20.0));
    p.set("lmuy", 0.9).expect("lower-case key");
    assert_eq!(p.scaling.lmuy, 0.9);
    assert!(matches!(p.set("NOPE1", 1.0), Err(TirError::UnknownKey { key }) if key == "NOPE1"));
    assert!(matches!(p.set("PKY1", f64::NAN), Err(TirError::InvalidValue { .. })));
    assert_eq!(p.get("NOPE1"), None);
    let fy = p.group_values(CoefGroup::PureFy);
    assert_eq!(fy.len(), CoefGroup::PureFy.keys().len());
}

#[test]
fn crlf_and_lf_read_the_same() {
    let text = sample_text();
    assert!(text.contains("\r\n"), "the sample file uses CRLF");
    let lf = text.replace("\r\n", "\n");
    let a = read(&text).expect("crlf");
    let b = read(&lf).expect("lf");
    assert_eq!(a, b);
}

#[test]
fn missing_key_is_reported_by_name() {
    let text: String = sample_text().lines().filter(|l| !l.starts_with("PKY4 ")).map(|l| format!("{l}\n")).collect();
    let err = read(&text).expect_err("PKY4 removed");
    match &err {
        TirError::MissingKey { key, section, file } => {
            assert_eq!(key, "PKY4");
            assert_eq!(section, "LATERAL_COEFFICIENTS");
            assert_eq!(file, "test.tir");
        }
        other => panic!("wrong error: {other}"),
    }
    assert!(err.to_string().contains("PKY4"), "{err}");
}

#[test]
fn malformed_value_is_reported_by_line_and_key() {
    let text = sample_text().replace("= 27.42326", "= 27.4x2326");
    let line = text.lines().position(|l| l.starts_with("PKY1 ")).expect("PKY1 line") + 1;
    let err = read(&text).expect_err("bad number");
    match &err {
        TirError::MalformedValue { line: l, key, text, .. } => {
            assert_eq!(*l, line);
            assert_eq!(key, "PKY1");
            assert_eq!(text, "27.4x2326");
        }
        other => panic!("wrong error: {other}"),
    }
    assert!(err.to_string().starts_with(&format!("test.tir:{line}:")), "{err}");
}

#[test]
fn malformed_line_is_reported() {
    let text = sample_text().replace("PKY1                      \t = 27.42326", "PKY1 27.42326");
    let err = read(&text).expect_err("no =");
    assert!(matches!(err, TirError::MalformedLine { .. }), "{err}");
}

#[test]
fn unsupported_fittyp_is_rejected_clearly() {
    for (fit, name) in [("62", "6.2"), ("6", "5.2"), ("21", "5.2")] {
        let text = sample_text().replace("FITTYP                    \t = 61", &format!("FITTYP = {fit}"));
        let err = read(&text).expect_err("not 6.1");
        assert!(matches!(err, TirError::UnsupportedVersion { .. }), "{err}");
        let msg = err.to_string();
        assert!(msg.contains(name) && msg.contains("only MF-Tyre 6.1"), "{msg}");
    }
}

#[test]
fn missing_fittyp_is_reported() {
    let text: String = sample_text().lines().filter(|l| !l.starts_with("FITTYP")).map(|l| format!("{l}\n")).collect();
    assert!(matches!(read(&text), Err(TirError::MissingFittyp { .. })));
}

#[test]
fn shape_table_and_unknown_sections_are_kept() {
    let mut text = sample_text();
    text.push_str(
        "[SHAPE]\r\n{radial width}\r\n 1.0 0.0\r\n 1.0 0.4\r\n 0.9 0.9\r\n\
         [DOCTOR_ADDITIONS]\r\n$ added by the doctor\r\nTHERMAL_GRIP = 0.97 $ a note\r\nNAME = 'warm'\r\n",
    );
    let p = read(&text).expect("extra sections are fine");
    let shape = &p.extra_sections["SHAPE"];
    assert_eq!(shape.lines[0], "{radial width}");
    assert_eq!(shape.lines.len(), 4);
    let doc = &p.extra_sections["DOCTOR_ADDITIONS"];
    assert_eq!(doc.get("THERMAL_GRIP"), Some(TirValue::Number(0.97)));
    assert_eq!(doc.get("name"), Some(TirValue::Text("warm".into())));

    let back = read(&p.to_tir_string()).expect("round trip");
    assert_eq!(back.extra_sections, p.extra_sections);
    assert_eq!(back, p);

    let mut edited = back.clone();
    if let Some(sec) = edited.extra_sections.get_mut("DOCTOR_ADDITIONS") {
        sec.set("THERMAL_GRIP", TirValue::Number(0.95));
        sec.set("NEW_KEY", TirValue::Number(1.5));
    }
    let again = read(&edited.to_tir_string()).expect("edited");
    let doc = &again.extra_sections["DOCTOR_ADDITIONS"];
    assert_eq!(doc.get("THERMAL_GRIP"), Some(TirValue::Number(0.95)));
    assert_eq!(doc.get("NEW_KEY"), Some(TirValue::Number(1.5)));
}

#[test]
fn comments_quotes_and_spacing_are_tolerated() {
    let text = sample_text()
        .replace(
            "PKY2                      \t = 3.660821        \t $Load at which Kfy reaches maximum value",
            "  pky2=3.660821$no spaces, lower case",
        )
        .replace("TYRESIDE                  \t = 'RIGHT'", "TYRESIDE = 'RIGHT $ not a comment'");
    let p = read(&format!("! leading comment\n{text}")).expect("tolerant");
    assert_eq!(p.get("PKY2"), Some(3.660821));
    assert_eq!(p.other_value("MODEL", "TYRESIDE"), Some(&TirValue::Text("RIGHT $ not a comment".into())));
}

#[test]
fn duplicate_and_invalid_values_are_reported() {
    let dup = sample_text().replace("[LATERAL_COEFFICIENTS]", "[LATERAL_COEFFICIENTS]\nPKY1 = 1.0");
    assert!(matches!(read(&dup), Err(TirError::DuplicateKey { key, .. }) if key == "PKY1"));
    let bad = sample_text().replace("= 6752  ", "= -1    ");
    assert!(matches!(read(&bad), Err(TirError::InvalidValue { key, .. }) if key == "FNOMIN"));
    let units = sample_text().replace("'meter'", "'mm'");
    assert!(matches!(read(&units), Err(TirError::UnsupportedUnit { .. })));
}

#[test]
fn read_tir_names_the_file_on_io_errors() {
    let err = TyreParams::read_tir(std::path::Path::new("/nonexistent/x.tir")).expect_err("no file");
    assert!(err.to_string().contains("/nonexistent/x.tir"), "{err}");
}
