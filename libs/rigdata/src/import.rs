//! Files and folders → the fitter's [`Dataset`] plus an [`Inspection`] of what was found.
//!
//! One path does it all: [`read_path`] takes a TTC `.dat`, a `.mat`, a TYDEX `.tdx` (tyrerig's
//! own or another tool's) or a folder of them, reads each file into a [`ChannelTable`],
//! interprets its channels ([`crate::interpret`]), finds its sweeps ([`crate::sweeps`]) and
//! turns each sweep into a [`Segment`] with its [`Cell`], kind and origin.

use std::path::{Path, PathBuf};

use mffit::{Cell, DataKind, Dataset, Origin, Procedure, Sample, Segment, SweepKind};

use crate::conditioning::{same_cell, typical_reach};
use crate::error::{Place, ReadError, Warning, Warnings};
use crate::inspect::{CellRow, FileReport, Inspection, SweepRow};
use crate::interpret::{Convention, Family, KappaSource, interpret};
use crate::sweeps::{Conditioning, FoundSweep, SweepOptions, Swept, TestKind, find_sweeps};

/// The segment section (and inspection kind) of camber sweeps; they are free-rolling data the
/// fitter takes as cornering data, told apart from slip-angle sweeps by this name.
pub const CAMBER_SECTION: &str = "camber";
use crate::table::ChannelTable;
use crate::{dat, mat, tydex};

/// Options of the readers.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Sign convention (default: from the data).
    pub convention: Convention,
    /// Segmentation thresholds.
    pub sweeps: SweepOptions,
}

/// What [`read_path`] returns.
#[derive(Debug, Clone)]
pub struct Import {
    /// The data for the fitter.
    pub dataset: Dataset,
    /// What was read, file by file.
    pub inspection: Inspection,
}

/// File formats the readers know.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileFormat {
    /// TTC ASCII.
    Dat,
    /// MATLAB.
    Mat,
    /// TYDEX.
    Tdx,
}

impl FileFormat {
    /// From the extension (`.dat`, `.txt`, `.asc`; `.mat`; `.tdx`, `.tydex`).
    pub fn of(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
        match ext.as_str() {
            "dat" | "txt" | "asc" | "tsv" => Some(FileFormat::Dat),
            "mat" => Some(FileFormat::Mat),
            "tdx" | "tydex" => Some(FileFormat::Tdx),
            _ => None,
        }
    }

    /// From the first bytes, for files whose extension says nothing.
    pub fn sniff(bytes: &[u8]) -> Self {
        if bytes.starts_with(b"MATLAB") || bytes.get(126..128).is_some_and(|e| e == b"IM" || e == b"MI") {
            FileFormat::Mat
        } else if String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]).contains("**MEASURCHNLS") {
            FileFormat::Tdx
        } else {
            FileFormat::Dat
        }
    }
}

/// The files of a folder the readers know (sorted by name), or the path itself.
pub fn files_of(path: &Path) -> Result<Vec<PathBuf>, ReadError> {
    if !path.is_dir() {
        return Ok(vec![path.to_owned()]);
    }
    let io = |source| ReadError::Io { path: path.to_owned(), source };
    let mut files: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && FileFormat::of(p).is_some())
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(ReadError::at(Place::file(&path.display().to_string()), "folder holds no .dat, .mat or .tdx file"));
    }
    Ok(files)
}

/// Reads a file or every known file of a folder.
pub fn read_path(path: &Path, opt: &ReadOptions) -> Result<Import, ReadError> {
    let mut dataset = Dataset::default();
    let mut inspection = Inspection::default();
    for f in files_of(path)? {
        let (d, report) = read_file_unlabelled(&f, opt)?;
        dataset.extend(d);
        inspection.files.push(report);
    }
    // A test is often a folder of one-sweep files: conditioning and repeats are judged across it.
    label(&mut dataset, &mut inspection, opt.sweeps.conditioning_fraction);
    Ok(Import { dataset, inspection })
}

/// Reads one file.
pub fn read_file(path: &Path, opt: &ReadOptions) -> Result<(Dataset, FileReport), ReadError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_owned(), source })?;
    let format = FileFormat::of(path).unwrap_or_else(|| FileFormat::sniff(&bytes));
    read_bytes(&bytes, &file, format, opt)
}

