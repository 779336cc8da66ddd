//! Reading `.mat` files. Every length in the file is checked against the bytes actually there
//! before anything is allocated, so a corrupted dimension or byte count gives an error, never a
//! huge allocation; decompression stops at a bound set by the compressed size.

use std::io::Read as _;
use std::path::Path;

use super::{class, ty};
use crate::channels::role_of;
use crate::error::{Place, ReadError, Warning, Warnings};
use crate::table::{ChannelTable, Column};

/// A `.mat` file read into a table (units empty: MATLAB files carry none).
#[derive(Debug, Clone)]
pub struct MatFile {
    /// The channels.
    pub table: ChannelTable,
    /// Which layout the channels were in (`top-level variables`, `struct variable `run``, …).
    pub layout: String,
    /// The file's format (`MATLAB 5.0 MAT-file (little-endian)`, `MATLAB Level 4`, …).
    pub format: String,
    /// What was odd.
    pub warnings: Vec<Warning>,
}

/// Deflate cannot expand data more than about 1032:1; a stream claiming more is corrupt.
const MAX_INFLATE_RATIO: usize = 1032;
/// And no variable of a rig file needs more than this once decompressed.
const MAX_INFLATED_BYTES: usize = 1 << 30;
/// Structs inside cells inside structs…: a rig file needs two levels; a file with more is odd,
/// and a crafted one must not exhaust the stack.
const MAX_DEPTH: usize = 12;

#[derive(Debug, Clone)]
enum Value {
    Numeric { dims: Vec<usize>, values: Vec<f64>, complex: bool },
    Char { text: String },
    Struct { dims: Vec<usize>, fields: Vec<(String, Vec<Value>)> },
    Cell { dims: Vec<usize>, items: Vec<Value> },
    Other { class: u8 },
    Empty,
}

impl Value {
    fn describe(&self) -> String {
        match self {
            Value::Numeric { dims, .. } => format!("numeric {}", dims_text(dims)),
            Value::Char { .. } => "char array".into(),
            Value::Struct { dims, .. } => format!("struct {}", dims_text(dims)),
            Value::Cell { dims, .. } => format!("cell array {}", dims_text(dims)),
            Value::Other { class } => format!("class {class}"),
            Value::Empty => "empty".into(),
        }
    }
}

fn dims_text(d: &[usize]) -> String {
    d.iter().map(|x| x.to_string()).collect::<Vec<_>>().join("×")
}

struct Ctx<'f> {
    file: &'f str,
    be: bool,
    warn: Warnings,
}

impl Ctx<'_> {
    fn err(&self, var: &str, message: impl Into<String>) -> ReadError {
        let place = Place::file(self.file);
        ReadError::at(if var.is_empty() { place } else { place.channel(var) }, message)
    }

    fn u32_at(&self, b: &[u8], at: usize) -> Option<u32> {
        let x: [u8; 4] = b.get(at..at + 4)?.try_into().ok()?;
        Some(if self.be { u32::from_be_bytes(x) } else { u32::from_le_bytes(x) })
    }
}

/// One data element: its type, its data and where the next element starts.
struct Element<'a> {
    ty: u32,
    data: &'a [u8],
    next: usize,
}

