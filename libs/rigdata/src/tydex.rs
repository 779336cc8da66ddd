//! TYDEX `.tdx` files (TYDEX 1.3): keyword blocks `**HEADER`, `**COMMENTS`, `**CONSTANTS`,
//! `**MEASURCHNLS`, `**MEASURDATA`, `**END`. Channel and constant lines are fixed-width: name in
//! columns 1–10, description 11–40, unit 41–50, then the conversion factor to SI (and sometimes
//! an offset) for a channel, or the value for a constant.
//!
//! Two kinds of file come in:
//! * tyrerig's own export ([`to_tydex`]): the fitter's segments in ISO-W, with a `SEGMENT`
//!   channel indexing `SEGMENT` lines of `**COMMENTS` that keep procedure, kind, section and sweep
//!   name, so export → import loses nothing the fitter uses ([`read_own`]);
//! * other tools' and rigs' files: channel subsets and units vary (deg or rad, bar or Pa, kN or
//!   N, km/h); they become a [`ChannelTable`] in the units the conversion factor implies, and go
//!   through the same interpretation and sweep finding as TTC files. One file usually holds one
//!   measurement, so a test is a folder of them.

use std::fmt::Write as _;
use std::path::Path;

use mffit::{DataKind, Dataset, Procedure, Sample, Segment};

use crate::channels::role_of;
use crate::error::{Place, ReadError, Warning, Warnings};
use crate::table::{ChannelTable, Column};
use crate::units::{self, Quantity};

/// A channel line of `**MEASURCHNLS`.
#[derive(Debug, Clone, PartialEq)]
pub struct TdxChannel {
    /// Name (TYDEX: `FX`, `SLIPANGL`, …).
    pub name: String,
    /// Description.
    pub description: String,
    /// Unit as written.
    pub unit: String,
    /// Conversion factor to SI (1 when absent).
    pub factor: f64,
    /// Offset after the factor (0 when absent).
    pub offset: f64,
    /// Line in the file.
    pub line: usize,
}

/// A `**CONSTANTS` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct TdxConstant {
    /// Name.
    pub name: String,
    /// Description.
    pub description: String,
    /// Unit.
    pub unit: String,
    /// Value as written.
    pub value: String,
}

/// A TYDEX file's blocks, as written.
#[derive(Debug, Clone, Default)]
pub struct TdxFile {
    /// `**HEADER` lines as (keyword, value).
    pub header: Vec<(String, String)>,
    /// `**COMMENTS` lines.
    pub comments: Vec<String>,
    /// `**CONSTANTS`.
    pub constants: Vec<TdxConstant>,
    /// `**MEASURCHNLS`.
    pub channels: Vec<TdxChannel>,
    /// `**MEASURDATA` rows (values as written), with their first line.
    pub rows: Vec<(usize, Vec<f64>)>,
    /// What was odd.
    pub warnings: Vec<Warning>,
}

/// Fixed-width fields of a channel/constant line: name (1–10), description (11–40), unit
/// (41–50), rest; a short line is split on whitespace instead (name, …, unit, numbers).
fn fixed(line: &str) -> (String, String, String, String) {
    let chars: Vec<char> = line.chars().collect();
    let part = |a: usize, b: usize| {
        chars.get(a..b.min(chars.len())).map(|c| c.iter().collect::<String>().trim().to_owned()).unwrap_or_default()
    };
    if chars.len() > 50 && !chars[..10].iter().collect::<String>().trim().contains(' ') {
        return (part(0, 10), part(10, 40), part(40, 50), part(50, chars.len()));
    }
    let w: Vec<&str> = line.split_whitespace().collect();
    let nums = w.iter().rev().take_while(|s| s.parse::<f64>().is_ok()).count().min(2).min(w.len().saturating_sub(1));
    let rest = w[w.len() - nums..].join(" ");
    let unit = if w.len() >= 2 + nums { w[w.len() - nums - 1].to_owned() } else { String::new() };
    let desc = if w.len() > 2 + nums { w[1..w.len() - nums - 1].join(" ") } else { String::new() };
    (w.first().map(|s| (*s).to_owned()).unwrap_or_default(), desc, unit, rest)
}

