//! Calspan TIRF / FSAE TTC ASCII run files (`.dat`): a title line, a line of channel names, a
//! line of units, then one tab-separated row per sample.
//!
//! Real files are not always clean, and each oddity is met with a warning (or, where nothing
//! sensible can be done, an error) naming file, line and channel: Windows line ends, trailing
//! tabs, blank lines, `NaN` values, a last line cut short by a crashed logger, rows with more or
//! fewer values than there are channels, a missing title or units line, duplicate names.

use std::path::Path;

use crate::channels::role_of;
use crate::error::{Place, ReadError, Warning, Warnings};
use crate::table::ChannelTable;

/// A text file read into a table, with the file line each row came from.
#[derive(Debug, Clone)]
pub struct TextTable {
    /// The channels, units as written.
    pub table: ChannelTable,
    /// 1-based line number of each row.
    pub lines: Vec<usize>,
    /// What was odd about the file.
    pub warnings: Vec<Warning>,
    /// Lines after the units that did not become rows, per reason (blank lines not counted):
    /// `inspect` accounts for them besides the rows.
    pub lines_not_read: Vec<(String, usize)>,
}

/// Fields of a line: tab-separated when the line has tabs (the TTC layout), else
/// semicolon- or comma-separated (a run re-saved as CSV from a spreadsheet; a semicolon file's
/// values may have decimal commas), else separated by runs of spaces. Trailing empty fields (trailing tabs) are dropped.
fn fields(line: &str) -> (Vec<&str>, bool) {
    let mut f: Vec<&str> = if let Some(sep) = ['\t', ';', ','].into_iter().find(|c| line.contains(*c)) {
        line.split(sep).map(str::trim).collect()
    } else {
        line.split_whitespace().collect()
    };
    let mut trailing = false;
    while f.last().is_some_and(|s| s.is_empty()) {
        f.pop();
        trailing = true;
    }
    (f, trailing)
}

fn is_number(s: &str) -> bool {
    s.parse::<f64>().is_ok()
}

/// How many of a line's fields are channel names the readers know.
fn known_names(f: &[&str]) -> usize {
    f.iter().filter(|s| role_of(name_and_unit(s).0).is_some()).count()
}

/// A channel header with its unit in brackets, as re-exported files write them (`FZ [N]`,
/// `SA (deg)`, `ET[s]`): the name and the unit; a plain name has no unit.
fn name_and_unit(field: &str) -> (&str, Option<&str>) {
    let f = field.trim();
    for (open, close) in [('[', ']'), ('(', ')')] {
        if let Some(body) = f.strip_suffix(close)
            && let Some(at) = body.rfind(open)
            && at > 0
        {
            return (body[..at].trim(), Some(body[at + 1..].trim()));
        }
    }
    (f, None)
}

/// A names line split at spaces has `FZ [N]` as two tokens: a token that is only a bracketed
/// unit belongs to the name before it.
fn rejoin_bracketed(f: Vec<&str>, line: &str) -> Vec<String> {
    let spaced = !line.contains(['\t', ';', ',']);
    let mut out: Vec<String> = Vec::with_capacity(f.len());
    for t in f {
        let bracket_only = (t.starts_with('[') && t.ends_with(']')) || (t.starts_with('(') && t.ends_with(')'));
        match out.last_mut() {
            Some(last) if spaced && bracket_only => last.push_str(t),
            _ => out.push(t.to_owned()),
        }
    }
    out
}

/// Lines of the file (without their `\n` / `\r\n`), numbered from 1. A file with only `\r`
/// line ends (old Mac) is split on `\r`.
fn numbered_lines(text: &str) -> Vec<(usize, &str)> {
    let sep = if !text.contains('\n') && text.contains('\r') { '\r' } else { '\n' };
    text.split(sep).enumerate().map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l))).collect()
}

/// Reads a TTC `.dat` file.
pub fn read_dat(path: &Path) -> Result<TextTable, ReadError> {
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_owned(), source })?;
    parse_dat(&bytes, &path.display().to_string())
}