/// Reads the element at `at` of `b`; `var` names the variable in errors.
fn element<'a>(cx: &Ctx, b: &'a [u8], at: usize, var: &str) -> Result<Element<'a>, ReadError> {
    let first =
        cx.u32_at(b, at).ok_or_else(|| cx.err(var, format!("file ends inside a data element tag at byte {at}")))?;
    if first >> 16 != 0 {
        // Small data element: count in the upper half, type in the lower, data in the next 4 bytes.
        let n = (first >> 16) as usize;
        if n > 4 {
            return Err(cx.err(var, format!("small data element at byte {at} claims {n} bytes (at most 4)")));
        }
        let data = b
            .get(at + 4..at + 4 + n)
            .ok_or_else(|| cx.err(var, format!("file ends inside the element at byte {at}")))?;
        return Ok(Element { ty: first & 0xffff, data, next: at + 8 });
    }
    let n = cx
        .u32_at(b, at + 4)
        .ok_or_else(|| cx.err(var, format!("file ends inside a data element tag at byte {at}")))? as usize;
    let start = at + 8;
    let end = start.checked_add(n).filter(|&e| e <= b.len()).ok_or_else(|| {
        cx.err(
            var,
            format!(
                "element at byte {at} claims {n} bytes but only {} remain (truncated or corrupt file)",
                b.len().saturating_sub(start)
            ),
        )
    })?;
    // Elements are padded to 8 bytes, except compressed ones.
    let next = if first == ty::COMPRESSED { end } else { end.div_ceil(8) * 8 };
    Ok(Element { ty: first, data: &b[start..end], next })
}