fn read_file_unlabelled(path: &Path, opt: &ReadOptions) -> Result<(Dataset, FileReport), ReadError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_owned(), source })?;
    let format = FileFormat::of(path).unwrap_or_else(|| FileFormat::sniff(&bytes));
    read_unlabelled(&bytes, &file, format, opt)
}

/// Judges conditioning sweeps across everything read (a sweep reaching less than `fraction` of
/// its family's typical reach — the 75th percentile of the slip-angle sweeps, or of the
/// slip-ratio sweeps), numbers repeated sweeps per cell, names the segments, and fills each
/// file's table of sweeps per cell. Segments without a cell (tyrerig's own TYDEX) are left as
/// they are.
fn label(d: &mut Dataset, ins: &mut Inspection, fraction: f64) {
    // Rows and segments are in the same order, file by file.
    let leading: Vec<bool> = ins.files.iter().flat_map(|f| &f.sweeps).map(|r| r.conditioning_by_plan).collect();
    let camber = |s: &Segment| s.section == CAMBER_SECTION;
    for sa in [true, false] {
        let fam = |s: &Segment| !camber(s) && s.cell.is_some_and(|c| (c.kind == SweepKind::Cornering) == sa);
        let reach: Vec<f64> =
            d.segments.iter().filter(|s| fam(s)).filter_map(|s| s.cell.map(|c| c.slip_reach)).collect();
        let Some(typical) = typical_reach(reach) else { continue };
        for (k, s) in d.segments.iter_mut().enumerate().filter(|(_, s)| fam(s)) {
            let short = s.cell.is_some_and(|c| c.slip_reach < fraction * typical);
            let lead = leading.get(k).copied().unwrap_or(false);
            s.kind = if short || lead { DataKind::WarmUp } else { DataKind::Sweep };
        }
    }
    let mut segs_reason = d.segments.iter();
    for row in ins.files.iter_mut().flat_map(|f| f.sweeps.iter_mut()) {
        let Some(seg) = segs_reason.next() else { break };
        if seg.cell.is_none() {
            continue;
        }
        row.conditioning_reason = match (seg.kind == DataKind::WarmUp, row.conditioning_reason.take()) {
            (false, _) => None,
            (true, Some(r)) => Some(r),
            (true, None) => Some(Conditioning::ShortReach.name().to_owned()),
        };
    }
    let speeds: Vec<f64> = d.segments.iter().filter_map(|s| s.cell.map(|c| c.vx_mps)).collect();
    let speeds_differ = speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - speeds.iter().copied().fold(f64::INFINITY, f64::min)
        > 1.0;
    let mut groups: Vec<(Cell, bool, bool, usize)> = Vec::new();
    let mut segs = d.segments.iter_mut();
    for f in &mut ins.files {
        let mut cells: Vec<(Cell, bool, usize)> = Vec::new();
        for row in &mut f.sweeps {
            let Some(seg) = segs.next() else { break };
            let Some(cell) = seg.cell else { continue };
            let cond = seg.kind == DataKind::WarmUp;
            let cam = seg.section == CAMBER_SECTION;
            let k = match groups.iter_mut().find(|(c, cd, cm, _)| *cd == cond && *cm == cam && same_cell(c, &cell)) {
                Some(g) => {
                    g.3 += 1;
                    (g.0, g.3)
                }
                None => {
                    groups.push((cell, cond, cam, 1));
                    (cell, 1)
                }
            };
            let label = if cam { camber_label(&k.0, speeds_differ) } else { cell_label(&k.0, speeds_differ) };
            seg.sweep =
                if cond { format!("warmup (conditioning) {label} #{}", k.1) } else { format!("{label} #{}", k.1) };
            row.name = seg.sweep.clone();
            row.conditioning = cond;
            if !cond {
                match cells.iter_mut().find(|(c, cm, _)| *cm == cam && same_cell(c, &k.0)) {
                    Some(c) => c.2 += 1,
                    None => cells.push((k.0, cam, 1)),
                }
            }
        }
        {
            f.cells = cells
                .iter()
                .map(|(c, cam, k)| CellRow {
                    label: if *cam { camber_label(c, speeds_differ) } else { cell_label(c, speeds_differ) },
                    kind: if *cam { CAMBER_SECTION.into() } else { c.kind.name().into() },
                    p_kpa: c.p_pa / 1e3,
                    fz_n: c.fz_n,
                    ia_deg: c.gamma_rad.to_degrees(),
                    sa_deg: c.alpha_rad.to_degrees(),
                    v_kph: c.vx_mps * 3.6,
                    sweeps: *k,
                })
                .collect();
        }
        f.conditioning_sweeps = f.sweeps.iter().filter(|r| r.conditioning).count();
        f.rows_in_sweeps = f.sweeps.iter().filter(|r| !r.conditioning).map(|r| r.rows).sum();
        f.rows_in_conditioning = f.sweeps.iter().filter(|r| r.conditioning).map(|r| r.rows).sum();
    }
}

