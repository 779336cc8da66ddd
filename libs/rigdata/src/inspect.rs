//! What a reading found, for a person to check before fitting (`tyrerig inspect`,
//! `tyrerig import … --dry-run`) or for a machine (`--json`).

use std::fmt::Write as _;

use serde::Serialize;

use crate::error::Warning;
use crate::interpret::ChannelUse;
use crate::sweeps::Conditioning;

/// The reason a cold start's sweeps are conditioning, as reported.
const COLD_START: &str = Conditioning::ColdStart.name();

/// One sweep found.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct SweepRow {
    /// Segment name (`cornering P83kPa FZ1100N IA0 #2`).
    pub name: String,
    /// `cornering`, `drive/brake`, `combined`.
    pub kind: String,
    /// A conditioning (warm-up) sweep, not fitted.
    pub conditioning: bool,
    /// Why it is a conditioning sweep (`short reach`, `leading sweeps at a cell swept again
    /// later`).
    pub conditioning_reason: Option<String>,
    /// Conditioning by the run's plan (warm-up sweeps, a cold start), whatever its reach.
    pub conditioning_by_plan: bool,
    /// The tread temperature as it begins, °C, where the file has tread temperatures.
    pub tread_start_c: Option<f64>,
    /// First line (text files) or row (1-based, `.mat`).
    pub first_row: usize,
    /// Last line or row.
    pub last_row: usize,
    /// Rows.
    pub rows: usize,
    /// Median load, N (ISO-W, positive).
    pub fz_n: f64,
    /// Median pressure, kPa.
    pub p_kpa: f64,
    /// Median camber, deg.
    pub ia_deg: f64,
    /// Held slip angle, deg (slip-ratio sweeps).
    pub sa_deg: f64,
    /// Median road speed, kph.
    pub v_kph: f64,
    /// Largest |slip| reached: deg for cornering, slip ratio for slip-ratio sweeps; for camber
    /// sweeps the camber spanned, deg.
    pub reach: f64,
}

/// One test cell: the sweeps (not counting conditioning ones) run at it.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct CellRow {
    /// Cell name.
    pub label: String,
    /// Kind.
    pub kind: String,
    /// Pressure, kPa.
    pub p_kpa: f64,
    /// Load, N.
    pub fz_n: f64,
    /// Camber, deg.
    pub ia_deg: f64,
    /// Held slip angle, deg.
    pub sa_deg: f64,
    /// Speed, kph.
    pub v_kph: f64,
    /// Sweeps.
    pub sweeps: usize,
}

/// What was found in one file.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct FileReport {
    /// File.
    pub file: String,
    /// Format.
    pub format: String,
    /// `.mat` layout.
    pub layout: Option<String>,
    /// Title line.
    pub title: Option<String>,
    /// Tyre.
    pub tire_id: Option<String>,
    /// Test id as written.
    pub test_id: Option<String>,
    /// Test kind the file states.
    pub test_kind_stated: Option<String>,
    /// Test kind found in the data (`cornering`, `drive/brake/combined`, `mixed`, `none`).
    pub test_kind_found: String,
    /// Sign convention read in.
    pub convention: String,
    /// How it was decided.
    pub convention_basis: String,
    /// Slip-ratio channel.
    pub slip_ratio_from: String,
    /// Rows in the file.
    pub rows: usize,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Channels.
    pub channels: Vec<ChannelUse>,
    /// Cells (conditioning sweeps not counted).
    pub cells: Vec<CellRow>,
    /// Sweeps, conditioning ones included.
    pub sweeps: Vec<SweepRow>,
    /// Conditioning sweeps.
    pub conditioning_sweeps: usize,
    /// Rows in (fitted) sweeps.
    pub rows_in_sweeps: usize,
    /// Rows in conditioning sweeps.
    pub rows_in_conditioning: usize,
    /// Rows excluded per reason.
    pub excluded: Vec<(String, usize)>,
    /// Lines of a text file that did not become rows, per reason (see the warnings for where).
    pub lines_not_read: Vec<(String, usize)>,
    /// Warnings.
    pub warnings: Vec<Warning>,
}

/// The reading of one or several files.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Inspection {
    /// Per file.
    pub files: Vec<FileReport>,
}

impl Inspection {
    /// Camber sweeps found (conditioning ones not counted), over all files.
    pub fn camber_sweeps(&self) -> usize {
        self.files.iter().flat_map(|f| &f.sweeps).filter(|s| !s.conditioning && s.kind == "camber").count()
    }

    /// Sweeps found (conditioning ones not counted), per kind (cornering, drive/brake,
    /// combined), over all files; camber sweeps in [`Inspection::camber_sweeps`].
    pub fn sweep_counts(&self) -> (usize, usize, usize) {
        let mut c = (0, 0, 0);
        for s in self.files.iter().flat_map(|f| &f.sweeps).filter(|s| !s.conditioning) {
            match s.kind.as_str() {
                "cornering" => c.0 += 1,
                "drive/brake" => c.1 += 1,
                "combined" => c.2 += 1,
                _ => {}
            }
        }
        c
    }

    /// The report as text.
    pub fn to_text(&self, verbose: bool) -> String {
        let mut s = String::new();
        for f in &self.files {
            f.write_text(&mut s, verbose);
        }
        if self.files.len() > 1 {
            let (c, d, k) = self.sweep_counts();
            let _ = writeln!(
                s,
                "\n{} files: {c} cornering, {d} drive/brake, {k} combined, {} camber sweeps",
                self.files.len(),
                self.camber_sweeps()
            );
        }
        s
    }
}

