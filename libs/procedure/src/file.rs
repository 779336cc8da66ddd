//! The procedure file format (TOML) and its loading with errors that name file, line and key.
//!
//! Parsing is serde with `deny_unknown_fields`; toml's spans turn every syntax, type and
//! unknown-key error into `file:line:column: key: message`. A second pass checks what serde
//! cannot (which keys belong to which step kind, ranges, exclusive alternatives) and reports
//! the line of the offending key.

use crate::primitives::GraphBlock;
use crate::setpoint::RigMode;
use crate::sweep::AsymLevel;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Errors from loading, validating or expanding a procedure.
#[derive(Debug, thiserror::Error)]
pub enum ProcedureError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Read {
        /// File.
        file: String,
        /// Cause.
        source: std::io::Error,
    },
    /// Syntax, type, unknown or missing key.
    #[error("{file}:{line}:{column}: key `{key}`: {message}")]
    Parse {
        /// File.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The key (or table) concerned.
        key: String,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A value or combination that parses but makes no sense.
    #[error("{file}:{line}: key `{key}`: {message}")]
    Invalid {
        /// File.
        file: String,
        /// 1-based line.
        line: usize,
        /// The key concerned.
        key: String,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A file includes itself, directly or not.
    #[error("{file}: include cycle through `{include}`")]
    IncludeCycle {
        /// The including file.
        file: String,
        /// The include that closes the cycle.
        include: String,
    },
    /// A run input is out of range.
    #[error("run input `{key}`: {message}")]
    BadInput {
        /// Input name.
        key: &'static str,
        /// What was wrong.
        message: String,
    },
    /// The load index is not in the ETRTO table.
    #[error(transparent)]
    LoadIndex(#[from] crate::load_index::UnknownLoadIndex),
    /// The expanded plan leaves the rig envelope.
    #[error(transparent)]
    Envelope(#[from] crate::plan::PlanEnvelopeError),
}

/// One of the run's three inflation pressures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressureSlot {
    /// `pressures_bar[0]` (thesis: 2.1 bar).
    Low,
    /// `pressures_bar[1]` (thesis: 2.6 bar).
    Mid,
    /// `pressures_bar[2]` (thesis: 3.3 bar).
    High,
}

impl PressureSlot {
    /// Index into `RunInputs::pressures_bar`.
    pub fn index(self) -> usize {
        match self {
            Self::Low => 0,
            Self::Mid => 1,
            Self::High => 2,
        }
    }
}

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcedureFile {
    /// Header.
    pub procedure: ProcedureHeader,
    /// Other procedure files run in order before this file's own sections (suites).
    #[serde(default)]
    pub include: Vec<Spanned<IncludeSpec>>,
    /// Sections in order.
    #[serde(default)]
    pub section: Vec<Spanned<SectionSpec>>,
}

fn default_tyre_change_s() -> f64 {
    900.0
}
fn default_ref_s() -> f64 {
    3.0
}
fn default_specimen() -> String {
    "A".into()
}

/// `[procedure]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcedureHeader {
    /// Machine name, e.g. `gs2mf_freerolling`.
    pub name: String,
    /// Human title.
    pub title: String,
    /// Rig configuration tag that starts every sweep name (`FreeRoll`, `BrkDrv`, …).
    pub config_tag: String,
    /// Default rig mode of the sections.
    #[serde(default)]
    pub mode: RigMode,
    /// Tyre specimen label; a change of specimen inserts a tyre change.
    #[serde(default = "default_specimen")]
    pub specimen: String,
    /// Count the first mount as a tyre change (suites: the thesis counts both specimens).
    #[serde(default)]
    pub count_first_mount: bool,
    /// Rig time of a tyre change \[s\].
    #[serde(default = "default_tyre_change_s")]
    pub tyre_change_s: f64,
    /// Free-rolling reference hold before each longitudinal sweep \[s\].
    #[serde(default = "default_ref_s")]
    pub free_rolling_ref_s: f64,
    /// Free text.
    #[serde(default)]
    pub description: String,
}

/// `[[include]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IncludeSpec {
    /// Path relative to the including file.
    pub file: String,
    /// Override the included procedure's specimen.
    #[serde(default)]
    pub specimen: Option<String>,
}

