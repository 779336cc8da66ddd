//! `.tir` property-file reader and writer.
//!
//! The reader accepts what real files contain: `[SECTION]` headers, `KEY = value` lines with
//! `$` inline comments, `!` and `$` comment lines, quoted strings, CRLF or LF line ends, the
//! same key in two sections (`MASS` in `[UNITS]` and `[INERTIA]`), and sections it does not
//! know (kept verbatim, e.g. MF 5.2 `[SHAPE]` tables or a later tool's own section). The
//! writer prints floats in Rust's shortest round-trip form, so read → write → read is exact.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use crate::params::{CoefGroup, KeySpec, OtherEntry, TyreParams};

/// Errors reading, validating or editing a `.tir` parameter set.
#[derive(Debug, thiserror::Error)]
pub enum TirError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// File name.
        file: String,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A line is neither a section header, a comment nor `KEY = value`.
    #[error("{file}:{line}: cannot parse `{text}`: expected `[SECTION]`, `KEY = value` or a comment")]
    MalformedLine {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// The offending line.
        text: String,
    },
    /// A model parameter's value is not a number.
    #[error("{file}:{line}: {key} = `{text}` is not a number")]
    MalformedValue {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// Key.
        key: String,
        /// The value text.
        text: String,
    },
    /// A required model parameter is absent.
    #[error("{file}: missing parameter {key} (expected in section [{section}])")]
    MissingKey {
        /// File name.
        file: String,
        /// Key.
        key: String,
        /// Section it belongs in.
        section: String,
    },
    /// A model parameter appears twice.
    #[error("{file}:{line}: {key} given again (first at line {first_line})")]
    DuplicateKey {
        /// File name.
        file: String,
        /// 1-based line of the repeat.
        line: usize,
        /// Line of the first occurrence.
        first_line: usize,
        /// Key.
        key: String,
    },
    /// No FITTYP in `[MODEL]`.
    #[error("{file}: FITTYP is missing, so the Magic Formula version is unknown (expected FITTYP = 61 in [MODEL])")]
    MissingFittyp {
        /// File name.
        file: String,
    },
    /// A Magic Formula version this crate does not implement.
    #[error(
        "{file}:{line}: FITTYP = {value} ({version}) is not supported: only MF-Tyre 6.1 (FITTYP = 61) is implemented"
    )]
    UnsupportedVersion {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// FITTYP as written.
        value: String,
        /// What that FITTYP denotes.
        version: &'static str,
    },
    /// A `[UNITS]` entry other than SI.
    #[error("{file}:{line}: unit {key} = '{value}' is not supported; expected {expected}")]
    UnsupportedUnit {
        /// File name.
        file: String,
        /// 1-based line.
        line: usize,
        /// Key (LENGTH, FORCE, …).
        key: String,
        /// Unit as written.
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// A parameter value outside what the model can use.
    #[error("{file}:{line}: {key} = {value} is invalid: {reason}")]
    InvalidValue {
        /// File name (or source of the parameter set).
        file: String,
        /// 1-based line, 0 when not from a file.
        line: usize,
        /// Key.
        key: String,
        /// Value.
        value: f64,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// `set`/`get` with a key that is not a typed coefficient.
    #[error("unknown parameter key {key}: not an MF-Tyre 6.1 coefficient this crate models")]
    UnknownKey {
        /// Key as given.
        key: String,
    },
}

/// A `.tir` value: a number or a quoted string.
#[derive(Debug, Clone, PartialEq)]
pub enum TirValue {
    /// A numeric value.
    Number(f64),
    /// A quoted string, without the quotes.
    Text(String),
}

impl TirValue {
    /// The number, if numeric.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            TirValue::Number(v) => Some(*v),
            TirValue::Text(_) => None,
        }
    }
}

impl std::fmt::Display for TirValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TirValue::Number(v) => f.write_str(&format_number(*v)),
            TirValue::Text(s) => write!(f, "'{s}'"),
        }
    }
}

/// A section this crate does not interpret, kept line by line (without line ends).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExtraSection {
    /// The section's lines after its `[NAME]` header, verbatim.
    pub lines: Vec<String>,
}

impl ExtraSection {
    /// The `KEY = value` entries of the section (other lines are skipped).
    pub fn entries(&self) -> Vec<(String, TirValue)> {
        self.lines
            .iter()
            .filter_map(|l| match parse_line(l) {
                Ok(Line::Entry { key, value, .. }) => Some((key.to_owned(), classify_value(value))),
                _ => None,
            })
            .collect()
    }