/// Reads the bytes of a file of a known format; `file` names it in messages.
pub fn read_bytes(
    bytes: &[u8],
    file: &str,
    format: FileFormat,
    opt: &ReadOptions,
) -> Result<(Dataset, FileReport), ReadError> {
    let (mut d, report) = read_unlabelled(bytes, file, format, opt)?;
    let mut inspection = Inspection { files: vec![report] };
    label(&mut d, &mut inspection, opt.sweeps.conditioning_fraction);
    Ok((d, inspection.files.remove(0)))
}

fn read_unlabelled(
    bytes: &[u8],
    file: &str,
    format: FileFormat,
    opt: &ReadOptions,
) -> Result<(Dataset, FileReport), ReadError> {
    match format {
        FileFormat::Dat => {
            let t = dat::parse_dat(bytes, file)?;
            let lines = t.lines;
            let not_read = t.lines_not_read;
            let (d, mut report) = from_table(
                &t.table,
                "TTC ASCII (.dat)",
                None,
                Family::Ttc,
                t.warnings,
                &|r| lines.get(r).copied().unwrap_or(r + 1),
                opt,
                None,
            )?;
            report.lines_not_read = not_read;
            Ok((d, report))
        }
        FileFormat::Mat => {
            let m = mat::parse_mat(bytes, file)?;
            from_table(&m.table, &m.format, Some(m.layout), Family::Ttc, m.warnings, &|r| r + 1, opt, None)
        }
        FileFormat::Tdx => {
            let tdx = tydex::parse_tdx(&String::from_utf8_lossy(bytes), file)?;
            if tdx.is_own() {
                let (d, mut w) = tydex::read_own(&tdx, file)?;
                let mut warnings = tdx.warnings.clone();
                warnings.append(&mut w);
                let report = own_report(&d, file, warnings);
                return Ok((d, report));
            }
            let (table, mut w) = tdx.to_table(file);
            let mut warnings = tdx.warnings.clone();
            warnings.append(&mut w);
            let lines: Vec<usize> = tdx.rows.iter().map(|(l, _)| *l).collect();
            let fnomin = tdx.constant_si(&["FNOMIN", "FZW", "NOMLOAD", "FZNOMIN"]).map(|x| x.0);
            from_table(
                &table,
                "TYDEX (.tdx)",
                None,
                Family::Tydex,
                warnings,
                &|r| lines.get(r).copied().unwrap_or(r + 1),
                opt,
                fnomin,
            )
        }
    }
}

/// A report for our own TYDEX file (segments as exported, no sweep finding).
fn own_report(d: &Dataset, file: &str, warnings: Vec<Warning>) -> FileReport {
    FileReport {
        file: file.to_owned(),
        format: "TYDEX (.tdx), tyrerig export: segments as exported".into(),
        rows: d.len(),
        rows_in_sweeps: d.len(),
        convention: "ISO-W".into(),
        convention_basis: "tyrerig export".into(),
        sweeps: d
            .segments
            .iter()
            .map(|s| SweepRow {
                name: s.sweep.clone(),
                kind: format!("{:?} {}", s.kind, s.procedure.name()),
                conditioning: s.kind == DataKind::WarmUp,
                rows: s.samples.len(),
                ..SweepRow::default()
            })
            .collect(),
        warnings,
        ..FileReport::default()
    }
}

fn deg(x: f64) -> String {
    let d = (x.to_degrees() * 10.0).round() / 10.0;
    let d = if d == 0.0 { 0.0 } else { d };
    format!("{d}")
}