/// `[[section]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionSpec {
    /// Name (a pressure suffix is added when the section loops over pressures).
    pub name: String,
    /// Run the whole section once at this pressure.
    #[serde(default)]
    pub pressure: Option<PressureSlot>,
    /// Run the whole section once per pressure, in order.
    #[serde(default)]
    pub pressures: Option<Vec<PressureSlot>>,
    /// Run the whole section once at this absolute pressure \[bar\] (plans written for one
    /// tyre class, e.g. TTC-style runs at four pressures).
    #[serde(default)]
    pub pressure_bar: Option<f64>,
    /// Run the whole section once per absolute pressure \[bar\], in order.
    #[serde(default)]
    pub pressures_bar: Option<Vec<f64>>,
    /// Rig mode for the section's steps.
    #[serde(default)]
    pub mode: Option<RigMode>,
    /// Tyre specimen for this section (overrides the header's).
    #[serde(default)]
    pub specimen: Option<String>,
    /// With `pressures`: a fresh specimen per pressure, labelled `<specimen>_<low|mid|high>`
    /// (the Square Matrix tests each pressure on its own tyres).
    #[serde(default)]
    pub specimen_per_pressure: bool,
    /// Steps in order.
    #[serde(default)]
    pub step: Vec<Spanned<StepSpec>>,
}

/// A step's primitive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepKindSpec {
    /// Slip sweep (slip angle: `*_deg`/`*_dps` keys; slip ratio: `*_pct`/`*_pct_ps` keys).
    Sweep,
    /// Vertical-load sweep.
    VerticalLoad,
    /// On-centre holds.
    OnCentre,
    /// Rolling-radius steps.
    RollingRadius,
    /// Step-steer pairs.
    StepSteer,
    /// Static longitudinal drags.
    StaticLong,
    /// Warm-up blocks.
    WarmUp,
    /// Graph-sweep block.
    GraphSweeps,
    /// Plain hold at zero slip.
    Hold,
    /// Belt stopped with the load applied (the standstill real run files start and end with).
    Standstill,
}

/// `[[section.step]]`: one flat table; which keys are allowed depends on `kind`.
#[allow(missing_docs)] // every key is documented in docs/procedures.md
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct StepSpec {
    pub kind: Option<StepKindSpec>,
    pub label: Option<String>,
    pub mode: Option<RigMode>,
    // slip-angle sweep
    pub peak_deg: Option<f64>,
    pub waypoints_deg: Option<Vec<f64>>,
    pub rate_dps: Option<f64>,
    pub low_rate_dps: Option<f64>,
    pub high_rate_dps: Option<f64>,
    pub threshold_deg: Option<f64>,
    // slip-ratio sweep
    pub peak_pct: Option<f64>,
    pub waypoints_pct: Option<Vec<f64>>,
    pub rate_pct_ps: Option<f64>,
    pub low_rate_pct_ps: Option<f64>,
    pub high_rate_pct_ps: Option<f64>,
    pub threshold_pct: Option<f64>,
    // load
    pub load: Option<f64>,
    pub loads: Option<Vec<f64>>,
    pub fz_n: Option<f64>,
    pub asym: Option<AsymLevel>,
    pub asym_factors: Option<[f64; 2]>,
    pub adverse: Option<bool>,
    pub saturation_deg: Option<f64>,
    pub low_load: Option<f64>,
    pub high_load: Option<f64>,
    // camber
    pub camber_deg: Option<f64>,
    pub cambers_deg: Option<Vec<f64>>,
    pub camber_coupling_deg: Option<f64>,
    // held slip angle
    pub slip_angle_deg: Option<f64>,
    pub slip_angles_deg: Option<Vec<f64>>,
    // pressure and speed
    pub pressure: Option<PressureSlot>,
    pub pressures: Option<Vec<PressureSlot>>,
    pub speed_mps: Option<f64>,
    pub speeds_mps: Option<Vec<f64>>,
    // repetition and pauses
    pub repeat: Option<u32>,
    pub thermal_pause: Option<bool>,
    // holds, step-steer, static long, vertical load, warm-up, graph sweeps
    pub hold_s: Option<f64>,
    pub distance_m: Option<f64>,
    pub displacement_m: Option<f64>,
    pub belt_speed_mps: Option<f64>,
    pub roll_s: Option<f64>,
    pub roll_speed_mps: Option<f64>,
    pub pre_roll_s: Option<f64>,
    pub steer_rate_dps: Option<f64>,
    pub slip_rate_dps: Option<f64>,
    pub blocks: Option<u32>,
    pub block: Option<GraphBlock>,
}