/// Parses the bytes of a TTC `.dat` file; `file` names it in messages.
pub fn parse_dat(bytes: &[u8], file: &str) -> Result<TextTable, ReadError> {
    let mut warn = Warnings::default();
    let text = String::from_utf8_lossy(bytes);
    if matches!(text, std::borrow::Cow::Owned(_)) {
        warn.push(
            "encoding",
            Place::file(file),
            "not valid UTF-8: undecodable bytes replaced (check the title and units)",
        );
    }
    let lines = numbered_lines(&text);
    // The names line: the first of the first few non-blank lines that holds at least two
    // channel names and no number. Lines above it are the title.
    let head: Vec<usize> =
        lines.iter().enumerate().filter(|(_, (_, l))| !l.trim().is_empty()).map(|(i, _)| i).take(10).collect();
    let names_at = head
        .iter()
        .copied()
        .find(|&i| {
            let (f, _) = fields(lines[i].1);
            let f = rejoin_bracketed(f, lines[i].1);
            let f: Vec<&str> = f.iter().map(String::as_str).collect();
            known_names(&f) >= 2 && !f.iter().any(|s| is_number(s))
        })
        .ok_or_else(|| {
            ReadError::at(
                Place::file(file),
                "no line of channel names in the first lines (expected e.g. `ET  V  N  SA  IA  RL  RE  P  FX  FY  FZ …`)",
            )
        })?;
    let title_lines: Vec<&str> = lines[..names_at].iter().map(|(_, l)| l.trim()).filter(|l| !l.is_empty()).collect();
    let title = if title_lines.is_empty() {
        warn.push("no title", Place::line(file, 1), "no title line: the file starts with the channel names");
        None
    } else {
        Some(title_lines.join(" "))
    };
    let names_line = lines[names_at].0;
    let (raw_names, _) = fields(lines[names_at].1);
    let raw_names = rejoin_bracketed(raw_names, lines[names_at].1);
    let header_units: Vec<Option<String>> = raw_names.iter().map(|n| name_and_unit(n).1.map(str::to_owned)).collect();
    let raw_names: Vec<&str> = raw_names.iter().map(|n| name_and_unit(n).0).collect();
    let mut names: Vec<String> = Vec::with_capacity(raw_names.len());
    for (i, n) in raw_names.iter().enumerate() {
        let mut name = if n.is_empty() {
            warn.push(
                "empty name",
                Place::line(file, names_line),
                format!("column {} has no name: called COL{}", i + 1, i + 1),
            );
            format!("COL{}", i + 1)
        } else {
            (*n).to_owned()
        };
        if names.iter().any(|x| x.eq_ignore_ascii_case(&name)) {
            let renamed = format!("{name}_{}", i + 1);
            warn.push(
                "duplicate name",
                Place::line(file, names_line).channel(&name),
                format!("channel name repeated in column {}: the second is called {renamed} and not used", i + 1),
            );
            name = renamed;
        }
        names.push(name);
    }
    // The units line follows; a file without one goes straight to numbers.
    let next = lines.iter().enumerate().skip(names_at + 1).find(|(_, (_, l))| !l.trim().is_empty()).map(|(i, _)| i);
    let (units, data_from) = match next {
        Some(i) => {
            let (f, _) = fields(lines[i].1);
            if f.iter().all(|s| s.is_empty() || is_number(s)) && header_units.iter().any(Option::is_some) {
                // The units came with the names (`FZ [N]`).
                (header_units.iter().map(|u| u.clone().unwrap_or_default()).collect(), i)
            } else if f.iter().all(|s| s.is_empty() || is_number(s)) {
                warn.push(
                    "no units",
                    Place::line(file, lines[i].0),
                    "no units line after the channel names: TTC units assumed (checked against magnitudes)",
                );
                (vec![String::new(); names.len()], i)
            } else {
                let units_line = lines[i].0;
                let mut u: Vec<String> = f.iter().map(|s| (*s).to_owned()).collect();
                // Separated by spaces, `deg C` / `deg F` (other rounds' spelling) came apart.
                if u.len() > names.len() && !lines[i].1.contains(['\t', ',', ';']) {
                    u = rejoin_degrees(u);
                }
                if u.len() > names.len() {
                    warn.push(
                        "units count",
                        Place::line(file, units_line),
                        format!("{} units for {} channels: the extra ones ignored", u.len(), names.len()),
                    );
                    u.truncate(names.len());
                }
                for (k, name) in names.iter().enumerate().skip(u.len()) {
                    warn.push(
                        "missing unit",
                        Place::line(file, units_line).channel(name),
                        format!("no unit given (column {}): the TTC unit is assumed", k + 1),
                    );
                }
                u.resize(names.len(), String::new());
                (u, i + 1)
            }
        }
        None => return Err(ReadError::at(Place::line(file, names_line), "no data after the channel names")),
    };
    let last_nonblank = lines.iter().rposition(|(_, l)| !l.trim().is_empty()).unwrap_or(0);
    let n = names.len();
    // Capacity from the line count (bounded by the file's size).
    let cap = lines.len().saturating_sub(data_from);
    let mut cols: Vec<Vec<f64>> = (0..n).map(|_| Vec::with_capacity(cap)).collect();
    let mut row_lines = Vec::with_capacity(cap);
    let mut trailing_tabs = 0usize;
    let mut not_read: Vec<(String, usize)> = Vec::new();
    let mut skip = |why: &str| match not_read.iter_mut().find(|(w, _)| w == why) {
        Some((_, n)) => *n += 1,
        None => not_read.push((why.to_owned(), 1)),
    };
    let mut first_trailing = 0usize;
    for (idx, &(ln, line)) in lines.iter().enumerate().skip(data_from) {
        if line.trim().is_empty() {
            // The empty piece after the final newline is not a blank line.
            if idx + 1 < lines.len() {
                warn.push("blank line", Place::line(file, ln), "blank line skipped");
            }
            continue;
        }
        let (f, trailing) = fields(line);
        if trailing {
            trailing_tabs += 1;
            if first_trailing == 0 {
                first_trailing = ln;
            }
        }
        if !f.iter().any(|s| is_number(s)) {
            warn.push("not data", Place::line(file, ln), format!("not a row of numbers (`{}`): skipped", clip(line)));
            skip("not a row of numbers");
            continue;
        }
        if f.len() < n {
            if idx == last_nonblank {
                warn.push(
                    "truncated last line",
                    Place::line(file, ln).channel(&names[f.len()]),
                    format!("last line cut short ({} of {n} values): dropped", f.len()),
                );
                skip("last line cut short");
            } else {
                warn.push(
                    "missing values",
                    Place::line(file, ln).channel(&names[f.len()]),
                    format!("{} of {n} values (missing from this channel on): row dropped", f.len()),
                );
                skip("values missing");
            }
            continue;
        }
        if f.len() > n {
            warn.push(
                "extra values",
                Place::line(file, ln),
                format!("{} values for {n} channels: the extra ones ignored", f.len()),
            );
        }
        for (k, s) in f.iter().take(n).enumerate() {
            // A semicolon-separated file from a spreadsheet writes decimal commas (`0,02`).
            let v = match s.parse::<f64>().or_else(|e| match s.replacen(',', ".", 1).parse::<f64>() {
                Ok(v) if !s.contains('.') => Ok(v),
                _ => Err(e),
            }) {
                Ok(v) => v,
                Err(_) => {
                    warn.push(
                        "not a number",
                        Place::line(file, ln).channel(&names[k]),
                        format!("`{}` is not a number: read as NaN", clip(s)),
                    );
                    f64::NAN
                }
            };
            cols[k].push(v);
        }
        row_lines.push(ln);
    }
    if trailing_tabs > 0 {
        warn.push(
            "trailing tab",
            Place::line(file, first_trailing),
            format!("{trailing_tabs} lines end with a tab (first here): the empty last field ignored"),
        );
    }
    if row_lines.is_empty() {
        return Err(ReadError::at(
            Place::line(file, names_line),
            "no rows of numbers after the channel names and units",
        ));
    }
    let mut table = ChannelTable { source: file.to_owned(), title, ..Default::default() };
    table.tire_id = table.title.as_deref().and_then(tire_name_of);
    for ((name, unit), values) in names.into_iter().zip(units).zip(cols) {
        table.columns.push(crate::table::Column { name, unit, values });
    }
    Ok(TextTable { table, lines: row_lines, warnings: warn.finish(file), lines_not_read: not_read })
}