/// The name of a cell a person reads: `cornering P83kPa FZ1100N IA0`, `combined … SA3`.
pub fn cell_label(c: &Cell, with_speed: bool) -> String {
    let mut s = format!(
        "{} P{:.0}kPa FZ{:.0}N IA{}",
        c.kind.name(),
        c.p_pa / 1e3,
        (c.fz_n / 10.0).round() * 10.0,
        deg(c.gamma_rad)
    );
    if c.kind == SweepKind::Combined {
        s.push_str(&format!(" SA{}", deg(c.alpha_rad)));
    }
    if with_speed && c.vx_mps.is_finite() {
        s.push_str(&format!(" V{:.0}kph", c.vx_mps * 3.6));
    }
    s
}

/// The name of a camber sweep's cell: `camber P83kPa FZ1100N SA1.8`.
pub fn camber_label(c: &Cell, with_speed: bool) -> String {
    let mut s = format!(
        "{CAMBER_SECTION} P{:.0}kPa FZ{:.0}N SA{}",
        c.p_pa / 1e3,
        (c.fz_n / 10.0).round() * 10.0,
        deg(c.alpha_rad)
    );
    if with_speed && c.vx_mps.is_finite() {
        s.push_str(&format!(" V{:.0}kph", c.vx_mps * 3.6));
    }
    s
}

#[allow(clippy::too_many_arguments)]
fn from_table(
    table: &ChannelTable,
    format: &str,
    layout: Option<String>,
    family: Family,
    mut warnings: Vec<Warning>,
    line_of: &dyn Fn(usize) -> usize,
    opt: &ReadOptions,
    fnomin: Option<f64>,
) -> Result<(Dataset, FileReport), ReadError> {
    let file = table.source.clone();
    let mut warn = Warnings::default();
    let it = interpret(table, family, opt.convention, &mut warn)?;
    let stated = table.test_id.as_deref().or(table.title.as_deref()).and_then(TestKind::from_id);
    let seg = find_sweeps(&it.signals, it.kappa_source, stated, &opt.sweeps);
    let s = &it.signals;
    // Cross-check with what the file says its test is.
    let n_sa = seg.sweeps.iter().filter(|w| w.cell.kind == SweepKind::Cornering).count();
    let n_k = seg.sweeps.len() - n_sa;
    let found = match (n_sa > 0, n_k > 0) {
        (true, false) => Some(TestKind::Cornering),
        (false, true) => Some(TestKind::DriveBrake),
        _ => None,
    };
    if let Some(st) = stated {
        let id = table.test_id.as_deref().or(table.title.as_deref()).unwrap_or_default();
        if st == TestKind::Cornering && n_k > 0 {
            warn.push(
                "test kind",
                Place::file(&file),
                format!("the file says `{id}` (cornering) but {n_k} slip-ratio sweeps were found"),
            );
        }
        if st == TestKind::DriveBrake && n_sa > 0 {
            warn.push(
                "test kind",
                Place::file(&file),
                format!("the file says `{id}` (drive/brake/combined) but {n_sa} slip-angle sweeps were found"),
            );
        }
    }
    if seg.kappa_ignored {
        warn.push("SR ignored", Place::file(&file).channel("SR"), "cornering test with only SR: the wheel rolls free, so no slip-ratio sweeps were looked for and the slip ratio is 0");
    }
    if seg.sweeps.is_empty() {
        warn.push("no sweeps", Place::file(&file), "no sweep found (see the excluded rows)");
    }
    let mut segments = Vec::with_capacity(seg.sweeps.len());
    let mut rows_sw = Vec::with_capacity(seg.sweeps.len());
    for w in &seg.sweeps {
        let camber = w.swept == Swept::Camber;
        rows_sw.push(SweepRow {
            name: String::new(),
            kind: if camber { CAMBER_SECTION.into() } else { w.cell.kind.name().into() },
            conditioning: w.conditioning.is_some(),
            conditioning_reason: w.conditioning.map(|c| c.name().to_owned()),
            conditioning_by_plan: w.conditioning.is_some_and(Conditioning::by_plan),
            tread_start_c: Some(w.tread_start_c).filter(|t| t.is_finite()),
            first_row: line_of(w.first),
            last_row: line_of(w.last),
            rows: w.last + 1 - w.first,
            fz_n: w.cell.fz_n,
            p_kpa: w.cell.p_pa / 1e3,
            ia_deg: w.cell.gamma_rad.to_degrees(),
            sa_deg: w.cell.alpha_rad.to_degrees(),
            v_kph: w.cell.vx_mps * 3.6,
            reach: match w.swept {
                Swept::SlipAngle => w.cell.slip_reach.to_degrees(),
                Swept::Camber => w.camber_span_deg,
                Swept::SlipRatio => w.cell.slip_reach,
            },
        });
        segments.push(Segment {
            procedure: if w.cell.kind == SweepKind::Cornering { Procedure::FreeRolling } else { Procedure::BrkDrv },
            kind: if w.conditioning.is_some() { DataKind::WarmUp } else { DataKind::Sweep },
            section: if camber { CAMBER_SECTION.to_owned() } else { w.cell.kind.name().to_owned() },
            sweep: String::new(),
            samples: samples_of(s, w, it.kappa_source),
            cell: Some(w.cell),
            origin: Some(Origin { file: file.clone(), first_row: line_of(w.first), last_row: line_of(w.last) }),
        });
    }
    warnings.extend(warn.finish(&file));
    let n = table.rows();
    let report = FileReport {
        file: file.clone(),
        format: format.to_owned(),
        layout,
        title: table.title.clone(),
        tire_id: table.tire_id.clone(),
        test_id: table.test_id.clone(),
        test_kind_stated: stated.map(|k| k.name().to_owned()),
        test_kind_found: found
            .map(|k| k.name().to_owned())
            .unwrap_or_else(|| if seg.sweeps.is_empty() { "none".into() } else { "mixed".into() }),
        convention: it.convention.name().into(),
        convention_basis: it.convention_basis.clone(),
        slip_ratio_from: match it.kappa_source {
            KappaSource::LoadedRadius => format!("{} (loaded radius)", it.kappa_channel.clone().unwrap_or_default()),
            KappaSource::EffectiveRadius => format!(
                "{} (effective radius; no SL in the file), zeroed in {} free-rolling rows",
                it.kappa_channel.clone().unwrap_or_default(),
                seg.sr_zeroed
            ),
            KappaSource::Absent => "none (taken as 0)".into(),
        },
        rows: n,
        sample_rate_hz: 1.0 / it.period_s,
        channels: it.channels.clone(),
        cells: Vec::new(),
        sweeps: rows_sw,
        conditioning_sweeps: 0,
        rows_in_sweeps: 0,
        rows_in_conditioning: 0,
        excluded: seg.excluded.iter().map(|(e, c)| (e.name().to_owned(), *c)).collect(),
        lines_not_read: Vec::new(),
        warnings,
    };
    let dataset = Dataset { segments, fnomin_n: fnomin, sources: vec![file] };
    Ok((dataset, report))
}