/// Keys every kind accepts.
const COMMON_KEYS: &[&str] = &["kind", "label", "mode", "pressure", "pressures", "thermal_pause"];

impl StepKindSpec {
    /// The name as written in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sweep => "sweep",
            Self::VerticalLoad => "vertical_load",
            Self::OnCentre => "on_centre",
            Self::RollingRadius => "rolling_radius",
            Self::StepSteer => "step_steer",
            Self::StaticLong => "static_long",
            Self::WarmUp => "warm_up",
            Self::GraphSweeps => "graph_sweeps",
            Self::Hold => "hold",
            Self::Standstill => "standstill",
        }
    }

    /// Keys this kind accepts besides the common ones (`kind`, `label`, `mode`, `pressure`,
    /// `pressures`, `thermal_pause`).
    pub fn allowed_keys(self) -> &'static [&'static str] {
        match self {
            Self::Sweep => &[
                "peak_deg",
                "waypoints_deg",
                "rate_dps",
                "low_rate_dps",
                "high_rate_dps",
                "threshold_deg",
                "peak_pct",
                "waypoints_pct",
                "rate_pct_ps",
                "low_rate_pct_ps",
                "high_rate_pct_ps",
                "threshold_pct",
                "load",
                "loads",
                "fz_n",
                "asym",
                "asym_factors",
                "adverse",
                "saturation_deg",
                "camber_deg",
                "cambers_deg",
                "camber_coupling_deg",
                "slip_angle_deg",
                "slip_angles_deg",
                "speed_mps",
                "repeat",
            ],
            Self::VerticalLoad => &[
                "slip_angle_deg",
                "slip_angles_deg",
                "low_load",
                "high_load",
                "slip_rate_dps",
                "camber_deg",
                "speed_mps",
                "repeat",
            ],
            Self::OnCentre => {
                &["slip_angle_deg", "slip_angles_deg", "load", "loads", "hold_s", "camber_deg", "speed_mps"]
            }
            Self::RollingRadius => &["load", "loads", "speed_mps", "speeds_mps", "hold_s"],
            Self::StepSteer => &[
                "slip_angle_deg",
                "slip_angles_deg",
                "load",
                "loads",
                "roll_speed_mps",
                "pre_roll_s",
                "distance_m",
                "steer_rate_dps",
            ],
            Self::StaticLong => {
                &["load", "loads", "repeat", "displacement_m", "belt_speed_mps", "roll_speed_mps", "roll_s"]
            }
            Self::WarmUp => &["blocks", "peak_deg", "rate_dps", "roll_s", "load", "loads", "speed_mps"],
            Self::GraphSweeps => &["block", "speed_mps"],
            Self::Hold => &["hold_s", "load", "fz_n", "camber_deg", "speed_mps", "slip_angle_deg"],
            Self::Standstill => &["hold_s", "load", "fz_n", "camber_deg"],
        }
    }
}

impl StepSpec {
    /// The keys present in this table.
    pub fn present_keys(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        macro_rules! k {
            ($($f:ident),*) => { $( if self.$f.is_some() { v.push(stringify!($f)); } )* };
        }
        k!(
            kind,
            label,
            mode,
            peak_deg,
            waypoints_deg,
            rate_dps,
            low_rate_dps,
            high_rate_dps,
            threshold_deg,
            peak_pct,
            waypoints_pct,
            rate_pct_ps,
            low_rate_pct_ps,
            high_rate_pct_ps,
            threshold_pct,
            load,
            loads,
            fz_n,
            asym,
            asym_factors,
            adverse,
            saturation_deg,
            low_load,
            high_load,
            camber_deg,
            cambers_deg,
            camber_coupling_deg,
            slip_angle_deg,
            slip_angles_deg,
            pressure,
            pressures,
            speed_mps,
            speeds_mps,
            repeat,
            thermal_pause,
            hold_s,
            distance_m,
            displacement_m,
            belt_speed_mps,
            roll_s,
            roll_speed_mps,
            pre_roll_s,
            steer_rate_dps,
            slip_rate_dps,
            blocks,
            block
        );
        v
    }