impl FileReport {
    fn write_text(&self, s: &mut String, verbose: bool) {
        let _ = writeln!(s, "== {}", self.file);
        let opt = |o: &Option<String>| o.clone().unwrap_or_else(|| "-".into());
        let _ = writeln!(
            s,
            "format      {}{}",
            self.format,
            self.layout.as_ref().map(|l| format!(", channels as {l}")).unwrap_or_default()
        );
        if let Some(t) = &self.title {
            let _ = writeln!(s, "title       {t}");
        }
        let _ = writeln!(s, "tyre        {}", opt(&self.tire_id));
        let stated = match (&self.test_id, &self.test_kind_stated) {
            (Some(id), Some(k)) => format!("`{id}` ({k})"),
            (Some(id), None) => format!("`{id}` (kind not recognised)"),
            (None, Some(k)) => format!("{k} (from the title)"),
            (None, None) => "-".into(),
        };
        let _ = writeln!(s, "test        stated: {stated}; found in the data: {}", self.test_kind_found);
        let _ = writeln!(s, "axes        {} ({}), converted to ISO-W", self.convention, self.convention_basis);
        let _ = writeln!(s, "slip ratio  {}", self.slip_ratio_from);
        let _ = writeln!(s, "rows        {} at {:.1} Hz", self.rows, self.sample_rate_hz);
        if !self.channels.is_empty() {
            let _ = writeln!(s, "\nchannels    {:<10} {:<10} {:<10} becomes", "name", "unit", "read as");
            for c in &self.channels {
                let unit = if c.unit_written.is_empty() { "(none)" } else { c.unit_written.as_str() };
                let _ = writeln!(s, "            {:<10} {:<10} {:<10} {}", c.name, unit, c.unit_read, c.used_as);
            }
        }
        if !self.cells.is_empty() {
            let _ = writeln!(
                s,
                "\nsweeps per cell ({} sweeps, {} conditioning)",
                self.sweeps.len() - self.conditioning_sweeps,
                self.conditioning_sweeps
            );
            let _ = writeln!(
                s,
                "  {:<12} {:>7} {:>7} {:>6} {:>6} {:>6} {:>6}",
                "kind", "P kPa", "FZ N", "IA deg", "SA deg", "V kph", "sweeps"
            );
            for c in &self.cells {
                // Rounded first so a -0.01° camber prints as 0.0, not -0.0.
                let r1 = |x: f64| (x * 10.0).round() / 10.0 + 0.0;
                let _ = writeln!(
                    s,
                    "  {:<12} {:>7.1} {:>7.0} {:>6.1} {:>6.1} {:>6.1} {:>6}",
                    c.kind,
                    r1(c.p_kpa),
                    c.fz_n,
                    r1(c.ia_deg),
                    r1(c.sa_deg),
                    r1(c.v_kph),
                    c.sweeps
                );
            }
        }
        if verbose && !self.sweeps.is_empty() {
            let _ = writeln!(s, "\nsweeps");
            for w in &self.sweeps {
                let why = w.conditioning_reason.as_ref().map(|r| format!("  ({r})")).unwrap_or_default();
                let _ =
                    writeln!(s, "  {:<48} rows {:>6}–{:<6} reach {:.3}{why}", w.name, w.first_row, w.last_row, w.reach);
            }
        }
        let leading = self
            .sweeps
            .iter()
            .filter(|w| w.conditioning_reason.as_deref().is_some_and(|r| r.starts_with("leading")))
            .count();
        if leading > 0 {
            let _ = writeln!(
                s,
                "\nconditioning {leading} sweeps open the run at a cell swept again later: warm-up, not fitted"
            );
        }
        let cold: Vec<f64> = self
            .sweeps
            .iter()
            .filter(|w| w.conditioning_reason.as_deref() == Some(COLD_START))
            .filter_map(|w| w.tread_start_c)
            .collect();
        if let (Some(first), Some(last)) = (cold.first(), cold.last()) {
            let settled = self.sweeps.iter().filter(|w| !w.conditioning).find_map(|w| w.tread_start_c);
            let (n, temps) = match cold.len() {
                1 => ("1 sweep".to_owned(), format!("at {first:.0} °C")),
                n => (format!("{n} sweeps"), format!("{first:.0} → {last:.0} °C at their starts")),
            };
            let _ = writeln!(
                s,
                "\nconditioning {n} begun before the tread temperature settled ({temps}{}), swept again later: cold \
                 tyre, not fitted",
                settled.map(|t| format!("; the first sweep fitted starts at {t:.0} °C")).unwrap_or_default()
            );
        }
        let excluded: usize = self.excluded.iter().map(|e| e.1).sum();
        let _ = writeln!(
            s,
            "\nrows        {} = {} in sweeps + {} in conditioning sweeps + {} excluded{}",
            self.rows,
            self.rows_in_sweeps,
            self.rows_in_conditioning,
            excluded,
            if self.rows_in_sweeps + self.rows_in_conditioning + excluded == self.rows {
                String::new()
            } else {
                "  (DO NOT ADD UP: a reader fault, please report)".to_owned()
            }
        );
        for (why, n) in &self.excluded {
            let _ = writeln!(s, "  {n:>8}  {why}");
        }
        if !self.lines_not_read.is_empty() {
            let _ = writeln!(s, "lines not read as rows (see the warnings for where)");
            for (why, n) in &self.lines_not_read {
                let _ = writeln!(s, "  {n:>8}  {why}");
            }
        }
        if !self.warnings.is_empty() {
            let _ = writeln!(s, "\nwarnings");
            for w in &self.warnings {
                let _ = writeln!(s, "  {w}");
            }
        }
        let _ = writeln!(s);
    }
}