/// Parses the text of a TYDEX file.
pub fn parse_tdx(text: &str, file: &str) -> Result<TdxFile, ReadError> {
    let mut warn = Warnings::default();
    let mut out = TdxFile::default();
    let mut block = "";
    let mut pending: Vec<f64> = Vec::new();
    let mut pending_line = 0;
    let mut ended = false;
    for (ln, line) in text.lines().enumerate() {
        let ln = ln + 1;
        let line = line.strip_suffix('\r').unwrap_or(line);
        let t = line.trim();
        if let Some(kw) = t.strip_prefix("**") {
            block = match kw.trim().to_ascii_uppercase().as_str() {
                "HEADER" => "header",
                "COMMENTS" => "comments",
                "CONSTANTS" => "constants",
                "MEASURCHNLS" => "channels",
                "MEASURDATA" => "data",
                "END" => {
                    ended = true;
                    "end"
                }
                other => {
                    warn.push("block", Place::line(file, ln), format!("unknown block `**{other}`: skipped"));
                    "other"
                }
            };
            continue;
        }
        if t.is_empty() || t.starts_with('!') || t.starts_with('$') {
            continue;
        }
        match block {
            "header" => {
                let (k, v) = t.split_once(char::is_whitespace).unwrap_or((t, ""));
                out.header.push((k.to_ascii_uppercase(), v.trim().to_owned()));
            }
            "comments" => out.comments.push(t.to_owned()),
            "constants" => {
                let (name, description, unit, value) = fixed(line);
                out.constants.push(TdxConstant { name: name.to_ascii_uppercase(), description, unit, value });
            }
            "channels" => {
                let (name, description, unit, rest) = fixed(line);
                let mut nums = rest.split_whitespace().map(str::parse::<f64>);
                let factor = match nums.next() {
                    Some(Ok(f)) if f.is_finite() && f != 0.0 => f,
                    Some(_) => {
                        warn.push(
                            "factor",
                            Place::line(file, ln).channel(&name),
                            format!("conversion factor `{rest}` is not a non-zero number: 1 used"),
                        );
                        1.0
                    }
                    None => 1.0,
                };
                let offset = nums.next().and_then(Result::ok).filter(|o| o.is_finite()).unwrap_or(0.0);
                out.channels.push(TdxChannel {
                    name: name.to_ascii_uppercase(),
                    description,
                    unit,
                    factor,
                    offset,
                    line: ln,
                });
            }
            "data" => {
                if out.channels.is_empty() {
                    return Err(ReadError::at(Place::line(file, ln), "**MEASURDATA before any **MEASURCHNLS channel"));
                }
                if pending.is_empty() {
                    pending_line = ln;
                }
                for (k, w) in t.split_whitespace().enumerate() {
                    match w.parse::<f64>() {
                        Ok(v) => pending.push(v),
                        Err(_) => {
                            let ch = out
                                .channels
                                .get((pending.len()) % out.channels.len())
                                .map(|c| c.name.clone())
                                .unwrap_or_default();
                            warn.push(
                                "not a number",
                                Place::line(file, ln).channel(&ch),
                                format!("value {} `{w}` is not a number: read as NaN", k + 1),
                            );
                            pending.push(f64::NAN);
                        }
                    }
                }
                let n = out.channels.len();
                // A row may wrap over several lines; a line holding more than a row is an error.
                if pending.len() == n {
                    out.rows.push((pending_line, std::mem::take(&mut pending)));
                } else if pending.len() > n {
                    return Err(ReadError::at(
                        Place::line(file, ln),
                        format!("{} values where a row has {n} (one per **MEASURCHNLS channel)", pending.len()),
                    ));
                }
            }
            "end" => {}
            _ => {}
        }
    }
    if !pending.is_empty() {
        warn.push(
            "truncated row",
            Place::line(file, pending_line),
            format!("last row has {} of {} values: dropped", pending.len(), out.channels.len()),
        );
    }
    if !ended {
        warn.push("no end", Place::file(file), "no **END line: the file may be truncated");
    }
    if out.channels.is_empty() {
        return Err(ReadError::at(Place::file(file), "no **MEASURCHNLS block (channel list)"));
    }
    if out.rows.is_empty() {
        return Err(ReadError::at(Place::file(file), "no rows in **MEASURDATA"));
    }
    out.warnings = warn.finish(file);
    Ok(out)
}