    /// Every numeric scalar present, with its key (for finiteness checks).
    fn numbers(&self) -> Vec<(&'static str, f64)> {
        let mut v = Vec::new();
        macro_rules! n {
            ($($f:ident),*) => { $( if let Some(x) = self.$f { v.push((stringify!($f), x)); } )* };
        }
        n!(
            peak_deg,
            rate_dps,
            low_rate_dps,
            high_rate_dps,
            threshold_deg,
            peak_pct,
            rate_pct_ps,
            low_rate_pct_ps,
            high_rate_pct_ps,
            threshold_pct,
            load,
            fz_n,
            saturation_deg,
            low_load,
            high_load,
            camber_deg,
            camber_coupling_deg,
            slip_angle_deg,
            speed_mps,
            hold_s,
            distance_m,
            displacement_m,
            belt_speed_mps,
            roll_s,
            roll_speed_mps,
            pre_roll_s,
            steer_rate_dps,
            slip_rate_dps
        );
        macro_rules! l {
            ($($f:ident),*) => { $( if let Some(xs) = &self.$f { for x in xs { v.push((stringify!($f), *x)); } } )* };
        }
        l!(waypoints_deg, waypoints_pct, loads, cambers_deg, slip_angles_deg, speeds_mps);
        if let Some([a, b]) = self.asym_factors {
            v.push(("asym_factors", a));
            v.push(("asym_factors", b));
        }
        v
    }
}

/// A loaded procedure file with its includes resolved.
#[derive(Debug, Clone)]
pub struct ProcedureDoc {
    /// File name as given (for error messages).
    pub file: String,
    /// The source text (for line lookups).
    pub src: String,
    /// The parsed file.
    pub spec: ProcedureFile,
    /// Included documents, in order, with their include specs.
    pub includes: Vec<(IncludeSpec, ProcedureDoc)>,
}

/// 1-based (line, column) of a byte offset.
pub fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(src.len());
    let before = &src[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rfind('\n').map_or(offset, |i| offset - i - 1) + 1;
    (line, col)
}

/// The line (1-based) where `key = …` appears in the table starting at `span` (the table's
/// body runs to the next `[` header), else the table's first line.
pub fn key_line(src: &str, span: std::ops::Range<usize>, key: &str) -> usize {
    let start = span.start.min(src.len());
    let mut offset = start;
    for (i, line) in src[start..].split_inclusive('\n').enumerate() {
        let t = line.trim_start();
        if i > 0 && t.starts_with('[') {
            break;
        }
        if let Some(rest) = t.strip_prefix(key)
            && rest.trim_start().starts_with('=')
        {
            return line_col(src, offset).0;
        }
        offset += line.len();
    }
    line_col(src, start).0
}

fn parse_error(file: &str, src: &str, e: &toml::de::Error) -> ProcedureError {
    let message = e.message().trim().to_owned();
    let span = e.span().unwrap_or(0..0);
    let (line, column) = line_col(src, span.start);
    // The key: named in the message (`unknown field `x``, `missing field `x``), else the text
    // left of `=` on the error's line, else the table header there.
    let key = if message.contains("field `") {
        message.split('`').nth(1).map(str::to_owned).unwrap_or_default()
    } else {
        let line_text = src.lines().nth(line.saturating_sub(1)).unwrap_or("");
        match line_text.split_once('=') {
            Some((k, _)) => k.trim().to_owned(),
            None => line_text.trim().to_owned(),
        }
    };
    ProcedureError::Parse { file: file.to_owned(), line, column, key, message }
}

/// Parse and validate one file's text (no includes resolved).
pub fn parse_file(file: &str, src: &str) -> Result<ProcedureFile, ProcedureError> {
    let spec: ProcedureFile = toml::from_str(src).map_err(|e| parse_error(file, src, &e))?;
    validate(file, src, &spec)?;
    Ok(spec)
}

