//! Data formats people already have: TYDEX `.tdx` (export and import) and Calspan TTC-style
//! tab-separated `.dat` files (import, SAE → ISO-W).
//!
//! TYDEX files written here carry the channels the thesis uses (RUNTIME, FX, FYW, FZW, MXW, MYW,
//! MZW, SLIPANGL, LONGSLIP, INCLANGL, INFLPRES, TRAJVELW, ROTSPEED, DSTWOWHC, TRDTEMPC,
//! LONGDISP) in ISO-W axes, plus SEGMENT (index into the `SEGMENT` lines of `**COMMENTS`, which
//! keep procedure, kind, section and sweep name so a round trip loses nothing the fitter uses).
//! Channel lines are fixed-width (name 1–10, description 11–40, unit 41–50, then the conversion
//! factor), the layout of the TYDEX 1.3 `**MEASURCHNLS` block.
//!
//! SAE → ISO-W (Pacejka, *Tire and Vehicle Dynamics*, §2.2): the SAE frame is the ISO frame
//! turned 180° about x, so FY, FZ, MY, MZ and the slip angle change sign; FX, MX, slip ratio and
//! inclination angle keep theirs.

use std::fmt::Write as _;
use std::path::Path;

use crate::data::{DataKind, Dataset, Procedure, Sample, Segment};
use crate::error::FitError;

struct Chan {
    name: &'static str,
    desc: &'static str,
    unit: &'static str,
    get: fn(&Sample) -> f64,
    set: fn(&mut Sample, f64),
}