/// Numeric values of an element, whatever type they were stored in.
fn numbers(cx: &Ctx, e: &Element, var: &str) -> Result<Vec<f64>, ReadError> {
    macro_rules! conv {
        ($t:ty, $n:expr) => {{
            if e.data.len() % $n != 0 {
                return Err(
                    cx.err(var, format!("{} bytes of data is not a whole number of {}-byte values", e.data.len(), $n))
                );
            }
            e.data
                .chunks_exact($n)
                .map(|c| {
                    let a: [u8; $n] = c.try_into().unwrap_or([0; $n]);
                    (if cx.be { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
                })
                .collect()
        }};
    }
    Ok(match e.ty {
        ty::INT8 => e.data.iter().map(|&x| x as i8 as f64).collect(),
        ty::UINT8 => e.data.iter().map(|&x| x as f64).collect(),
        ty::INT16 => conv!(i16, 2),
        ty::UINT16 => conv!(u16, 2),
        ty::INT32 => conv!(i32, 4),
        ty::UINT32 => conv!(u32, 4),
        ty::SINGLE => conv!(f32, 4),
        ty::DOUBLE => conv!(f64, 8),
        ty::INT64 => conv!(i64, 8),
        ty::UINT64 => conv!(u64, 8),
        other => return Err(cx.err(var, format!("data type {other} is not numeric"))),
    })
}

fn text_of(cx: &Ctx, e: &Element, var: &str) -> Result<String, ReadError> {
    Ok(match e.ty {
        ty::UINT16 | ty::UTF16 => {
            if !e.data.len().is_multiple_of(2) {
                return Err(cx.err(var, "UTF-16 text with an odd number of bytes"));
            }
            let u: Vec<u16> = e
                .data
                .chunks_exact(2)
                .map(|c| if cx.be { u16::from_be_bytes([c[0], c[1]]) } else { u16::from_le_bytes([c[0], c[1]]) })
                .collect();
            String::from_utf16_lossy(&u)
        }
        ty::UTF8 | ty::UINT8 | ty::INT8 => String::from_utf8_lossy(e.data).into_owned(),
        ty::UTF32 | ty::UINT32 | ty::INT32 => numbers(cx, &Element { ty: ty::UINT32, data: e.data, next: 0 }, var)?
            .into_iter()
            .map(|c| char::from_u32(c as u32).unwrap_or('\u{fffd}'))
            .collect(),
        ty::DOUBLE => {
            numbers(cx, e, var)?.into_iter().map(|c| char::from_u32(c as u32).unwrap_or('\u{fffd}')).collect()
        }
        other => return Err(cx.err(var, format!("char array stored as data type {other}"))),
    })
}

/// Column-major char matrix → text (rows joined by newlines, trailing blanks trimmed).
fn char_rows(text: &str, dims: &[usize]) -> String {
    let chars: Vec<char> = text.chars().collect();
    let rows = dims.first().copied().unwrap_or(1).max(1);
    if rows == 1 || !chars.len().is_multiple_of(rows) {
        return text.trim_end_matches(['\0', ' ']).to_owned();
    }
    let cols = chars.len() / rows;
    (0..rows)
        .map(|r| (0..cols).map(|c| chars[c * rows + r]).collect::<String>().trim_end_matches(['\0', ' ']).to_owned())
        .collect::<Vec<_>>()
        .join("\n")
}

fn product(cx: &Ctx, dims: &[usize], var: &str) -> Result<usize, ReadError> {
    dims.iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or_else(|| cx.err(var, format!("dimensions {} overflow", dims_text(dims))))
}

/// Parses the data of an `miMATRIX` element into its name and value.
fn matrix(cx: &mut Ctx, b: &[u8], depth: usize, parent: &str) -> Result<(String, Value), ReadError> {
    if depth > MAX_DEPTH {
        return Err(cx.err(parent, format!("structs/cells nested deeper than {MAX_DEPTH} levels")));
    }
    if b.is_empty() {
        return Ok((String::new(), Value::Empty));
    }
    let flags = element(cx, b, 0, parent)?;
    if flags.ty != ty::UINT32 || flags.data.len() < 4 {
        return Err(cx.err(
            parent,
            format!("array flags expected (uint32), found type {} of {} bytes", flags.ty, flags.data.len()),
        ));
    }
    let f0 = cx.u32_at(flags.data, 0).unwrap_or(0);
    let cls = (f0 & 0xff) as u8;
    let complex = f0 & 0x0800 != 0;
    let de = element(cx, b, flags.next, parent)?;
    if !matches!(de.ty, ty::INT32 | ty::UINT32) || de.data.len() % 4 != 0 {
        return Err(cx.err(parent, format!("dimensions expected (int32), found type {}", de.ty)));
    }
    let mut dims = Vec::with_capacity(de.data.len() / 4);
    for k in 0..de.data.len() / 4 {
        let d = cx.u32_at(de.data, 4 * k).unwrap_or(0) as i32;
        if d < 0 {
            return Err(cx.err(parent, format!("negative dimension {d}")));
        }
        dims.push(d as usize);
    }
    let ne = element(cx, b, de.next, parent)?;
    if !matches!(ne.ty, ty::INT8 | ty::UINT8 | ty::UTF8) {
        return Err(cx.err(parent, format!("array name expected (int8), found type {}", ne.ty)));
    }
    let name = String::from_utf8_lossy(ne.data).trim_end_matches('\0').to_owned();
    let here = if name.is_empty() { parent.to_owned() } else { name.clone() };
    let mut at = ne.next;
    let count = product(cx, &dims, &here)?;
    let value = match cls {
        class::DOUBLE..=class::UINT64 => {
            let re = element(cx, b, at, &here)?;
            at = re.next;
            let values = numbers(cx, &re, &here)?;
            if values.len() != count {
                return Err(cx.err(
                    &here,
                    format!("dimensions {} say {count} values, the data holds {}", dims_text(&dims), values.len()),
                ));
            }
            if complex {
                // The imaginary part follows; rig data has none worth keeping.
                let _ = element(cx, b, at, &here)?;
            }
            Value::Numeric { dims, values, complex }
        }
        class::CHAR => {
            let e = element(cx, b, at, &here)?;
            let text = text_of(cx, &e, &here)?;
            Value::Char { text: char_rows(&text, &dims) }
        }
        class::STRUCT => {
            let le = element(cx, b, at, &here)?;
            let len = match le.ty {
                ty::INT32 | ty::UINT32 => cx.u32_at(le.data, 0).unwrap_or(0) as usize,
                _ => return Err(cx.err(&here, "struct field name length expected (int32)")),
            };
            let fe = element(cx, b, le.next, &here)?;
            at = fe.next;
            if len == 0 || fe.data.len() % len != 0 {
                return Err(cx.err(
                    &here,
                    format!("struct field names of {} bytes do not divide into names of {len}", fe.data.len()),
                ));
            }
            let names: Vec<String> =
                fe.data.chunks(len).map(|c| String::from_utf8_lossy(c).trim_end_matches('\0').to_owned()).collect();
            // Every field of every element is at least an 8-byte tag: bound the count by the bytes.
            let total =
                count.checked_mul(names.len()).filter(|&t| t <= b.len().saturating_sub(at) / 8).ok_or_else(|| {
                    cx.err(
                        &here,
                        format!(
                            "struct {} with {} fields cannot fit in {} bytes",
                            dims_text(&dims),
                            names.len(),
                            b.len() - at
                        ),
                    )
                })?;
            let mut fields: Vec<(String, Vec<Value>)> = names.into_iter().map(|n| (n, Vec::new())).collect();
            let nf = fields.len();
            for k in 0..total {
                let e = element(cx, b, at, &here)?;
                at = e.next;
                let fname = format!("{here}.{}", fields[k % nf].0);
                let v = if e.ty == ty::MATRIX {
                    matrix(cx, e.data, depth + 1, &fname)?.1
                } else {
                    Value::Other { class: 0 }
                };
                fields[k % nf].1.push(v);
            }
            Value::Struct { dims, fields }
        }
        class::CELL => {
            // Every item is at least an 8-byte tag: bound the count by the bytes.
            if count > b.len().saturating_sub(at) / 8 {
                return Err(cx.err(
                    &here,
                    format!("cell {} cannot fit in {} bytes", dims_text(&dims), b.len().saturating_sub(at)),
                ));
            }
            let mut items = Vec::with_capacity(count);
            for k in 0..count {
                let e = element(cx, b, at, &here)?;
                at = e.next;
                items.push(if e.ty == ty::MATRIX {
                    matrix(cx, e.data, depth + 1, &format!("{here}{{{}}}", k + 1))?.1
                } else {
                    Value::Other { class: 0 }
                });
            }
            Value::Cell { dims, items }
        }
        other => Value::Other { class: other },
    };
    let _ = at;
    Ok((name, value))
}

fn inflate(cx: &Ctx, data: &[u8], var: &str) -> Result<Vec<u8>, ReadError> {
    let limit = data.len().saturating_mul(MAX_INFLATE_RATIO).saturating_add(64).min(MAX_INFLATED_BYTES);
    let mut out = Vec::new();
    flate2::read::ZlibDecoder::new(data)
        .take(limit as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| cx.err(var, format!("compressed variable does not decompress: {e}")))?;
    if out.len() > limit {
        return Err(cx.err(var, format!("compressed variable expands beyond {limit} bytes (corrupt)")));
    }
    Ok(out)
}

/// Top-level variables of a Level 5 file.
fn level5(cx: &mut Ctx, b: &[u8]) -> Result<Vec<(String, Value)>, ReadError> {
    let mut vars = Vec::new();
    let mut at = 128;
    let mut index = 0usize;
    while at + 8 <= b.len() {
        index += 1;
        let label = format!("variable #{index}");
        // Zero padding at the end of a file is not an element.
        if b[at..at + 8].iter().all(|&x| x == 0) {
            at += 8;
            continue;
        }
        let e = match element(cx, b, at, &label) {
            Ok(e) => e,
            Err(e) => {
                cx.warn.push("truncated", Place::file(cx.file), format!("{e}: the rest of the file ignored"));
                break;
            }
        };
        at = e.next;
        let parsed = match e.ty {
            ty::MATRIX => matrix(cx, e.data, 0, &label),
            ty::COMPRESSED => inflate(cx, e.data, &label).and_then(|raw| {
                let inner = element(cx, &raw, 0, &label)?;
                if inner.ty != ty::MATRIX {
                    return Err(cx.err(&label, format!("compressed element holds type {}, not a matrix", inner.ty)));
                }
                matrix(cx, inner.data, 0, &label)
            }),
            other => {
                cx.warn.push(
                    "element",
                    Place::file(cx.file),
                    format!("{label}: data element of type {other} at top level skipped"),
                );
                continue;
            }
        };
        match parsed {
            Ok(v) => vars.push(v),
            Err(e) => cx.warn.push("variable", Place::file(cx.file), format!("{e}: variable skipped")),
        }
    }
    Ok(vars)
}

/// Variables of a Level 4 file (numeric and text matrices, no header).
fn level4(cx: &mut Ctx, b: &[u8]) -> Result<Vec<(String, Value)>, ReadError> {
    let mut vars = Vec::new();
    let mut at = 0usize;
    while at < b.len() {
        let hdr = |be: bool, k: usize| -> Option<i32> {
            let x: [u8; 4] = b.get(at + 4 * k..at + 4 * k + 4)?.try_into().ok()?;
            Some(if be { i32::from_be_bytes(x) } else { i32::from_le_bytes(x) })
        };
        let bad = || cx.err("", format!("not a MATLAB Level 4 matrix header at byte {at}"));
        let mopt_le = hdr(false, 0).ok_or_else(bad)?;
        let be = !(0..=52).contains(&mopt_le);
        let mopt = hdr(be, 0).ok_or_else(bad)?;
        let (m, o, p, t) = (mopt / 1000, (mopt / 100) % 10, (mopt / 10) % 10, mopt % 10);
        if !(0..=1).contains(&m) || o != 0 || !(0..=5).contains(&p) || !(0..=2).contains(&t) {
            return Err(bad());
        }
        let (rows, cols, imagf, namlen) = (
            hdr(be, 1).ok_or_else(bad)?,
            hdr(be, 2).ok_or_else(bad)?,
            hdr(be, 3).ok_or_else(bad)?,
            hdr(be, 4).ok_or_else(bad)?,
        );
        if rows < 0 || cols < 0 || !(0..=1).contains(&imagf) || !(1..=4096).contains(&namlen) {
            return Err(bad());
        }
        let name_at = at + 20;
        let name_b = b.get(name_at..name_at + namlen as usize).ok_or_else(bad)?;
        let name = String::from_utf8_lossy(name_b).trim_end_matches('\0').to_owned();
        let size = [8usize, 4, 4, 2, 2, 1][p as usize];
        let dims = vec![rows as usize, cols as usize];
        let count = product(cx, &dims, &name)?;
        let nbytes = count.checked_mul(size).and_then(|x| x.checked_mul(1 + imagf as usize));
        let data_at = name_at + namlen as usize;
        let data = nbytes.and_then(|n| b.get(data_at..data_at + n)).ok_or_else(|| {
            cx.err(&name, format!("{} matrix of {}-byte values does not fit in the file", dims_text(&dims), size))
        })?;
        let tyc = [ty::DOUBLE, ty::SINGLE, ty::INT32, ty::INT16, ty::UINT16, ty::UINT8][p as usize];
        let cxe = Ctx { file: cx.file, be: m == 1, warn: Warnings::default() };
        let values = numbers(&cxe, &Element { ty: tyc, data: &data[..count * size], next: 0 }, &name)?;
        at = data_at + data.len();
        let value = match t {
            0 => Value::Numeric { dims: dims.clone(), values, complex: imagf == 1 },
            1 => {
                let text: String = values.iter().map(|&c| char::from_u32(c as u32).unwrap_or('\u{fffd}')).collect();
                Value::Char { text: char_rows(&text, &dims) }
            }
            _ => Value::Other { class: 5 },
        };
        vars.push((name, value));
    }
    Ok(vars)
}

/// Reads a `.mat` file.
pub fn read_mat(path: &Path) -> Result<MatFile, ReadError> {
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_owned(), source })?;
    parse_mat(&bytes, &path.display().to_string())
}