/// Parse `file` and its includes; `read` returns the text of a path relative to the including
/// file's directory (the pure entry point: tests pass an in-memory map).
pub fn parse_with(
    file: &str,
    src: &str,
    read: &mut dyn FnMut(&str) -> Result<String, ProcedureError>,
) -> Result<ProcedureDoc, ProcedureError> {
    parse_rec(file, src, read, &mut vec![file.to_owned()])
}

fn parse_rec(
    file: &str,
    src: &str,
    read: &mut dyn FnMut(&str) -> Result<String, ProcedureError>,
    stack: &mut Vec<String>,
) -> Result<ProcedureDoc, ProcedureError> {
    let spec = parse_file(file, src)?;
    let dir = Path::new(file).parent().map(Path::to_path_buf).unwrap_or_default();
    let mut includes = Vec::new();
    for inc in &spec.include {
        let path: PathBuf = dir.join(&inc.get_ref().file);
        let name = path.to_string_lossy().into_owned();
        if stack.contains(&name) {
            return Err(ProcedureError::IncludeCycle { file: file.to_owned(), include: inc.get_ref().file.clone() });
        }
        let text = read(&name)?;
        stack.push(name.clone());
        let doc = parse_rec(&name, &text, read, stack)?;
        stack.pop();
        includes.push((inc.get_ref().clone(), doc));
    }
    Ok(ProcedureDoc { file: file.to_owned(), src: src.to_owned(), spec, includes })
}

/// Load a procedure file and its includes from disk.
pub fn load(path: &Path) -> Result<ProcedureDoc, ProcedureError> {
    let mut read =
        |p: &str| std::fs::read_to_string(p).map_err(|source| ProcedureError::Read { file: p.to_owned(), source });
    let name = path.to_string_lossy().into_owned();
    let src = read(&name)?;
    parse_with(&name, &src, &mut read)
}

fn validate(file: &str, src: &str, spec: &ProcedureFile) -> Result<(), ProcedureError> {
    // Header keys are looked up in the `[procedure]` table.
    let whole = src.find("[procedure]").unwrap_or(0)..src.len();
    let invalid = |span: std::ops::Range<usize>, key: &str, message: String| ProcedureError::Invalid {
        file: file.to_owned(),
        line: key_line(src, span, key),
        key: key.to_owned(),
        message,
    };
    let h = &spec.procedure;
    if h.name.trim().is_empty() {
        return Err(invalid(whole, "name", "must not be empty".into()));
    }
    if h.config_tag.trim().is_empty() || h.config_tag.contains(char::is_whitespace) {
        return Err(invalid(whole, "config_tag", "expected a word such as `FreeRoll` or `BrkDrv`".into()));
    }
    for (k, v) in [("tyre_change_s", h.tyre_change_s), ("free_rolling_ref_s", h.free_rolling_ref_s)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(whole.clone(), k, format!("expected seconds ≥ 0, got {v}")));
        }
    }
    if spec.section.is_empty() && spec.include.is_empty() {
        return Err(invalid(whole, "section", "a procedure needs at least one [[section]] or [[include]]".into()));
    }
    for sec in &spec.section {
        let span = sec.span();
        let s = sec.get_ref();
        if s.pressure.is_some() && s.pressures.is_some() {
            return Err(invalid(span, "pressures", "give either `pressure` or `pressures`, not both".into()));
        }
        if s.pressures.as_ref().is_some_and(Vec::is_empty) {
            return Err(invalid(span, "pressures", "expected at least one pressure".into()));
        }
        let slots = s.pressure.is_some() || s.pressures.is_some();
        if slots && (s.pressure_bar.is_some() || s.pressures_bar.is_some()) {
            return Err(invalid(
                span,
                "pressures_bar",
                "give either pressure slots (`pressure`, `pressures`) or bars (`pressure_bar`, `pressures_bar`), not both"
                    .into(),
            ));
        }
        if s.pressure_bar.is_some() && s.pressures_bar.is_some() {
            return Err(invalid(
                span,
                "pressures_bar",
                "give either `pressure_bar` or `pressures_bar`, not both".into(),
            ));
        }
        if s.pressures_bar.as_ref().is_some_and(Vec::is_empty) {
            return Err(invalid(span, "pressures_bar", "expected at least one pressure".into()));
        }
        for (key, p) in s
            .pressure_bar
            .iter()
            .map(|p| ("pressure_bar", *p))
            .chain(s.pressures_bar.iter().flatten().map(|p| ("pressures_bar", *p)))
        {
            if !(p.is_finite() && p > 0.0) {
                return Err(invalid(span.clone(), key, format!("expected a positive pressure in bar, got {p}")));
            }
        }
        if s.step.is_empty() {
            return Err(invalid(span, "step", format!("section `{}` has no [[section.step]]", s.name)));
        }
        for st in &s.step {
            validate_step(st.get_ref(), st.span(), &invalid)?;
        }
    }
    Ok(())
}