const CHANNELS: [Chan; 16] = [
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
        name: "TRDTEMPC",
        desc: "Tread temperature centre",
        unit: "degC",
        get: |s| s.temp_c,
        set: |s, v| s.temp_c = v,
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

/// Text of a TYDEX file holding every segment of `data`.
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
    for (i, seg) in data.segments.iter().enumerate() {
        // Names never hold whitespace in our logs; replace it so the line splits cleanly.
        let clean = |t: &str| if t.is_empty() { "-".to_owned() } else { t.replace(char::is_whitespace, "_") };
        let _ = writeln!(
            s,
            "SEGMENT {i} {} {} {} {}",
            seg.procedure.name(),
            kind_name(seg.kind),
            clean(&seg.section),
            clean(&seg.sweep)
        );
    }
    let _ = writeln!(s, "\n**MEASURCHNLS");
    for c in &CHANNELS {
        let _ = writeln!(s, "{:<10}{:<30}{:<10}{:>10}", c.name, c.desc, c.unit, 1);
    }
    let _ = writeln!(s, "{:<10}{:<30}{:<10}{:>10}", "SEGMENT", "Segment index (see COMMENTS)", "-", 1);
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

/// Writes a TYDEX file.
pub fn write_tydex(path: &Path, data: &Dataset) -> Result<(), FitError> {
    let id = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    std::fs::write(path, to_tydex(data, &id)).map_err(|source| FitError::Io { path: path.to_owned(), source })
}

/// Scale (and offset) turning a value in `unit` into the fitter's unit for that quantity.
fn unit_factor(unit: &str) -> (f64, f64) {
    match unit.trim().to_ascii_lowercase().as_str() {
        "kpa" => (1e3, 0.0),
        "bar" => (1e5, 0.0),
        "psi" => (6894.757, 0.0),
        "km/h" | "kph" => (1.0 / 3.6, 0.0),
        "rpm" => (std::f64::consts::PI / 30.0, 0.0),
        "mm" => (1e-3, 0.0),
        "cm" => (1e-2, 0.0),
        "kn" => (1e3, 0.0),
        "rad" => (180.0 / std::f64::consts::PI, 0.0), // angles are stored in degrees in the table
        "%" => (0.01, 0.0),
        "degf" => (5.0 / 9.0, -32.0 * 5.0 / 9.0),
        _ => (1.0, 0.0),
    }
}

fn fmt_err(path: &Path, line: usize, message: impl Into<String>) -> FitError {
    FitError::Format { path: path.to_owned(), line, message: message.into() }
}

/// Parses a TYDEX file (ours or another tool's, as long as its channel names are TYDEX's).
pub fn parse_tydex(text: &str, path: &Path) -> Result<Dataset, FitError> {
    let mut section = "";
    let mut chans: Vec<(String, (f64, f64), f64)> = Vec::new();
    let mut segs_meta: Vec<(Procedure, DataKind, String, String)> = Vec::new();
    let mut fnomin = None;
    let mut rows: Vec<(usize, Sample)> = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let ln = ln + 1;
        let t = line.trim();
        if t.starts_with("**") {
            section = match t {
                "**HEADER" => "header",
                "**COMMENTS" => "comments",
                "**CONSTANTS" => "constants",
                "**MEASURCHNLS" => "channels",
                "**MEASURDATA" => "data",
                "**END" => "end",
                _ => "other",
            };
            continue;
        }
        if t.is_empty() {
            continue;
        }
        match section {
            "comments" => {
                let w: Vec<&str> = t.split_whitespace().collect();
                if w.first() == Some(&"SEGMENT") && w.len() >= 6 {
                    let procedure = match w[2] {
                        "FreeRolling" => Procedure::FreeRolling,
                        "BrkDrv" => Procedure::BrkDrv,
                        "StaticLong" => Procedure::StaticLong,
                        other => return Err(fmt_err(path, ln, format!("unknown procedure `{other}`"))),
                    };
                    let kind =
                        kind_of(w[3]).ok_or_else(|| fmt_err(path, ln, format!("unknown segment kind `{}`", w[3])))?;
                    let un = |x: &str| if x == "-" { String::new() } else { x.to_owned() };
                    segs_meta.push((procedure, kind, un(w[4]), un(w[5])));
                } else if w.first() == Some(&"FNOMIN") && w.len() >= 2 {
                    fnomin = w[1].parse().ok();
                }
            }
            "channels" => {
                let (name, unit, factor) = if line.len() >= 50
                    && line.is_char_boundary(10)
                    && line.is_char_boundary(40)
                    && line.is_char_boundary(50)
                {
                    let factor = line[50..].split_whitespace().next().and_then(|f| f.parse().ok()).unwrap_or(1.0);
                    (line[..10].trim().to_owned(), line[40..50].trim().to_owned(), factor)
                } else {
                    let w: Vec<&str> = t.split_whitespace().collect();
                    (w[0].to_owned(), w.get(w.len().saturating_sub(2)).copied().unwrap_or("").to_owned(), 1.0)
                };
                chans.push((name.to_ascii_uppercase(), unit_factor(&unit), factor));
            }
            "data" => {
                let vals: Result<Vec<f64>, _> = t.split_whitespace().map(str::parse::<f64>).collect();
                let vals = vals.map_err(|e| fmt_err(path, ln, format!("expected numbers: {e}")))?;
                if vals.len() != chans.len() {
                    return Err(fmt_err(
                        path,
                        ln,
                        format!("{} values, expected {} (one per channel)", vals.len(), chans.len()),
                    ));
                }
                let mut s = Sample::default();
                let mut seg = 0usize;
                for ((name, (k, off), factor), v) in chans.iter().zip(vals) {
                    let v = v * factor;
                    if name == "SEGMENT" {
                        seg = v.max(0.0) as usize;
                        continue;
                    }
                    if let Some(c) = CHANNELS.iter().find(|c| c.name == name) {
                        (c.set)(&mut s, v * k + off);
                    }
                }
                rows.push((seg, s));
            }
            _ => {}
        }
    }
    if chans.is_empty() || rows.is_empty() {
        return Err(fmt_err(path, 0, "no **MEASURCHNLS or **MEASURDATA block"));
    }
    for need in ["FZW", "SLIPANGL"] {
        if !chans.iter().any(|c| c.0 == need) {
            return Err(fmt_err(path, 0, format!("channel {need} missing")));
        }
    }
    let nseg = rows.iter().map(|r| r.0).max().unwrap_or(0) + 1;
    let mut segments: Vec<Segment> = (0..nseg)
        .map(|i| {
            let (procedure, kind, section, sweep) = segs_meta.get(i).cloned().unwrap_or((
                Procedure::FreeRolling,
                DataKind::Sweep,
                "tydex".into(),
                format!("segment_{i}"),
            ));
            Segment { procedure, kind, section, sweep, samples: Vec::new(), cell: None, origin: None }
        })
        .collect();
    for (i, s) in rows {
        segments[i].samples.push(s);
    }
    segments.retain(|s| !s.samples.is_empty());
    if segs_meta.is_empty() {
        // A foreign file: classify by what was driven.
        for s in &mut segments {
            s.procedure = classify(&s.samples);
        }
    }
    Ok(Dataset { segments, fnomin_n: fnomin, sources: vec![path.display().to_string()] })
}

/// Reads a TYDEX file.
pub fn read_tydex(path: &Path) -> Result<Dataset, FitError> {
    let text = std::fs::read_to_string(path).map_err(|source| FitError::Io { path: path.to_owned(), source })?;
    parse_tydex(&text, path)
}

