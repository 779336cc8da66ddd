//! Procedure file validation: every error names file, line and key and says what was expected.

use procedure::file::{ProcedureError, parse_file, parse_with};

const GOOD: &str = r#"
[procedure]
name = "t"
title = "Test"
config_tag = "FreeRoll"

[[section]]
name = "s1"
pressure = "mid"

[[section.step]]
kind = "sweep"
peak_deg = 16.0
low_rate_dps = 2.0
high_rate_dps = 30.0
threshold_deg = 4.0
asym = "medium"
"#;

fn err(src: &str) -> (usize, String, String) {
    match parse_file("t.toml", src).unwrap_err() {
        ProcedureError::Parse { file, line, key, message, .. }
        | ProcedureError::Invalid { file, line, key, message } => {
            assert_eq!(file, "t.toml");
            (line, key, message)
        }
        other => panic!("unexpected {other}"),
    }
}

fn line_of(src: &str, needle: &str) -> usize {
    src.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn good_file_parses() {
    parse_file("t.toml", GOOD).unwrap();
}

#[test]
fn unknown_key_in_step() {
    let src = GOOD.replace("asym = \"medium\"", "asym = \"medium\"\npeak_dgs = 3.0");
    let (line, key, msg) = err(&src);
    assert_eq!(key, "peak_dgs");
    assert_eq!(line, line_of(&src, "peak_dgs"));
    assert!(msg.contains("unknown field"), "{msg}");
    let e = parse_file("t.toml", &src).unwrap_err().to_string();
    assert!(e.starts_with(&format!("t.toml:{line}:")), "{e}");
    assert!(e.contains("peak_dgs"), "{e}");
}

#[test]
fn unknown_key_in_header() {
    let src = GOOD.replace("title = \"Test\"", "title = \"Test\"\ncolour = \"red\"");
    let (line, key, _) = err(&src);
    assert_eq!(key, "colour");
    assert_eq!(line, line_of(&src, "colour"));
}

#[test]
fn bad_value_type() {
    let src = GOOD.replace("peak_deg = 16.0", "peak_deg = \"sixteen\"");
    let (line, key, msg) = err(&src);
    assert_eq!(key, "peak_deg");
    assert_eq!(line, line_of(&src, "sixteen"));
    assert!(msg.contains("invalid type") || msg.contains("expected"), "{msg}");
}

#[test]
fn bad_enum_value() {
    let src = GOOD.replace("asym = \"medium\"", "asym = \"huge\"");
    let (line, key, msg) = err(&src);
    assert_eq!(key, "asym");
    assert_eq!(line, line_of(&src, "huge"));
    assert!(msg.contains("high") && msg.contains("medium"), "{msg}");
}

#[test]
fn bad_value_negative_rate() {
    let src = GOOD.replace("high_rate_dps = 30.0", "high_rate_dps = -30.0");
    let (line, key, msg) = err(&src);
    assert_eq!(key, "high_rate_dps");
    assert_eq!(line, line_of(&src, "-30.0"));
    assert!(msg.contains("positive"), "{msg}");
}

#[test]
fn key_of_another_kind() {
    let src = GOOD.replace("asym = \"medium\"", "asym = \"medium\"\nhold_s = 3.0");
    let (line, key, msg) = err(&src);
    assert_eq!(key, "hold_s");
    assert_eq!(line, line_of(&src, "hold_s"));
    assert!(msg.contains("not used by kind"), "{msg}");
}

#[test]
fn missing_section() {
    let src = r#"
[procedure]
name = "t"
title = "Test"
config_tag = "FreeRoll"
"#;
    let (_, key, msg) = err(src);
    assert_eq!(key, "section");
    assert!(msg.contains("[[section]]"), "{msg}");
}

#[test]
fn missing_header_key() {
    let src = GOOD.replace("config_tag = \"FreeRoll\"\n", "");
    let (line, key, msg) = err(&src);
    assert_eq!(key, "config_tag");
    assert!(msg.contains("missing"), "{msg}");
    assert_eq!(line, line_of(&src, "[procedure]"));
}

#[test]
fn missing_kind_and_missing_rate() {
    let src = GOOD.replace("kind = \"sweep\"\n", "");
    let (line, key, _) = err(&src);
    assert_eq!(key, "kind");
    assert_eq!(line, line_of(&src, "[[section.step]]"));
    let src = GOOD.replace("threshold_deg = 4.0\n", "");
    let (_, key, msg) = err(&src);
    assert_eq!(key, "threshold_deg");
    assert!(msg.contains("variable rate"), "{msg}");
}

#[test]
fn mixed_axes_and_two_loads() {
    let src = GOOD.replace("asym = \"medium\"", "asym = \"medium\"\npeak_pct = 20.0");
    let (line, key, _) = err(&src);
    assert_eq!(key, "peak_pct");
    assert_eq!(line, line_of(&src, "peak_pct"));
    let src = GOOD.replace("asym = \"medium\"", "asym = \"medium\"\nload = 1.0");
    let (line, key, msg) = err(&src);
    assert_eq!(key, "load");
    assert_eq!(line, line_of(&src, "load = 1.0"));
    assert!(msg.contains("exactly one"), "{msg}");
}

#[test]
fn syntax_error_has_line() {
    let src = GOOD.replace("peak_deg = 16.0", "peak_deg = = 16.0");
    let (line, _, _) = err(&src);
    assert_eq!(line, line_of(&src, "= = 16"));
}

#[test]
fn include_cycle_and_missing_include() {
    let a = r#"
[procedure]
name = "a"
title = "A"
config_tag = "A"
[[include]]
file = "b.toml"
"#;
    let b = a.replace("\"b.toml\"", "\"a.toml\"").replace("name = \"a\"", "name = \"b\"");
    let mut read = |p: &str| -> Result<String, ProcedureError> {
        match p {
            "a.toml" => Ok(a.to_owned()),
            "b.toml" => Ok(b.clone()),
            _ => Err(ProcedureError::Read {
                file: p.to_owned(),
                source: std::io::Error::from(std::io::ErrorKind::NotFound),
            }),
        }
    };
    let e = parse_with("a.toml", a, &mut read).unwrap_err();
    assert!(matches!(e, ProcedureError::IncludeCycle { .. }), "{e}");
    let c = a.replace("b.toml", "nope.toml");
    let e = parse_with("a.toml", &c, &mut read).unwrap_err();
    assert!(e.to_string().contains("nope.toml"), "{e}");
}

#[test]
fn absolute_section_pressures_are_checked() {
    let both = GOOD.replace("pressure = \"mid\"", "pressure = \"mid\"\npressures_bar = [0.7, 0.84]");
    let (_, key, msg) = err(&both);
    assert_eq!(key, "pressures_bar");
    assert!(msg.contains("not both"), "{msg}");
    let negative = GOOD.replace("pressure = \"mid\"", "pressures_bar = [0.7, -0.84]");
    let (line, key, msg) = err(&negative);
    assert_eq!((key.as_str(), line), ("pressures_bar", line_of(&negative, "pressures_bar")));
    assert!(msg.contains("-0.84"), "{msg}");
    let empty = GOOD.replace("pressure = \"mid\"", "pressures_bar = []");
    assert_eq!(err(&empty).1, "pressures_bar");
    parse_file("t.toml", &GOOD.replace("pressure = \"mid\"", "pressure_bar = 0.84")).unwrap();
}

#[test]
fn standstill_takes_a_hold_time_and_a_load_only() {
    let st = GOOD.replace(
        "kind = \"sweep\"\npeak_deg = 16.0\nlow_rate_dps = 2.0\nhigh_rate_dps = 30.0\nthreshold_deg = 4.0\nasym = \"medium\"",
        "kind = \"standstill\"\nhold_s = 5.0\nload = 0.6",
    );
    parse_file("t.toml", &st).unwrap();
    let (_, key, msg) = err(&st.replace("hold_s = 5.0\n", ""));
    assert_eq!(key, "hold_s");
    assert!(msg.contains("missing"), "{msg}");
    let (_, key, msg) = err(&st.replace("load = 0.6", "load = 0.6\nspeed_mps = 3.0"));
    assert_eq!(key, "speed_mps");
    assert!(msg.contains("not used by kind"), "{msg}");
}
