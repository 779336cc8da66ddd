//! A measured file's raw content: named channels with the units they were written in.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

/// One channel as written in the file: its name (`SA`, `FZ`, `TSTC`, …), its unit as written
/// (`deg`, `N`, `kPa`, `degC`, …; empty when the file does not say) and one value per row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Column {
    /// Channel name as written (case kept).
    pub name: String,
    /// Unit as written; empty when the format carries none (MATLAB files).
    pub unit: String,
    /// Values, one per row.
    pub values: Vec<f64>,
}

/// A measured run before interpretation: every channel of the file, in file order, plus what
/// the file says about itself. All columns have the same length.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ChannelTable {
    /// Where it came from (a path, or e.g. `virtual rig`).
    pub source: String,
    /// The title line of a TTC `.dat` (`TIRF Data File: Project …; Tire_Name=…`), if any.
    pub title: Option<String>,
    /// The tyre's id (`tireid` of a TTC `.mat`, or `Tire_Name` from a title).
    pub tire_id: Option<String>,
    /// The test's id (`testid` of a TTC `.mat`, e.g. `Cornering, Various pressures`).
    pub test_id: Option<String>,
    /// The channels.
    pub columns: Vec<Column>,
}

impl ChannelTable {
    /// Number of rows (0 without columns).
    pub fn rows(&self) -> usize {
        self.columns.first().map(|c| c.values.len()).unwrap_or(0)
    }

    /// The column named `name` (ASCII case-insensitive).
    pub fn column(&self, name: &str) -> Option<&Column> {
        self.columns.iter().find(|c| c.name.eq_ignore_ascii_case(name))
    }

    /// Appends a channel.
    pub fn push(&mut self, name: &str, unit: &str, values: Vec<f64>) {
        self.columns.push(Column { name: name.to_owned(), unit: unit.to_owned(), values });
    }
}

/// How [`to_dat`] lays out a TTC-style text file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DatLayout {
    /// Decimal places per value.
    pub decimals: usize,
    /// Windows line ends (`\r\n`), as files written on the rig's PC have.
    pub crlf: bool,
}

impl Default for DatLayout {
    fn default() -> Self {
        Self { decimals: 4, crlf: true }
    }
}

/// The TTC `.dat` layout: line 1 the title (or `tyrerig export` when the table has none), line 2
/// the channel names, line 3 the units, then one tab-separated row per sample. Non-finite values
/// are written as `NaN`.
pub fn to_dat(table: &ChannelTable, layout: DatLayout) -> String {
    let eol = if layout.crlf { "\r\n" } else { "\n" };
    let mut s = String::new();
    s.push_str(table.title.as_deref().unwrap_or("tyrerig export"));
    s.push_str(eol);
    let names: Vec<&str> = table.columns.iter().map(|c| c.name.as_str()).collect();
    s.push_str(&names.join("\t"));
    s.push_str(eol);
    let units: Vec<&str> = table.columns.iter().map(|c| c.unit.as_str()).collect();
    s.push_str(&units.join("\t"));
    s.push_str(eol);
    for row in 0..table.rows() {
        for (i, c) in table.columns.iter().enumerate() {
            if i > 0 {
                s.push('\t');
            }
            let v = c.values.get(row).copied().unwrap_or(f64::NAN);
            if v.is_finite() {
                let _ = write!(s, "{v:.*}", layout.decimals);
            } else {
                s.push_str("NaN");
            }
        }
        s.push_str(eol);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dat_layout_has_title_names_units_and_rows() {
        let mut t = ChannelTable { title: Some("TIRF Data File: test".into()), ..Default::default() };
        t.push("ET", "s", vec![0.0, 0.02]);
        t.push("SA", "deg", vec![1.5, f64::NAN]);
        let text = to_dat(&t, DatLayout { decimals: 3, crlf: false });
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines, ["TIRF Data File: test", "ET\tSA", "s\tdeg", "0.000\t1.500", "0.020\tNaN"]);
        assert_eq!(t.rows(), 2);
        assert_eq!(t.column("sa").map(|c| c.unit.as_str()), Some("deg"));
    }
}