fn classify(samples: &[Sample]) -> Procedure {
    let kmax = samples.iter().map(|s| s.kappa.abs()).fold(0.0, f64::max);
    if kmax > 0.02 { Procedure::BrkDrv } else { Procedure::FreeRolling }
}

/// Sign convention of a TTC-style file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Convention {
    /// SAE (Calspan TTC's own): z down; FY, FZ, MY, MZ and slip angle flip to reach ISO-W.
    Sae,
    /// Already ISO-W.
    IsoW,
}

/// Parses Calspan TTC-style tab-separated data: an optional title line, a line of channel names
/// (`ET V N SA IA RL RE P FX FY FZ MX MY MZ SR TSTC …`), a line of units, then numbers. Sweeps
/// are split where the slip (angle or ratio) comes back to zero after reaching both signs.
pub fn parse_ttc(text: &str, path: &Path, convention: Convention) -> Result<Dataset, FitError> {
    let lines: Vec<(usize, &str)> =
        text.lines().enumerate().map(|(i, l)| (i + 1, l)).filter(|(_, l)| !l.trim().is_empty()).collect();
    let is_numeric = |l: &str| l.split_whitespace().all(|w| w.parse::<f64>().is_ok());
    let first_data =
        lines.iter().position(|(_, l)| is_numeric(l)).ok_or_else(|| fmt_err(path, 0, "no numeric rows"))?;
    if first_data < 1 {
        return Err(fmt_err(path, 1, "expected a line of channel names before the data"));
    }
    // The line two above the data holds the names when a units line sits between them.
    let units_line = lines[first_data - 1].1;
    let has_units = first_data >= 2 && !units_line.split_whitespace().any(|w| ["SA", "FZ", "FY"].contains(&w));
    let names_line = if has_units { lines[first_data - 2].1 } else { units_line };
    let names: Vec<String> =
        names_line.split('\t').flat_map(|c| c.split_whitespace()).map(|s| s.to_ascii_uppercase()).collect();
    let units: Vec<String> = if has_units {
        units_line.split('\t').flat_map(|c| c.split_whitespace()).map(str::to_owned).collect()
    } else {
        Vec::new()
    };
    let col = |n: &str| names.iter().position(|x| x == n);
    let need = |n: &str| col(n).ok_or_else(|| fmt_err(path, lines[first_data - 1].0, format!("channel {n} missing")));
    let (c_sa, c_fz, c_fy) = (need("SA")?, need("FZ")?, need("FY")?);
    let conv = |i: Option<usize>, default_unit: &str| -> (Option<usize>, (f64, f64)) {
        let u = i.and_then(|i| units.get(i)).map(String::as_str).unwrap_or(default_unit);
        (i, unit_factor(u))
    };
    let get = |vals: &[f64], c: (Option<usize>, (f64, f64)), default: f64| {
        c.0.and_then(|i| vals.get(i)).map(|v| v * c.1.0 + c.1.1).unwrap_or(default)
    };
    let c_et = conv(col("ET"), "s");
    let c_v = conv(col("V"), "kph");
    let c_n = conv(col("N"), "rpm");
    let c_ia = conv(col("IA"), "deg");
    let c_rl = conv(col("RL"), "cm");
    let c_p = conv(col("P"), "kPa");
    let c_fx = conv(col("FX"), "N");
    let c_mx = conv(col("MX"), "Nm");
    let c_my = conv(col("MY"), "Nm");
    let c_mz = conv(col("MZ"), "Nm");
    let c_sr = conv(col("SR").or(col("SL")), "-");
    let c_t = conv(col("TSTC"), "degC");
    let (c_sa, c_fz, c_fy) = (conv(Some(c_sa), "deg"), conv(Some(c_fz), "N"), conv(Some(c_fy), "N"));
    let sg = if convention == Convention::Sae { -1.0 } else { 1.0 };
    let mut samples = Vec::new();
    for (ln, l) in &lines[first_data..] {
        let vals: Result<Vec<f64>, _> = l.split_whitespace().map(str::parse::<f64>).collect();
        let vals = vals.map_err(|e| fmt_err(path, *ln, format!("expected numbers: {e}")))?;
        if vals.len() < names.len() {
            return Err(fmt_err(path, *ln, format!("{} values, expected {}", vals.len(), names.len())));
        }
        let sa_deg = get(&vals, c_sa, 0.0);
        samples.push(Sample {
            time_s: get(&vals, c_et, 0.0),
            fz_n: sg * get(&vals, c_fz, 0.0),
            kappa: get(&vals, c_sr, 0.0),
            alpha_rad: (sg * sa_deg).to_radians(),
            gamma_rad: get(&vals, c_ia, 0.0).to_radians(),
            p_pa: get(&vals, c_p, 0.0),
            vx_mps: get(&vals, c_v, 0.0),
            omega_radps: get(&vals, c_n, 0.0),
            fx_n: get(&vals, c_fx, 0.0),
            fy_n: sg * get(&vals, c_fy, 0.0),
            mx_nm: get(&vals, c_mx, 0.0),
            my_nm: sg * get(&vals, c_my, 0.0),
            mz_nm: sg * get(&vals, c_mz, 0.0),
            rl_m: get(&vals, c_rl, 0.0),
            temp_c: get(&vals, c_t, f64::NAN),
            temp_inner_c: f64::NAN,
            temp_outer_c: f64::NAN,
            road_temp_c: f64::NAN,
            dist_m: 0.0,
        });
    }
    // Split into sweeps.
    let mut segments = Vec::new();
    let mut cur: Vec<Sample> = Vec::new();
    let (mut pos, mut neg) = (false, false);
    let flush = |cur: &mut Vec<Sample>, segments: &mut Vec<Segment>| {
        if cur.len() >= 3 {
            let n = segments.len();
            let procedure = classify(cur);
            segments.push(Segment {
                procedure,
                kind: DataKind::Sweep,
                section: "ttc".into(),
                sweep: format!("ttc_sweep_{n}"),
                samples: std::mem::take(cur),
                cell: None,
                origin: None,
            });
        }
        cur.clear();
    };
    for s in samples {
        let slip = if s.kappa.abs() > 0.005 { s.kappa / 0.01 } else { s.alpha_rad.to_degrees() };
        pos |= slip > 1.0;
        neg |= slip < -1.0;
        cur.push(s);
        if pos && neg && slip.abs() < 0.1 {
            flush(&mut cur, &mut segments);
            pos = false;
            neg = false;
        }
    }
    flush(&mut cur, &mut segments);
    for seg in &mut segments {
        let t0 = seg.samples[0].time_s;
        let mut d = 0.0;
        let mut prev: Option<(f64, f64)> = None;
        for s in seg.samples.iter_mut() {
            if let Some((t, v)) = prev {
                d += 0.5 * (v + s.vx_mps) * (s.time_s - t);
            }
            prev = Some((s.time_s, s.vx_mps));
            s.time_s -= t0;
            s.dist_m = d;
        }
    }
    if segments.is_empty() {
        return Err(fmt_err(path, 0, "no data rows"));
    }
    Ok(Dataset { segments, fnomin_n: None, sources: vec![path.display().to_string()] })
}