const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

/// Parses the bytes of a `.mat` file; `file` names it in messages.
pub fn parse_mat(b: &[u8], file: &str) -> Result<MatFile, ReadError> {
    let mut cx = Ctx { file, be: false, warn: Warnings::default() };
    let is_hdf5 =
        b.starts_with(HDF5_SIGNATURE) || b.get(512..520) == Some(HDF5_SIGNATURE) || b.starts_with(b"MATLAB 7.3");
    if is_hdf5 {
        return Err(ReadError::at(
            Place::file(file),
            "a MATLAB v7.3 (HDF5) file: not supported; re-save it in MATLAB with `save(name, '-v7')` (or `-v6`)",
        ));
    }
    let (vars, format) = match b.get(126..128) {
        Some(e) if e == b"IM" || e == b"MI" => {
            cx.be = e == b"MI";
            let version =
                if cx.be { u16::from_be_bytes([b[124], b[125]]) } else { u16::from_le_bytes([b[124], b[125]]) };
            if version != 0x0100 {
                cx.warn.push(
                    "version",
                    Place::file(file),
                    format!("header version {version:#06x}, expected 0x0100: read as Level 5"),
                );
            }
            let text = String::from_utf8_lossy(&b[..116]).trim_end_matches(['\0', ' ']).to_owned();
            let fmt = format!(
                "MATLAB Level 5 ({}-endian){}",
                if cx.be { "big" } else { "little" },
                text.split(',')
                    .next()
                    .filter(|s| s.starts_with("MATLAB"))
                    .map(|s| format!(": {s}"))
                    .unwrap_or_default()
            );
            (level5(&mut cx, b)?, fmt)
        }
        _ => match level4(&mut cx, b) {
            Ok(v) if !v.is_empty() => (v, "MATLAB Level 4".to_owned()),
            _ => {
                return Err(ReadError::at(
                    Place::file(file),
                    "not a MATLAB .mat file: no Level 5 header (`MATLAB 5.0 MAT-file`, endian mark at byte 126) and no Level 4 matrix",
                ));
            }
        },
    };
    let (table, layout) = tabulate(&mut cx, vars)?;
    Ok(MatFile { table, layout, format, warnings: cx.warn.finish(file) })
}

