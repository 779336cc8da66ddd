//! Writing Level 5 `.mat` files the way MATLAB does (`save -v7` / `-v6`), so fixtures exercise
//! every path of the reader: compressed or not, little- or big-endian, channels as top-level
//! variables or in one struct, doubles holding small integers stored as `int8`/`uint8`/…, and
//! 4-byte names in the small data element form.

use std::io::Write as _;
use std::path::Path;

use super::{class, ty};
use crate::channels::role_of;
use crate::error::{Place, ReadError};
use crate::table::ChannelTable;
use crate::units;

/// Where the channels go.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum MatLayout {
    /// One variable per channel (the usual TTC layout).
    #[default]
    Variables,
    /// One 1×1 struct variable of this name, one field per channel.
    Struct(String),
}

/// How `tireid` / `testid` are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CharEncoding {
    /// `miUINT16` code units (what MATLAB writes).
    #[default]
    Utf16,
    /// `miUTF8`.
    Utf8,
}

/// Where a `.mat` file's units are, if anywhere.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MatUnits {
    /// No units: the values converted to the TTC units, which a reader assumes.
    #[default]
    TtcAssumed,
    /// The values in the table's own units, listed in a 1×1 struct `channel` whose fields
    /// `name` and `units` are cell arrays of strings, as TTC's distributed files have them.
    ChannelStruct,
    /// The values in the table's own units and no units anywhere (a US-customary run saved
    /// without its units list): the reader must tell the system from the magnitudes.
    Unlisted,
}

/// Options of [`to_mat`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MatWriteOptions {
    /// zlib-compress each variable (`-v7`); `false` writes `-v6` style.
    pub compress: bool,
    /// Big-endian byte order (old Sun/IBM MATLAB); little-endian otherwise.
    pub big_endian: bool,
    /// Layout of the channels.
    pub layout: MatLayout,
    /// Store a channel whose values are all small integers in the smallest integer type, as
    /// MATLAB does (the class stays double).
    pub narrow_integers: bool,
    /// Text encoding of the id strings.
    pub chars: CharEncoding,
    /// Where the units go.
    pub units: MatUnits,
}

impl Default for MatWriteOptions {
    fn default() -> Self {
        Self {
            compress: true,
            big_endian: false,
            layout: MatLayout::Variables,
            narrow_integers: true,
            chars: CharEncoding::Utf16,
            units: MatUnits::TtcAssumed,
        }
    }
}

struct Out {
    be: bool,
    b: Vec<u8>,
}

impl Out {
    fn u32(&mut self, v: u32) {
        self.b.extend_from_slice(&if self.be { v.to_be_bytes() } else { v.to_le_bytes() });
    }

    fn pad(&mut self) {
        while !self.b.len().is_multiple_of(8) {
            self.b.push(0);
        }
    }

    /// A data element of `data` (already in the file's byte order); the small form when ≤ 4 bytes.
    fn element(&mut self, t: u32, data: &[u8]) {
        if !data.is_empty() && data.len() <= 4 {
            self.u32(((data.len() as u32) << 16) | t);
            self.b.extend_from_slice(data);
            self.b.extend(std::iter::repeat_n(0, 4 - data.len()));
        } else {
            self.u32(t);
            self.u32(data.len() as u32);
            self.b.extend_from_slice(data);
            self.pad();
        }
    }
}

/// Values in the smallest integer type that holds them all exactly (MATLAB's storage rule).
fn narrowest(values: &[f64]) -> Option<u32> {
    if values.is_empty() || !values.iter().all(|v| v.fract() == 0.0 && v.is_finite()) {
        return None;
    }
    let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    [
        (ty::UINT8, 0.0, 255.0),
        (ty::INT8, -128.0, 127.0),
        (ty::UINT16, 0.0, 65_535.0),
        (ty::INT16, -32_768.0, 32_767.0),
        (ty::UINT32, 0.0, 4_294_967_295.0),
        (ty::INT32, -2_147_483_648.0, 2_147_483_647.0),
    ]
    .iter()
    .find(|(_, a, b)| lo >= *a && hi <= *b)
    .map(|(t, _, _)| *t)
}