    /// The value of `key` (case-insensitive), if the section has it.
    pub fn get(&self, key: &str) -> Option<TirValue> {
        self.entries().into_iter().find(|(k, _)| k.eq_ignore_ascii_case(key)).map(|(_, v)| v)
    }

    /// Sets `key` to `value`: replaces the first line defining it, or appends one.
    pub fn set(&mut self, key: &str, value: TirValue) {
        let new_line = format!("{key:<25} = {value}");
        for line in &mut self.lines {
            if let Ok(Line::Entry { key: k, .. }) = parse_line(line)
                && k.eq_ignore_ascii_case(key)
            {
                *line = new_line;
                return;
            }
        }
        self.lines.push(new_line);
    }
}

/// Sections this crate interprets, in writing order.
const KNOWN_SECTIONS: &[&str] = &[
    "MDI_HEADER",
    "UNITS",
    "MODEL",
    "DIMENSION",
    "OPERATING_CONDITIONS",
    "INERTIA",
    "VERTICAL",
    "STRUCTURAL",
    "CONTACT_PATCH",
    "INFLATION_PRESSURE_RANGE",
    "VERTICAL_FORCE_RANGE",
    "LONG_SLIP_RANGE",
    "SLIP_ANGLE_RANGE",
    "INCLINATION_ANGLE_RANGE",
    "SCALING_COEFFICIENTS",
    "LONGITUDINAL_COEFFICIENTS",
    "OVERTURNING_COEFFICIENTS",
    "LATERAL_COEFFICIENTS",
    "ROLLING_COEFFICIENTS",
    "ALIGNING_COEFFICIENTS",
    "TURNSLIP_COEFFICIENTS",
];

/// Sections whose keys are never model coefficients (`MASS` in `[UNITS]` is a unit name).
const NON_COEF_SECTIONS: &[&str] = &["MDI_HEADER", "UNITS"];

enum Line<'a> {
    Blank,
    Section(&'a str),
    Entry { key: &'a str, value: &'a str },
}

/// Splits one line (line end already removed) into its syntactic form.
fn parse_line(raw: &str) -> Result<Line<'_>, ()> {
    let t = raw.trim();
    if t.is_empty() || t.starts_with('$') || t.starts_with('!') {
        return Ok(Line::Blank);
    }
    if let Some(rest) = t.strip_prefix('[') {
        let end = rest.find(']').ok_or(())?;
        return Ok(Line::Section(rest[..end].trim()));
    }
    let (key, rest) = t.split_once('=').ok_or(())?;
    let key = key.trim();
    if key.is_empty() || key.contains(char::is_whitespace) {
        return Err(());
    }
    let rest = rest.trim_start();
    let value = if let Some(q) = rest.strip_prefix('\'') {
        // A quoted string runs to the closing quote; `$` inside quotes is text.
        let end = q.find('\'').ok_or(())?;
        &rest[..end + 2]
    } else {
        let end = rest.find(['$', '!']).unwrap_or(rest.len());
        rest[..end].trim()
    };
    Ok(Line::Entry { key, value })
}

fn classify_value(text: &str) -> TirValue {
    if let Some(inner) = text.strip_prefix('\'').and_then(|s| s.strip_suffix('\'')) {
        return TirValue::Text(inner.to_owned());
    }
    match parse_number(text) {
        Some(v) => TirValue::Number(v),
        None => TirValue::Text(text.to_owned()),
    }
}

/// Parses a `.tir` number; also accepts Fortran `D` exponents. Rejects non-finite values.
fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    if t.is_empty() {
        return None;
    }
    let v: f64 = match t.parse() {
        Ok(v) => v,
        Err(_) => t.replace(['D', 'd'], "e").parse().ok()?,
    };
    // "inf"/"nan" parse in Rust but are never valid tyre parameters.
    v.is_finite().then_some(v)
}

/// Formats a float so that parsing it gives the identical `f64` (shortest round-trip form).
pub(crate) fn format_number(v: f64) -> String {
    if v == v.trunc() && v.abs() < 1e15 && !(v == 0.0 && v.is_sign_negative()) {
        // Integers print without ".0" so FITTYP, USE_MODE etc. look as other tools expect.
        format!("{}", v as i64)
    } else {
        format!("{v:?}")
    }
}

fn fittyp_version(v: f64) -> &'static str {
    match v as i64 {
        61 => "MF-Tyre 6.1",
        62 => "MF-Tyre/MF-Swift 6.2",
        6 | 21 => "MF-Tyre 5.2",
        5 => "MF-Tyre 5.0/5.1",
        4 => "Magic Formula 94",
        _ => "unknown Magic Formula version",
    }
}