fn is_vector(dims: &[usize]) -> bool {
    dims.iter().filter(|&&d| d != 1).count() <= 1
}

/// The variables → a table: the numeric vectors of the layout holding the most channels, all of
/// one length; `tireid` / `testid` from wherever they are.
fn tabulate(cx: &mut Ctx, vars: Vec<(String, Value)>) -> Result<(ChannelTable, String), ReadError> {
    let file = cx.file.to_owned();
    let mut table = ChannelTable { source: file.clone(), ..Default::default() };
    let unit_list = vars.iter().find_map(|(name, v)| unit_list_of(v).map(|l| (name.clone(), l)));
    // Candidate layouts: the top level, and each 1×1 struct variable.
    let mut layouts: Vec<(String, Vec<(String, Value)>)> = vec![("top-level variables".into(), Vec::new())];
    for (name, v) in vars {
        match v {
            Value::Struct { dims, fields } if dims.iter().product::<usize>() == 1 => {
                let fl: Vec<(String, Value)> =
                    fields.into_iter().filter_map(|(n, mut vs)| vs.pop().map(|v| (n, v))).collect();
                layouts.push((format!("struct variable `{name}`"), fl));
            }
            v => layouts[0].1.push((name, v)),
        }
    }
    // Ids first, from any layout.
    for (_, vs) in &layouts {
        for (n, v) in vs {
            if let Value::Char { text } = v {
                if n.eq_ignore_ascii_case("tireid") || n.eq_ignore_ascii_case("tyreid") {
                    table.tire_id.get_or_insert_with(|| text.trim().to_owned());
                } else if n.eq_ignore_ascii_case("testid") {
                    table.test_id.get_or_insert_with(|| text.trim().to_owned());
                }
            }
        }
    }
    let known = |vs: &Vec<(String, Value)>| {
        vs.iter()
            .filter(|(n, v)| role_of(n).is_some() && matches!(v, Value::Numeric { dims, .. } if is_vector(dims)))
            .count()
    };
    let best = (0..layouts.len()).max_by_key(|&i| (known(&layouts[i].1), usize::MAX - i)).unwrap_or(0);
    if known(&layouts[best].1) == 0 {
        return Err(ReadError::at(
            Place::file(&file),
            "no channel vectors found (expected numeric n×1 variables named ET, V, SA, FZ, …, or a struct holding them)",
        ));
    }
    for (i, (lname, vs)) in layouts.iter().enumerate() {
        if i != best && known(vs) > 0 {
            cx.warn.push(
                "layout",
                Place::file(&file),
                format!("{lname} also holds channels: not used (read {})", layouts[best].0),
            );
        }
    }
    let (layout, vs) = layouts.swap_remove(best);
    // Rows: the commonest length of the vectors (longest on a tie).
    let mut lengths: Vec<(usize, usize)> = Vec::new();
    for (_, v) in &vs {
        if let Value::Numeric { dims, values, .. } = v
            && is_vector(dims)
            && values.len() > 1
        {
            match lengths.iter_mut().find(|(l, _)| *l == values.len()) {
                Some((_, c)) => *c += 1,
                None => lengths.push((values.len(), 1)),
            }
        }
    }
    let rows = lengths.iter().max_by_key(|(l, c)| (*c, *l)).map(|(l, _)| *l).unwrap_or(0);
    for (name, v) in vs {
        let place = Place::file(&file).channel(&name);
        match v {
            Value::Numeric { dims, values, complex } if is_vector(&dims) && values.len() == rows => {
                if complex {
                    cx.warn.push("complex", place, "complex values: the real part used");
                }
                table.columns.push(Column { name, unit: String::new(), values });
            }
            Value::Numeric { dims, .. } => {
                let what = if is_vector(&dims) {
                    format!("a vector of {} values, not {rows}", dims.iter().product::<usize>())
                } else {
                    format!("a {} matrix", dims_text(&dims))
                };
                cx.warn.push("skipped variable", place, format!("{what}: not used as a channel"));
            }
            Value::Char { .. }
                if ["tireid", "tyreid", "testid", "source"].iter().any(|k| name.eq_ignore_ascii_case(k)) => {}
            other => cx.warn.push("skipped variable", place, format!("{}: not used", other.describe())),
        }
    }
    let layout = match unit_list {
        Some((holder, list)) => {
            let mut given = 0;
            for c in &mut table.columns {
                if let Some((_, u)) = list.iter().find(|(n, _)| n.trim().eq_ignore_ascii_case(&c.name)) {
                    c.unit = u.trim().to_owned();
                    given += 1;
                }
            }
            format!("{layout}; units of {given} channels from `{holder}`")
        }
        None => layout,
    };
    Ok((table, layout))
}

/// Channel names and their units, where a variable lists them: TTC files carry a 1×1 struct
/// `channel` whose fields `name` and `units` are cell arrays of strings (a struct array with one
/// element per channel is read too). `None` when `v` is no such list.
fn unit_list_of(v: &Value) -> Option<Vec<(String, String)>> {
    let Value::Struct { fields, .. } = v else { return None };
    let field = |keys: &[&str]| {
        fields.iter().find(|(n, _)| keys.iter().any(|k| n.eq_ignore_ascii_case(k))).map(|(_, vs)| vs.as_slice())
    };
    let texts = |vs: &[Value]| -> Option<Vec<String>> {
        let items = match vs {
            [Value::Cell { items, .. }] => items.as_slice(),
            many => many,
        };
        items
            .iter()
            .map(|i| match i {
                Value::Char { text } => Some(text.clone()),
                Value::Empty => Some(String::new()),
                _ => None,
            })
            .collect()
    };
    let names = texts(field(&["name", "names"])?)?;
    let units = texts(field(&["units", "unit"])?)?;
    (names.len() == units.len() && !names.is_empty()).then(|| names.into_iter().zip(units).collect())
}