/// Reads and parses a TYDEX file.
pub fn read_tdx(path: &Path) -> Result<TdxFile, ReadError> {
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_owned(), source })?;
    parse_tdx(&String::from_utf8_lossy(&bytes), &path.display().to_string())
}

impl TdxFile {
    /// True for a file written by [`to_tydex`] (segments listed in the comments).
    pub fn is_own(&self) -> bool {
        self.channels.iter().any(|c| c.name == "SEGMENT") && self.comments.iter().any(|c| c.starts_with("SEGMENT "))
    }

    /// A header value or constant by name.
    pub fn value(&self, name: &str) -> Option<&str> {
        self.header
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
            .or_else(|| self.constants.iter().find(|c| c.name.eq_ignore_ascii_case(name)).map(|c| c.value.as_str()))
    }

    /// A numeric constant converted by its unit to the fitter's (N, Pa, m, …).
    pub fn constant_si(&self, names: &[&str]) -> Option<(f64, String)> {
        self.constants.iter().find(|c| names.iter().any(|n| c.name.eq_ignore_ascii_case(n))).and_then(|c| {
            let v: f64 = c.value.split_whitespace().next()?.parse().ok()?;
            let u = units::parse(&c.unit);
            Some((u.map(|u| u.to_target(v)).unwrap_or(v), c.name.clone()))
        })
    }

    /// The tyre's name from the header (`MANUFACT`, `TYRESIZE`, …).
    pub fn tyre_id(&self) -> Option<String> {
        let parts: Vec<&str> = ["MANUFACT", "TYRENAME", "TIRENAME", "TYRE", "TYRESIZE"]
            .iter()
            .filter_map(|k| self.value(k))
            .filter(|v| !v.is_empty())
            .collect();
        (!parts.is_empty()).then(|| parts.join(" "))
    }

    /// The test's kind as the file states it (header or constants).
    pub fn test_id(&self) -> Option<String> {
        ["TESTMETH", "TESTKIND", "TESTTYPE", "MEASTYPE", "TESTNAME", "TEST"]
            .iter()
            .filter_map(|k| self.value(k))
            .find(|v| !v.is_empty())
            .map(str::to_owned)
    }

    /// A foreign file → a table in the units its conversion factors imply. Where a factor
    /// agrees with the written unit (or is 1), the unit is kept; where it does not, TYDEX's rule
    /// holds (value × factor + offset is SI) and the channel is given in SI, with a warning.
    pub fn to_table(&self, file: &str) -> (ChannelTable, Vec<Warning>) {
        let mut warn = Warnings::default();
        let mut table = ChannelTable {
            source: file.to_owned(),
            tire_id: self.tyre_id(),
            test_id: self.test_id(),
            ..Default::default()
        };
        table.title = self.value("MEASID").map(|m| format!("TYDEX measurement {m}"));
        for (k, c) in self.channels.iter().enumerate() {
            let place = Place::line(file, c.line).channel(&c.name);
            let values: Vec<f64> = self.rows.iter().map(|(_, r)| r[k]).collect();
            let role = role_of(&c.name);
            let unit = units::parse(&c.unit).filter(|u| role.is_none_or(|r| r.quantity() == u.quantity));
            let identity = (c.factor - 1.0).abs() < 1e-12 && c.offset == 0.0;
            let si_name = |q: Quantity| match q {
                Quantity::Temperature => "K",
                Quantity::Moment => "N-m",
                Quantity::Ratio => "none",
                q => q.target_unit(),
            };
            let (unit_text, values) = match (role, unit) {
                (_, Some(u)) => {
                    let (s, o) = units::tydex_si_factor(&u);
                    let agrees = (c.factor / s - 1.0).abs() < 1e-3 && (c.offset - o).abs() < 1e-3 * s.max(1.0);
                    if identity || agrees {
                        (c.unit.clone(), values)
                    } else {
                        warn.push(
                            "factor",
                            place,
                            format!("unit `{}` but conversion factor {} (offset {}): the factor used (value × factor + offset = SI)", c.unit, c.factor, c.offset),
                        );
                        (si_name(u.quantity).to_owned(), values.iter().map(|v| v * c.factor + c.offset).collect())
                    }
                }
                (Some(r), None) if !identity || c.unit.trim().is_empty() => {
                    if !c.unit.trim().is_empty() {
                        warn.push(
                            "factor",
                            place,
                            format!("unit `{}` unknown: the conversion factor to SI used", c.unit),
                        );
                    }
                    (si_name(r.quantity()).to_owned(), values.iter().map(|v| v * c.factor + c.offset).collect())
                }
                _ => (c.unit.clone(), values),
            };
            table.columns.push(Column { name: c.name.clone(), unit: unit_text, values });
        }
        // A file without a pressure channel states the pressure as a constant.
        if table.column("INFLPRES").is_none()
            && let Some((p, name)) = self.constant_si(&["NOMPRES", "INFLPRES", "PRESSURE"])
        {
            warn.push(
                "constant",
                Place::file(file).channel(&name),
                format!("no INFLPRES channel: the constant {name} = {:.0} Pa used", p),
            );
            let n = table.rows();
            table.columns.push(Column { name: "INFLPRES".into(), unit: "Pa".into(), values: vec![p; n] });
        }
        (table, warn.finish(file))
    }
}