fn validate_step(
    st: &StepSpec,
    span: std::ops::Range<usize>,
    invalid: &dyn Fn(std::ops::Range<usize>, &str, String) -> ProcedureError,
) -> Result<(), ProcedureError> {
    let Some(kind) = st.kind else {
        return Err(invalid(
            span,
            "kind",
            "missing: expected one of sweep, vertical_load, on_centre, rolling_radius, \
             step_steer, static_long, warm_up, graph_sweeps, hold, standstill"
                .into(),
        ));
    };
    let allowed = kind.allowed_keys();
    for key in st.present_keys() {
        if !COMMON_KEYS.contains(&key) && !allowed.contains(&key) {
            return Err(invalid(
                span,
                key,
                format!("not used by kind `{kind:?}`; expected one of {}", allowed.join(", ")),
            ));
        }
    }
    for (key, x) in st.numbers() {
        if !x.is_finite() {
            return Err(invalid(span, key, format!("expected a finite number, got {x}")));
        }
    }
    let positive = [
        ("rate_dps", st.rate_dps),
        ("low_rate_dps", st.low_rate_dps),
        ("high_rate_dps", st.high_rate_dps),
        ("rate_pct_ps", st.rate_pct_ps),
        ("low_rate_pct_ps", st.low_rate_pct_ps),
        ("high_rate_pct_ps", st.high_rate_pct_ps),
        ("peak_deg", st.peak_deg),
        ("peak_pct", st.peak_pct),
        ("load", st.load),
        ("fz_n", st.fz_n),
        ("low_load", st.low_load),
        ("high_load", st.high_load),
        ("hold_s", st.hold_s),
        ("distance_m", st.distance_m),
        ("belt_speed_mps", st.belt_speed_mps),
        ("roll_speed_mps", st.roll_speed_mps),
        ("steer_rate_dps", st.steer_rate_dps),
        ("slip_rate_dps", st.slip_rate_dps),
        ("speed_mps", st.speed_mps),
        ("displacement_m", st.displacement_m),
        ("saturation_deg", st.saturation_deg),
    ];
    for (key, v) in positive {
        if let Some(x) = v
            && x <= 0.0
        {
            return Err(invalid(span, key, format!("expected a positive number, got {x}")));
        }
    }
    for (key, list) in [("loads", &st.loads), ("speeds_mps", &st.speeds_mps)] {
        if let Some(xs) = list {
            if xs.is_empty() {
                return Err(invalid(span, key, "expected a non-empty list".into()));
            }
            if let Some(x) = xs.iter().find(|x| **x <= 0.0) {
                return Err(invalid(span, key, format!("expected positive values, got {x}")));
            }
        }
    }
    for (key, empty) in [
        ("cambers_deg", st.cambers_deg.as_ref().is_some_and(Vec::is_empty)),
        ("slip_angles_deg", st.slip_angles_deg.as_ref().is_some_and(Vec::is_empty)),
        ("pressures", st.pressures.as_ref().is_some_and(Vec::is_empty)),
    ] {
        if empty {
            return Err(invalid(span, key, "expected a non-empty list".into()));
        }
    }
    for (key, a, b) in [
        ("loads", st.load.is_some(), st.loads.is_some()),
        ("cambers_deg", st.camber_deg.is_some(), st.cambers_deg.is_some()),
        ("slip_angles_deg", st.slip_angle_deg.is_some(), st.slip_angles_deg.is_some()),
        ("pressures", st.pressure.is_some(), st.pressures.is_some()),
        ("speeds_mps", st.speed_mps.is_some(), st.speeds_mps.is_some()),
    ] {
        if a && b {
            return Err(invalid(span, key, format!("give either the single value or `{key}`, not both")));
        }
    }
    if st.repeat == Some(0) {
        return Err(invalid(span, "repeat", "expected at least 1".into()));
    }
    match kind {
        StepKindSpec::Sweep => validate_sweep(st, span, invalid),
        StepKindSpec::VerticalLoad => {
            for k in ["low_load", "high_load"] {
                let present = if k == "low_load" { st.low_load } else { st.high_load };
                if present.is_none() {
                    return Err(invalid(span, k, "missing: expected a factor of Fz0".into()));
                }
            }
            if st.slip_angle_deg.is_none() && st.slip_angles_deg.is_none() {
                return Err(invalid(span, "slip_angle_deg", "missing: expected degrees".into()));
            }
            Ok(())
        }
        StepKindSpec::OnCentre => {
            if st.slip_angle_deg.is_none() && st.slip_angles_deg.is_none() {
                return Err(invalid(span, "slip_angles_deg", "missing: expected degrees".into()));
            }
            require_loads(st, span.clone(), invalid)?;
            require(st.hold_s, "hold_s", span, invalid)
        }
        StepKindSpec::RollingRadius => {
            require_loads(st, span.clone(), invalid)?;
            require(st.hold_s, "hold_s", span, invalid)
        }
        StepKindSpec::StepSteer => {
            if st.slip_angle_deg.is_none() && st.slip_angles_deg.is_none() {
                return Err(invalid(span, "slip_angles_deg", "missing: expected degrees".into()));
            }
            require_loads(st, span, invalid)
        }
        StepKindSpec::StaticLong => require_loads(st, span, invalid),
        StepKindSpec::WarmUp => require_loads(st, span, invalid),
        StepKindSpec::GraphSweeps => {
            if st.block.is_none() {
                return Err(invalid(span, "block", "missing: expected `free_rolling` or `brk_drv`".into()));
            }
            Ok(())
        }
        StepKindSpec::Hold | StepKindSpec::Standstill => require(st.hold_s, "hold_s", span, invalid),
    }
}