fn check_unit(key: &str, value: &TirValue) -> Option<&'static str> {
    let TirValue::Text(s) = value else {
        return None;
    };
    let s = s.trim().to_ascii_lowercase();
    let (ok, expected) = match key {
        "LENGTH" => (matches!(s.as_str(), "meter" | "metre" | "m"), "'meter'"),
        "FORCE" => (matches!(s.as_str(), "newton" | "n"), "'newton'"),
        "ANGLE" => (matches!(s.as_str(), "radians" | "radian" | "rad"), "'radians'"),
        "MASS" => (matches!(s.as_str(), "kg" | "kilogram"), "'kg'"),
        "TIME" => (matches!(s.as_str(), "second" | "sec" | "s"), "'second'"),
        _ => (true, ""),
    };
    (!ok).then_some(expected)
}

impl TyreParams {
    /// Reads a `.tir` file. `source` names it in error messages (usually the file name).
    pub fn from_tir_str(text: &str, source: &str) -> Result<Self, TirError> {
        let file = source.to_owned();
        let mut params = TyreParams::empty(source);
        let mut section = String::new();
        let mut in_extra = false;
        let mut seen: HashMap<&'static str, usize> = HashMap::new();
        let mut fittyp: Option<(usize, String, f64)> = None;
        // Numeric values that failed to parse are reported only if they are model keys, and
        // only after FITTYP is known, so an MF 5.2 file gets the version message first.
        let mut pending_error: Option<TirError> = None;

        for (idx, raw) in text.split('\n').enumerate() {
            let line_no = idx + 1;
            let raw = raw.strip_suffix('\r').unwrap_or(raw);
            let parsed = parse_line(raw);
            if let Ok(Line::Section(name)) = parsed {
                section = name.to_ascii_uppercase();
                in_extra = !KNOWN_SECTIONS.contains(&section.as_str());
                if in_extra {
                    params.extra_sections.entry(section.clone()).or_default();
                }
                continue;
            }
            if in_extra {
                // Unknown sections (tables, other tools' data) are kept verbatim.
                if let Some(sec) = params.extra_sections.get_mut(&section)
                    && !raw.trim().is_empty()
                {
                    sec.lines.push(raw.to_owned());
                }
                continue;
            }
            let (key, value_text) = match parsed {
                Ok(Line::Blank) => continue,
                Ok(Line::Section(_)) => continue,
                Ok(Line::Entry { key, value }) => (key, value),
                Err(()) => {
                    return Err(TirError::MalformedLine { file, line: line_no, text: raw.trim().to_owned() });
                }
            };
            let key_upper = key.to_ascii_uppercase();

            if section == "MODEL" && key_upper == "FITTYP" {
                let v = parse_number(value_text.trim_matches('\''));
                match v {
                    Some(v) => fittyp = Some((line_no, value_text.to_owned(), v)),
                    None => {
                        return Err(TirError::MalformedValue {
                            file,
                            line: line_no,
                            key: key_upper,
                            text: value_text.to_owned(),
                        });
                    }
                }
                continue;
            }

            let coef_group =
                if NON_COEF_SECTIONS.contains(&section.as_str()) { None } else { CoefGroup::of_key(&key_upper) };
            if let Some(group) = coef_group {
                let spec_key = group.keys().iter().copied().find(|k| *k == key_upper).unwrap_or("");
                if let Some(first) = seen.get(spec_key) {
                    return Err(TirError::DuplicateKey { file, line: line_no, first_line: *first, key: key_upper });
                }
                seen.insert(spec_key, line_no);
                match parse_number(value_text) {
                    Some(v) => {
                        if let Some(slot) = params.slot_mut(&key_upper) {
                            *slot = v;
                        }
                    }
                    None => {
                        if pending_error.is_none() {
                            pending_error = Some(TirError::MalformedValue {
                                file: file.clone(),
                                line: line_no,
                                key: key_upper,
                                text: value_text.to_owned(),
                            });
                        }
                    }
                }
            } else {
                let value = classify_value(value_text);
                if section == "UNITS"
                    && let Some(expected) = check_unit(&key_upper, &value)
                {
                    return Err(TirError::UnsupportedUnit {
                        file,
                        line: line_no,
                        key: key_upper,
                        value: value.to_string().trim_matches('\'').to_owned(),
                        expected,
                    });
                }
                params.other.push(OtherEntry { section: section.clone(), key: key.to_owned(), value });
            }
        }

        let Some((fit_line, fit_text, fit_value)) = fittyp else {
            return Err(TirError::MissingFittyp { file });
        };
        if fit_value != 61.0 {
            return Err(TirError::UnsupportedVersion {
                file,
                line: fit_line,
                value: fit_text,
                version: fittyp_version(fit_value),
            });
        }
        params.fittyp = 61;
        if let Some(e) = pending_error {
            return Err(e);
        }
        for group in CoefGroup::ALL {
            for spec in group.specs() {
                if seen.contains_key(spec.key) {
                    continue;
                }
                match spec.default {
                    None => {
                        return Err(TirError::MissingKey {
                            file,
                            key: spec.key.to_owned(),
                            section: spec.section.to_owned(),
                        });
                    }
                    Some(d) => {
                        if let Some(slot) = params.slot_mut(spec.key) {
                            *slot = d;
                        }
                    }
                }
            }
        }
        params.validate_with_lines(&file, &seen)?;
        Ok(params)
    }