// ---------------------------------------------------------------------------------------------
// tyrerig's own TYDEX export and its exact import.

struct Chan {
    name: &'static str,
    desc: &'static str,
    unit: &'static str,
    get: fn(&Sample) -> f64,
    set: fn(&mut Sample, f64),
}

const CHANNELS: [Chan; 19] = [
    Chan { name: "RUNTIME", desc: "Running time", unit: "s", get: |s| s.time_s, set: |s, v| s.time_s = v },
    Chan { name: "FX", desc: "Longitudinal force", unit: "N", get: |s| s.fx_n, set: |s, v| s.fx_n = v },
    Chan { name: "FYW", desc: "Lateral force", unit: "N", get: |s| s.fy_n, set: |s, v| s.fy_n = v },
    Chan { name: "FZW", desc: "Vertical load", unit: "N", get: |s| s.fz_n, set: |s, v| s.fz_n = v },
    Chan { name: "MXW", desc: "Overturning moment", unit: "Nm", get: |s| s.mx_nm, set: |s, v| s.mx_nm = v },
    Chan { name: "MYW", desc: "Rolling resistance moment", unit: "Nm", get: |s| s.my_nm, set: |s, v| s.my_nm = v },
    Chan { name: "MZW", desc: "Aligning moment", unit: "Nm", get: |s| s.mz_nm, set: |s, v| s.mz_nm = v },
    Chan {
        name: "SLIPANGL",
        desc: "Slip angle",
        unit: "deg",
        get: |s| s.alpha_rad.to_degrees(),
        set: |s, v| s.alpha_rad = v.to_radians(),
    },
    Chan { name: "LONGSLIP", desc: "Longitudinal slip", unit: "-", get: |s| s.kappa, set: |s, v| s.kappa = v },
    Chan {
        name: "INCLANGL",
        desc: "Inclination angle",
        unit: "deg",
        get: |s| s.gamma_rad.to_degrees(),
        set: |s, v| s.gamma_rad = v.to_radians(),
    },
    Chan { name: "INFLPRES", desc: "Inflation pressure", unit: "Pa", get: |s| s.p_pa, set: |s, v| s.p_pa = v },
    Chan { name: "TRAJVELW", desc: "Forward velocity", unit: "m/s", get: |s| s.vx_mps, set: |s, v| s.vx_mps = v },
    Chan {
        name: "ROTSPEED",
        desc: "Wheel rotational speed",
        unit: "rad/s",
        get: |s| s.omega_radps,
        set: |s, v| s.omega_radps = v,
    },
    Chan { name: "DSTWOWHC", desc: "Wheel centre to ground", unit: "m", get: |s| s.rl_m, set: |s, v| s.rl_m = v },
    Chan {
        name: "TRDTEMPI",
        desc: "Tread temperature inner",
        unit: "degC",
        get: |s| s.temp_inner_c,
        set: |s, v| s.temp_inner_c = v,
    },
    Chan {
        name: "TRDTEMPC",
        desc: "Tread temperature centre",
        unit: "degC",
        get: |s| s.temp_c,
        set: |s, v| s.temp_c = v,
    },
    Chan {
        name: "TRDTEMPO",
        desc: "Tread temperature outer",
        unit: "degC",
        get: |s| s.temp_outer_c,
        set: |s, v| s.temp_outer_c = v,
    },
    Chan {
        name: "ROADTEMP",
        desc: "Road surface temperature",
        unit: "degC",
        get: |s| s.road_temp_c,
        set: |s, v| s.road_temp_c = v,
    },
    Chan {
        name: "LONGDISP",
        desc: "Longitudinal displacement",
        unit: "m",
        get: |s| s.dist_m,
        set: |s, v| s.dist_m = v,
    },
];