fn require(
    v: Option<f64>,
    key: &str,
    span: std::ops::Range<usize>,
    invalid: &dyn Fn(std::ops::Range<usize>, &str, String) -> ProcedureError,
) -> Result<(), ProcedureError> {
    if v.is_none() {
        return Err(invalid(span, key, "missing".into()));
    }
    Ok(())
}

fn require_loads(
    st: &StepSpec,
    span: std::ops::Range<usize>,
    invalid: &dyn Fn(std::ops::Range<usize>, &str, String) -> ProcedureError,
) -> Result<(), ProcedureError> {
    if st.load.is_none() && st.loads.is_none() {
        return Err(invalid(span, "loads", "missing: expected `load` or `loads` (factors of Fz0)".into()));
    }
    Ok(())
}

fn validate_sweep(
    st: &StepSpec,
    span: std::ops::Range<usize>,
    invalid: &dyn Fn(std::ops::Range<usize>, &str, String) -> ProcedureError,
) -> Result<(), ProcedureError> {
    let deg = [
        st.peak_deg.is_some(),
        st.waypoints_deg.is_some(),
        st.rate_dps.is_some(),
        st.low_rate_dps.is_some(),
        st.high_rate_dps.is_some(),
        st.threshold_deg.is_some(),
    ];
    let pct = [
        st.peak_pct.is_some(),
        st.waypoints_pct.is_some(),
        st.rate_pct_ps.is_some(),
        st.low_rate_pct_ps.is_some(),
        st.high_rate_pct_ps.is_some(),
        st.threshold_pct.is_some(),
    ];
    let is_deg = deg.iter().any(|x| *x);
    let is_pct = pct.iter().any(|x| *x);
    if is_deg && is_pct {
        return Err(invalid(
            span,
            "peak_pct",
            "a sweep moves either slip angle (`*_deg`, `*_dps` keys) or slip ratio (`*_pct`, \
             `*_pct_ps` keys), not both"
                .into(),
        ));
    }
    if !is_deg && !is_pct {
        return Err(invalid(
            span,
            "peak_deg",
            "missing: expected `peak_deg` or `waypoints_deg` (slip angle) or `peak_pct` or \
             `waypoints_pct` (slip ratio)"
                .into(),
        ));
    }
    let (peak, wp, rate, lo, hi, th, sfx) = if is_deg {
        (deg[0], deg[1], st.rate_dps, st.low_rate_dps, st.high_rate_dps, st.threshold_deg, "deg")
    } else {
        (pct[0], pct[1], st.rate_pct_ps, st.low_rate_pct_ps, st.high_rate_pct_ps, st.threshold_pct, "pct")
    };
    let rsfx = if is_deg { "dps" } else { "pct_ps" };
    if peak == wp {
        return Err(invalid(
            span,
            &format!("peak_{sfx}"),
            format!("give exactly one of `peak_{sfx}` and `waypoints_{sfx}`"),
        ));
    }
    let wps = if is_deg { &st.waypoints_deg } else { &st.waypoints_pct };
    if let Some(w) = wps
        && w.len() < 2
    {
        return Err(invalid(span, &format!("waypoints_{sfx}"), "expected at least two waypoints".into()));
    }
    let variable = [lo.is_some(), hi.is_some(), th.is_some()];
    match (rate.is_some(), variable) {
        (true, [false, false, false]) => {}
        (false, [true, true, true]) => {
            if let Some(t) = th
                && t < 0.0
            {
                return Err(invalid(span, &format!("threshold_{sfx}"), "expected ≥ 0".into()));
            }
        }
        (true, _) => {
            return Err(invalid(
                span,
                &format!("rate_{rsfx}"),
                format!(
                    "a constant-rate sweep takes `rate_{rsfx}` only; a variable-rate sweep \
                     takes `low_rate_{rsfx}`, `high_rate_{rsfx}` and `threshold_{sfx}`"
                ),
            ));
        }
        (false, v) => {
            let missing = ["low_rate", "high_rate", "threshold"]
                .iter()
                .zip(v)
                .find(|(_, p)| !*p)
                .map(|(k, _)| *k)
                .unwrap_or("rate");
            let key = if missing == "threshold" { format!("threshold_{sfx}") } else { format!("{missing}_{rsfx}") };
            return Err(invalid(
                span,
                &key,
                format!(
                    "missing: expected `rate_{rsfx}` (constant rate) or all of `low_rate_{rsfx}`, \
                     `high_rate_{rsfx}`, `threshold_{sfx}` (variable rate)"
                ),
            ));
        }
    }
    let load_ways =
        [st.load.is_some() || st.loads.is_some(), st.fz_n.is_some(), st.asym.is_some() || st.asym_factors.is_some()];
    if load_ways.iter().filter(|x| **x).count() != 1 {
        return Err(invalid(
            span,
            "load",
            "expected exactly one of `load`/`loads` (factors of Fz0), `fz_n` (newtons) or \
             `asym`/`asym_factors` (asymmetric loading)"
                .into(),
        ));
    }
    if st.asym.is_some() && st.asym_factors.is_some() {
        return Err(invalid(span, "asym_factors", "give either the preset `asym` or `asym_factors`, not both".into()));
    }
    if is_pct && (load_ways[2] || st.camber_coupling_deg.is_some()) {
        return Err(invalid(
            span,
            if load_ways[2] { "asym" } else { "camber_coupling_deg" },
            "asymmetric loading and camber coupling follow slip angle; they are not used on \
             slip-ratio sweeps (braking and driving differ, §3.7)"
                .into(),
        ));
    }
    if st.camber_coupling_deg.is_some() && (st.camber_deg.is_some() || st.cambers_deg.is_some()) {
        return Err(invalid(
            span,
            "camber_coupling_deg",
            "give either a camber coupling or fixed cambers, not both".into(),
        ));
    }
    Ok(())
}