/// `Tire_Name=…` from a TIRF title line (`…; Tire_Name=Hoosier 16.0X7.5-10, R20, C2000; …`).
pub fn tire_name_of(title: &str) -> Option<String> {
    title.split(';').find_map(|part| {
        let (k, v) = part.split_once('=')?;
        (k.trim().eq_ignore_ascii_case("tire_name") || k.trim().eq_ignore_ascii_case("tyre_name"))
            .then(|| v.trim().to_owned())
            .filter(|v| !v.is_empty())
    })
}

/// A field or line, shortened for a message.
fn clip(s: &str) -> String {
    let s = s.trim();
    if s.chars().count() > 40 { format!("{}…", s.chars().take(40).collect::<String>()) } else { s.to_owned() }
}

/// `deg` followed by `C` or `F` is one unit, `deg C`, in a units line split at spaces.
fn rejoin_degrees(units: Vec<String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(units.len());
    for u in units {
        match out.last_mut() {
            Some(last) if last.eq_ignore_ascii_case("deg") && matches!(u.as_str(), "C" | "F" | "c" | "f") => {
                last.push(' ');
                last.push_str(&u);
            }
            _ => out.push(u),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comma_semicolon_and_space_separated_files_read_like_tab_separated_ones() {
        let tabbed = parse_dat(CLEAN.as_bytes(), "a.dat").unwrap();
        for sep in [",", ";", "   "] {
            let text = CLEAN.replace('\t', sep);
            let t = parse_dat(text.as_bytes(), "c.dat").unwrap_or_else(|e| panic!("{sep:?}: {e}"));
            assert_eq!(t.table.rows(), tabbed.table.rows(), "{sep:?}");
            for (a, b) in tabbed.table.columns.iter().zip(&t.table.columns) {
                assert_eq!((&a.name, &a.unit, &a.values), (&b.name, &b.unit, &b.values), "{sep:?}");
            }
            // The title's own commas and semicolons do not make it a names line.
            assert_eq!(t.table.tire_id, tabbed.table.tire_id, "{sep:?}");
        }
        // Semicolons with decimal commas, as a spreadsheet in many locales writes them.
        let text = CLEAN.replace('.', ",").replace('\t', ";");
        let t = parse_dat(text.as_bytes(), "e.dat").unwrap();
        assert_eq!(t.table.column("SA").unwrap().values, [0.5, 0.6]);
        assert_eq!(t.table.column("V").unwrap().values, [40.1, 40.0]);
        assert!(t.warnings.is_empty(), "{:?}", t.warnings);
        // Units in brackets with the names and no units line, as re-exported files write them.
        for header in ["ET [s]\tV [kph]\tSA (deg)\tFZ[N]\tP [kPa]", "ET [s]  V [kph]  SA (deg)  FZ[N]  P [kPa]"] {
            let text = format!("{header}\n0\t40.1\t0.5\t-1100\t83\n")
                .replace('\t', if header.contains('\t') { "\t" } else { "  " });
            let t = parse_dat(text.as_bytes(), "h.dat").unwrap_or_else(|e| panic!("{header}: {e}"));
            let unit = |n: &str| t.table.column(n).unwrap_or_else(|| panic!("{header}: {n}")).unit.clone();
            assert_eq!([unit("ET"), unit("V"), unit("SA"), unit("FZ"), unit("P")], ["s", "kph", "deg", "N", "kPa"]);
            assert_eq!(t.table.column("SA").unwrap().values, [0.5], "{header}");
            assert!(!t.warnings.iter().any(|w| w.message.contains("no units")), "{:?}", t.warnings);
        }
        // `deg C` split at the space is one unit again.
        let text = "ET  TSTC  AMBTMP  FZ  SA\n s  deg C  deg F  N  deg\n0  50  86  -1100  0.5\n";
        let t = parse_dat(text.as_bytes(), "d.dat").unwrap();
        let unit = |n: &str| t.table.column(n).unwrap().unit.clone();
        assert_eq!([unit("TSTC"), unit("AMBTMP"), unit("FZ"), unit("SA")], ["deg C", "deg F", "N", "deg"]);
        assert!(t.warnings.iter().all(|w| w.message.starts_with("no title line")), "{:?}", t.warnings);
    }

    const CLEAN: &str = "TIRF Data File: Project 1; Run 4; Tire_Name=Test 20.5x7.0-13, R25B; Rim_Width=7.0\r\n\
        ET\tV\tSA\tFZ\tP\r\n\
        s\tkph\tdeg\tN\tkPa\r\n\
        0.00\t40.1\t0.5\t-1100\t83\r\n\
        0.02\t40.0\t0.6\t-1101\t83\r\n";

    #[test]
    fn clean_file_reads_with_title_tyre_and_units() {
        let t = parse_dat(CLEAN.as_bytes(), "a.dat").unwrap();
        assert!(t.warnings.is_empty(), "{:?}", t.warnings);
        assert_eq!(t.table.rows(), 2);
        assert_eq!(t.lines, [4, 5]);
        assert_eq!(t.table.tire_id.as_deref(), Some("Test 20.5x7.0-13, R25B"));
        assert_eq!(t.table.column("FZ").unwrap().unit, "N");
        assert_eq!(t.table.column("SA").unwrap().values, [0.5, 0.6]);
    }

    #[test]
    fn oddities_are_warnings_naming_line_and_channel() {
        let text = "title\n\nET\tV\tSA\tFZ\t\n s\tkph\tdeg\tN\n\n0\t40\t0.5\t-1100\t\n0.02\t40\tNaN\t-1100\n0.04\t40\tx1\t-1100\t7\n0.06\t40\n0.08\t40\t1";
        let t = parse_dat(text.as_bytes(), "b.dat").unwrap();
        let w: Vec<String> = t.warnings.iter().map(|w| w.to_string()).collect();
        let has = |s: &str| w.iter().any(|x| x.contains(s));
        assert!(has("b.dat:5: blank line skipped"), "{w:?}");
        assert!(has("b.dat:8: channel SA: `x1` is not a number"), "{w:?}");
        assert!(has("b.dat:8: 5 values for 4 channels"), "{w:?}");
        assert!(has("b.dat:9: channel SA: 2 of 4 values"), "{w:?}");
        assert!(has("b.dat:10: channel FZ: last line cut short"), "{w:?}");
        assert!(has("lines end with a tab"), "{w:?}");
        assert_eq!(t.table.rows(), 3);
        assert!(t.table.column("SA").unwrap().values[1].is_nan());
        assert_eq!(t.lines, [6, 7, 8]);
    }

    #[test]
    fn missing_title_and_units_are_warnings() {
        let t = parse_dat(b"SA FZ\n1 -100\n2 -100\n", "c.dat").unwrap();
        assert_eq!(t.table.rows(), 2);
        assert!(t.table.title.is_none());
        assert_eq!(t.warnings.len(), 2, "{:?}", t.warnings);
        assert!(parse_dat(b"hello\nworld\n", "d.dat").unwrap_err().to_string().contains("no line of channel names"));
        assert!(parse_dat(b"t\nSA\tFZ\ndeg\tN\n", "e.dat").unwrap_err().to_string().contains("e.dat:2"));
    }
}