    /// Reads a `.tir` file from disk.
    pub fn read_tir(path: &Path) -> Result<Self, TirError> {
        let name = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| TirError::Io { file: name.clone(), source })?;
        // Some tools write Latin-1 comments; the numeric content is ASCII either way.
        let text = String::from_utf8_lossy(&bytes);
        Self::from_tir_str(&text, &name)
    }

    /// Checks the values the model divides by or takes roots of.
    pub fn validate(&self) -> Result<(), TirError> {
        self.validate_with_lines(&self.source, &HashMap::new())
    }

    fn validate_with_lines(&self, file: &str, lines: &HashMap<&'static str, usize>) -> Result<(), TirError> {
        let positive = [
            ("FNOMIN", self.vertical.fnomin),
            ("UNLOADED_RADIUS", self.dimension.unloaded_radius),
            ("NOMPRES", self.operating.nompres),
            ("LONGVL", self.model.longvl),
            ("VERTICAL_STIFFNESS", self.vertical.vertical_stiffness),
            ("LFZO", self.scaling.lfzo),
        ];
        for (key, value) in positive {
            if value <= 0.0 {
                return Err(TirError::InvalidValue {
                    file: file.to_owned(),
                    line: lines.get(key).copied().unwrap_or(0),
                    key: key.to_owned(),
                    value,
                    reason: "must be greater than zero",
                });
            }
        }
        if self.model.vxlow < 0.0 {
            return Err(TirError::InvalidValue {
                file: file.to_owned(),
                line: lines.get("VXLOW").copied().unwrap_or(0),
                key: "VXLOW".to_owned(),
                value: self.model.vxlow,
                reason: "must not be negative",
            });
        }
        let l = &self.limits;
        let ranges = [
            ("PRESMAX", l.presmin, l.presmax),
            ("FZMAX", l.fzmin, l.fzmax),
            ("KPUMAX", l.kpumin, l.kpumax),
            ("ALPMAX", l.alpmin, l.alpmax),
            ("CAMMAX", l.cammin, l.cammax),
        ];
        for (key, lo, hi) in ranges {
            if lo > hi {
                return Err(TirError::InvalidValue {
                    file: file.to_owned(),
                    line: lines.get(key).copied().unwrap_or(0),
                    key: key.to_owned(),
                    value: hi,
                    reason: "the range maximum is below its minimum",
                });
            }
        }
        Ok(())
    }

    /// Writes the parameter set as `.tir` text (LF line ends) that [`TyreParams::from_tir_str`]
    /// reads back to identical values. Extra sections follow the known ones, verbatim.
    pub fn to_tir_string(&self) -> String {
        let mut out = String::new();
        let specs: Vec<&KeySpec> = CoefGroup::ALL.iter().flat_map(|g| g.specs().iter()).collect();
        for section in KNOWN_SECTIONS {
            let _ = writeln!(out, "${:-<70}", section.to_ascii_lowercase());
            let _ = writeln!(out, "[{section}]");
            if *section == "MODEL" {
                let _ = writeln!(out, "{:<25} = {}", "FITTYP", self.fittyp);
            }
            for e in self.other.iter().filter(|e| e.section == *section) {
                let _ = writeln!(out, "{:<25} = {}", e.key, e.value);
            }
            for spec in specs.iter().filter(|s| s.section == *section) {
                if let Some(v) = self.get(spec.key) {
                    let _ = writeln!(out, "{:<25} = {}", spec.key, format_number(v));
                }
            }
        }
        // Entries read from sections the writer does not emit keep their section by becoming
        // extra lines there; in practice `other` only holds known sections.
        for (name, sec) in &self.extra_sections {
            let _ = writeln!(out, "[{name}]");
            for line in &sec.lines {
                let _ = writeln!(out, "{line}");
            }
        }
        out
    }
}