fn kind_name(k: DataKind) -> &'static str {
    match k {
        DataKind::WarmUp => "WarmUp",
        DataKind::GraphSweep => "GraphSweep",
        DataKind::Sweep => "Sweep",
        DataKind::OnCentre => "OnCentre",
        DataKind::RollingRadius => "RollingRadius",
        DataKind::StepSteer => "StepSteer",
        DataKind::StaticLong => "StaticLong",
    }
}

fn kind_of(s: &str) -> Option<DataKind> {
    Some(match s {
        "WarmUp" => DataKind::WarmUp,
        "GraphSweep" => DataKind::GraphSweep,
        "Sweep" => DataKind::Sweep,
        "OnCentre" => DataKind::OnCentre,
        "RollingRadius" => DataKind::RollingRadius,
        "StepSteer" => DataKind::StepSteer,
        "StaticLong" => DataKind::StaticLong,
        _ => return None,
    })
}

/// Text of a TYDEX file holding every segment of `data` (ISO-W; the conversion factors are the
/// units' factors to SI, temperatures with the 273.15 offset).
pub fn to_tydex(data: &Dataset, measid: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "**HEADER\nRELEASE   1.3\nMEASID    {measid}\nSUPPLIER  tyrerig\nDATE      -\n");
    let _ = writeln!(
        s,
        "**COMMENTS\nISO-W axes (TYDEX-W), contact-patch centred; SI units unless the channel says otherwise."
    );
    if let Some(f) = data.fnomin_n {
        let _ = writeln!(s, "FNOMIN {f}");
    }
    // Names never hold whitespace in our logs; replace it so the line splits cleanly.
    let clean = |t: &str| if t.is_empty() { "-".to_owned() } else { t.replace(char::is_whitespace, "_") };
    for (i, seg) in data.segments.iter().enumerate() {
        let _ = writeln!(
            s,
            "SEGMENT {i} {} {} {} {}",
            seg.procedure.name(),
            kind_name(seg.kind),
            clean(&seg.section),
            clean(&seg.sweep)
        );
    }
    if let Some(f) = data.fnomin_n {
        let _ = writeln!(s, "\n**CONSTANTS\n{:<10}{:<30}{:<10}{f}", "FNOMIN", "Nominal load", "N");
    }
    let _ = writeln!(s, "\n**MEASURCHNLS");
    for c in &CHANNELS {
        let (f, o) = units::parse(c.unit).map(|u| units::tydex_si_factor(&u)).unwrap_or((1.0, 0.0));
        let offset = if o != 0.0 { format!(" {o}") } else { String::new() };
        let _ = writeln!(s, "{:<10}{:<30}{:<10}{f:.15}{offset}", c.name, c.desc, c.unit);
    }
    let _ = writeln!(s, "{:<10}{:<30}{:<10}{:.15}", "SEGMENT", "Segment index (see COMMENTS)", "-", 1.0);
    let _ = writeln!(s, "\n**MEASURDATA");
    for (i, seg) in data.segments.iter().enumerate() {
        for smp in &seg.samples {
            for c in &CHANNELS {
                let _ = write!(s, "{:.12e} ", (c.get)(smp));
            }
            let _ = writeln!(s, "{i}");
        }
    }
    let _ = writeln!(s, "**END");
    s
}