/// Reads a TTC-style file.
pub fn read_ttc(path: &Path, convention: Convention) -> Result<Dataset, FitError> {
    let text = std::fs::read_to_string(path).map_err(|source| FitError::Io { path: path.to_owned(), source })?;
    parse_ttc(&text, path, convention)
}

/// Writes a dataset as TTC-style text (title, names, units, tab-separated rows) in the given
/// convention — for fixtures and for people who want the data in that form.
pub fn to_ttc(data: &Dataset, convention: Convention) -> String {
    let sg = if convention == Convention::Sae { -1.0 } else { 1.0 };
    let mut s = String::from("tyrerig TTC-style export\n");
    s.push_str("ET\tV\tN\tSA\tIA\tRL\tP\tFX\tFY\tFZ\tMX\tMY\tMZ\tSR\tTSTC\n");
    s.push_str("s\tkph\trpm\tdeg\tdeg\tcm\tkPa\tN\tN\tN\tNm\tNm\tNm\t-\tdegC\n");
    let mut t = 0.0;
    for seg in &data.segments {
        let t0 = seg.samples.first().map(|x| x.time_s).unwrap_or(0.0);
        for x in &seg.samples {
            let _ = writeln!(
                s,
                "{:.6}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.10e}\t{:.4}",
                t + x.time_s - t0,
                x.vx_mps * 3.6,
                x.omega_radps * 30.0 / std::f64::consts::PI,
                sg * x.alpha_rad.to_degrees(),
                x.gamma_rad.to_degrees(),
                x.rl_m * 100.0,
                x.p_pa / 1e3,
                x.fx_n,
                sg * x.fy_n,
                sg * x.fz_n,
                x.mx_nm,
                sg * x.my_nm,
                sg * x.mz_nm,
                x.kappa,
                if x.temp_c.is_finite() { x.temp_c } else { 0.0 },
            );
        }
        t += seg.samples.last().map(|x| x.time_s - t0).unwrap_or(0.0) + 1.0;
    }
    s
}