/// The fitter's samples of one sweep: time from the sweep's start, distance rolled.
fn samples_of(s: &crate::interpret::Signals, w: &FoundSweep, source: KappaSource) -> Vec<Sample> {
    let t0 = s.time_s[w.first];
    let zero_kappa = w.cell.kind == SweepKind::Cornering && source == KappaSource::EffectiveRadius;
    let mut out = Vec::with_capacity(w.last + 1 - w.first);
    let mut dist = 0.0;
    for r in w.first..=w.last {
        let vx = s.v_mps.as_ref().map(|v| v[r]).unwrap_or(f64::NAN);
        if r > w.first && vx.is_finite() {
            let prev = s.v_mps.as_ref().map(|v| v[r - 1]).unwrap_or(vx);
            dist += 0.5 * (vx + prev) * (s.time_s[r] - s.time_s[r - 1]).max(0.0);
        }
        out.push(Sample {
            time_s: s.time_s[r] - t0,
            fz_n: s.fz_n[r],
            kappa: if zero_kappa { 0.0 } else { s.kappa[r] },
            alpha_rad: s.alpha_rad[r],
            gamma_rad: s.gamma_rad[r],
            p_pa: s.p_pa[r],
            vx_mps: if vx.is_finite() { vx } else { 0.0 },
            omega_radps: s.omega_radps[r],
            fx_n: s.fx_n[r],
            fy_n: s.fy_n[r],
            mx_nm: s.mx_nm[r],
            my_nm: s.my_nm[r],
            mz_nm: s.mz_nm[r],
            rl_m: s.rl_m[r],
            temp_c: s.temp_centre_c[r],
            temp_inner_c: s.temp_inner_c[r],
            temp_outer_c: s.temp_outer_c[r],
            road_temp_c: s.road_temp_c[r],
            dist_m: dist,
        });
    }
    out
}