/// Writes our TYDEX export.
pub fn write_tydex(path: &Path, data: &Dataset) -> Result<(), ReadError> {
    let id = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    std::fs::write(path, to_tydex(data, &id)).map_err(|source| ReadError::Io { path: path.to_owned(), source })
}

/// The dataset of a file [`to_tydex`] wrote: segments exactly as exported. Rows whose load,
/// slip angle or slip ratio is not a number (a damaged file) are dropped with a warning.
pub fn read_own(tdx: &TdxFile, file: &str) -> Result<(Dataset, Vec<Warning>), ReadError> {
    let mut warn = Warnings::default();
    let mut meta: Vec<(Procedure, DataKind, String, String)> = Vec::new();
    let mut fnomin = None;
    for c in &tdx.comments {
        let w: Vec<&str> = c.split_whitespace().collect();
        if w.first() == Some(&"SEGMENT") && w.len() >= 6 {
            let procedure = match w[2] {
                "FreeRolling" => Procedure::FreeRolling,
                "BrkDrv" => Procedure::BrkDrv,
                "StaticLong" => Procedure::StaticLong,
                other => {
                    return Err(ReadError::at(
                        Place::file(file),
                        format!("**COMMENTS: unknown procedure `{other}` in `{c}`"),
                    ));
                }
            };
            let kind = kind_of(w[3]).ok_or_else(|| {
                ReadError::at(Place::file(file), format!("**COMMENTS: unknown segment kind `{}`", w[3]))
            })?;
            let un = |x: &str| if x == "-" { String::new() } else { x.to_owned() };
            meta.push((procedure, kind, un(w[4]), un(w[5])));
        } else if w.first() == Some(&"FNOMIN") && w.len() >= 2 {
            fnomin = w[1].parse().ok();
        }
    }
    let seg_col = tdx
        .channels
        .iter()
        .position(|c| c.name == "SEGMENT")
        .ok_or_else(|| ReadError::at(Place::file(file), "no SEGMENT channel"))?;
    // Each known channel with the unit conversion its unit line implies.
    let setters: Vec<(usize, &Chan, units::Unit)> = tdx
        .channels
        .iter()
        .enumerate()
        .filter_map(|(k, c)| {
            let ch = CHANNELS.iter().find(|x| x.name == c.name)?;
            let written = units::parse(&c.unit)?;
            let ours = units::parse(ch.unit)?;
            // Value in our unit = (value in the written unit → fitter unit) → our unit.
            let u = units::Unit {
                quantity: written.quantity,
                scale: written.scale / ours.scale,
                offset: (written.offset - ours.offset) / ours.scale,
            };
            Some((k, ch, u))
        })
        .collect();
    let mut segments: Vec<Segment> = Vec::new();
    for (ln, row) in &tdx.rows {
        let idx = row[seg_col];
        if !(idx >= 0.0 && idx < meta.len() as f64 && idx.fract() == 0.0) {
            return Err(ReadError::at(
                Place::line(file, *ln).channel("SEGMENT"),
                format!("segment index {idx} not listed in **COMMENTS"),
            ));
        }
        let i = idx as usize;
        while segments.len() <= i {
            let (procedure, kind, section, sweep) = meta[segments.len()].clone();
            segments.push(Segment { procedure, kind, section, sweep, samples: Vec::new(), cell: None, origin: None });
        }
        let mut s = Sample::default();
        for (k, ch, u) in &setters {
            (ch.set)(&mut s, u.to_target(row[*k]));
        }
        if !(s.fz_n.is_finite() && s.alpha_rad.is_finite() && s.kappa.is_finite()) {
            warn.push("non-finite", Place::line(file, *ln), "FZW, SLIPANGL or LONGSLIP not a number: row dropped");
            continue;
        }
        segments[i].samples.push(s);
    }
    segments.retain(|s| !s.samples.is_empty());
    Ok((Dataset { segments, fnomin_n: fnomin, sources: vec![file.to_owned()] }, warn.finish(file)))
}