fn numeric_bytes(values: &[f64], t: u32, be: bool) -> Vec<u8> {
    let mut b = Vec::with_capacity(values.len() * 8);
    for &v in values {
        macro_rules! put {
            ($x:expr) => {
                b.extend_from_slice(&if be { $x.to_be_bytes() } else { $x.to_le_bytes() })
            };
        }
        match t {
            ty::UINT8 => b.push(v as u8),
            ty::INT8 => b.push(v as i8 as u8),
            ty::UINT16 => put!(v as u16),
            ty::INT16 => put!(v as i16),
            ty::UINT32 => put!(v as u32),
            ty::INT32 => put!(v as i32),
            _ => put!(v),
        }
    }
    b
}

/// An `miMATRIX` element's content (flags, dimensions, name, data).
enum Body<'a> {
    Vector(&'a [f64]),
    Text(&'a str),
    Struct(Vec<(String, Body<'a>)>),
    /// A 1×n cell array of strings.
    Strings(Vec<&'a str>),
}

fn matrix(o: &mut Out, name: &str, body: &Body, opt: &MatWriteOptions) {
    let mut m = Out { be: o.be, b: Vec::new() };
    let (cls, dims): (u8, [u32; 2]) = match body {
        Body::Vector(v) => (class::DOUBLE, [v.len() as u32, 1]),
        Body::Text(s) => {
            let n = match opt.chars {
                CharEncoding::Utf16 => s.encode_utf16().count(),
                CharEncoding::Utf8 => s.chars().count(),
            };
            (class::CHAR, [1, n as u32])
        }
        Body::Struct(_) => (class::STRUCT, [1, 1]),
        Body::Strings(items) => (class::CELL, [1, items.len() as u32]),
    };
    let mut flags = Out { be: o.be, b: Vec::new() };
    flags.u32(cls as u32);
    flags.u32(0);
    m.element(ty::UINT32, &flags.b);
    let mut d = Out { be: o.be, b: Vec::new() };
    d.u32(dims[0]);
    d.u32(dims[1]);
    m.element(ty::INT32, &d.b);
    if name.is_empty() {
        // MATLAB writes an empty name as a full tag of zero length.
        m.u32(ty::INT8);
        m.u32(0);
    } else {
        m.element(ty::INT8, name.as_bytes());
    }
    match body {
        Body::Vector(v) => {
            let t = if opt.narrow_integers { narrowest(v).unwrap_or(ty::DOUBLE) } else { ty::DOUBLE };
            m.element(t, &numeric_bytes(v, t, o.be));
        }
        Body::Text(s) => match opt.chars {
            CharEncoding::Utf16 => {
                let mut t = Out { be: o.be, b: Vec::new() };
                for u in s.encode_utf16() {
                    t.b.extend_from_slice(&if o.be { u.to_be_bytes() } else { u.to_le_bytes() });
                }
                m.element(ty::UINT16, &t.b);
            }
            CharEncoding::Utf8 => m.element(ty::UTF8, s.as_bytes()),
        },
        Body::Struct(fields) => {
            let len = fields.iter().map(|(n, _)| n.len() + 1).max().unwrap_or(1).max(32);
            let mut l = Out { be: o.be, b: Vec::new() };
            l.u32(len as u32);
            m.element(ty::INT32, &l.b);
            let mut names = Vec::with_capacity(len * fields.len());
            for (n, _) in fields {
                names.extend_from_slice(n.as_bytes());
                names.extend(std::iter::repeat_n(0, len - n.len()));
            }
            m.element(ty::INT8, &names);
            for (_, f) in fields {
                let mut inner = Out { be: o.be, b: Vec::new() };
                matrix(&mut inner, "", f, &MatWriteOptions { compress: false, ..opt.clone() });
                m.b.extend_from_slice(&inner.b);
            }
        }
        Body::Strings(items) => {
            for item in items {
                let mut inner = Out { be: o.be, b: Vec::new() };
                matrix(&mut inner, "", &Body::Text(item), &MatWriteOptions { compress: false, ..opt.clone() });
                m.b.extend_from_slice(&inner.b);
            }
        }
    }
    o.u32(ty::MATRIX);
    o.u32(m.b.len() as u32);
    o.b.extend_from_slice(&m.b);
}

fn variable(o: &mut Out, name: &str, body: &Body, opt: &MatWriteOptions) {
    if opt.compress {
        let mut raw = Out { be: o.be, b: Vec::new() };
        matrix(&mut raw, name, body, opt);
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        // Writing into a Vec cannot fail.
        let _ = z.write_all(&raw.b);
        let packed = z.finish().unwrap_or_default();
        o.u32(ty::COMPRESSED);
        o.u32(packed.len() as u32);
        o.b.extend_from_slice(&packed);
    } else {
        matrix(o, name, body, opt);
    }
}

/// The bytes of a Level 5 `.mat` file holding `table`'s channels and ids. With
/// [`MatUnits::TtcAssumed`] channels the readers know are converted to the TTC units first (a
/// `.mat` without a units list has its reader assume them); an unknown unit on such a channel
/// is an error.
pub fn to_mat(table: &ChannelTable, opt: &MatWriteOptions) -> Result<Vec<u8>, ReadError> {
    let mut cols: Vec<(String, Vec<f64>)> = Vec::with_capacity(table.columns.len());
    for c in &table.columns {
        let values = match role_of(&c.name) {
            Some(role)
                if opt.units == MatUnits::TtcAssumed
                    && !c.unit.trim().is_empty()
                    && c.unit.trim() != role.ttc_unit() =>
            {
                let place = Place::file(&table.source).channel(&c.name);
                let from = units::parse(&c.unit).filter(|u| u.quantity == role.quantity()).ok_or_else(|| {
                    ReadError::at(
                        place.clone(),
                        format!("unit `{}` is not a unit of {}", c.unit, role.quantity().name()),
                    )
                })?;
                let to = units::parse(role.ttc_unit()).ok_or_else(|| ReadError::at(place, "no TTC unit"))?;
                c.values.iter().map(|&v| to.from_target(from.to_target(v))).collect()
            }
            _ => c.values.clone(),
        };
        cols.push((c.name.clone(), values));
    }
    let mut o =
        Out { be: opt.big_endian, b: Vec::with_capacity(128 + cols.iter().map(|c| c.1.len() * 8 + 64).sum::<usize>()) };
    let mut text = format!("MATLAB 5.0 MAT-file, Platform: tyrerig, Created by: rigdata ({})", table.source);
    text.truncate(116);
    while text.len() < 116 {
        text.push(' ');
    }
    o.b.extend_from_slice(text.as_bytes());
    o.b.extend_from_slice(&[0; 8]);
    let version: u16 = 0x0100;
    o.b.extend_from_slice(&if o.be { version.to_be_bytes() } else { version.to_le_bytes() });
    o.b.extend_from_slice(if o.be { b"MI" } else { b"IM" });
    let ids: Vec<(&str, &str)> = [("tireid", table.tire_id.as_deref()), ("testid", table.test_id.as_deref())]
        .into_iter()
        .filter_map(|(n, v)| v.map(|v| (n, v)))
        .collect();
    match &opt.layout {
        MatLayout::Variables => {
            for (n, v) in &cols {
                variable(&mut o, n, &Body::Vector(v), opt);
            }
        }
        MatLayout::Struct(name) => {
            let fields = cols.iter().map(|(n, v)| (n.clone(), Body::Vector(v))).collect();
            variable(&mut o, name, &Body::Struct(fields), opt);
        }
    }
    if opt.units == MatUnits::ChannelStruct {
        let names = table.columns.iter().map(|c| c.name.as_str()).collect();
        let units = table.columns.iter().map(|c| c.unit.trim()).collect();
        let list = Body::Struct(vec![("name".into(), Body::Strings(names)), ("units".into(), Body::Strings(units))]);
        variable(&mut o, "channel", &list, opt);
    }
    for (n, v) in ids {
        variable(&mut o, n, &Body::Text(v), opt);
    }
    Ok(o.b)
}

/// Writes a `.mat` file.
pub fn write_mat(path: &Path, table: &ChannelTable, opt: &MatWriteOptions) -> Result<(), ReadError> {
    let bytes = to_mat(table, opt)?;
    std::fs::write(path, bytes).map_err(|source| ReadError::Io { path: path.to_owned(), source })
}
