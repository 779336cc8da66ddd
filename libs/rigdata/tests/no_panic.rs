//! No input makes a reader panic: corrupted `.dat`, `.mat` and `.tdx` files (truncations, byte
//! flips, huge dimension and byte-count fields, garbage units, NaN rows, swapped lines) each
//! give a clear error or a dataset. Allocation is bounded by the file's size, so a `.mat` that
//! claims a 2^31-element matrix gets an error, not an out-of-memory abort. A fixed case budget
//! keeps CI fast (~10 s in release).

use proptest::prelude::*;
use rigdata::fixture::{FixtureSpec, ttc_run};
use rigdata::import::{FileFormat, ReadOptions, read_bytes};
use rigdata::mat::{MatLayout, MatWriteOptions, to_mat};
use rigdata::table::{DatLayout, to_dat};

fn small_spec() -> FixtureSpec {
    FixtureSpec { pressures_kpa: vec![83.0], loads_n: vec![1100.0, 660.0], sweep_s: 4.0, ..FixtureSpec::cornering() }
}

fn dat_bytes() -> Vec<u8> {
    to_dat(&ttc_run(&small_spec()).table, DatLayout::default()).into_bytes()
}

fn mat_bytes(compress: bool, in_struct: bool) -> Vec<u8> {
    let layout = if in_struct { MatLayout::Struct("run".into()) } else { MatLayout::Variables };
    to_mat(&ttc_run(&small_spec()).table, &MatWriteOptions { compress, layout, ..Default::default() }).unwrap()
}

/// Our TYDEX export, or (`foreign`) the same without the SEGMENT bookkeeping, so the generic
/// path (interpretation and sweep finding) runs.
fn tdx_bytes(foreign: bool) -> Vec<u8> {
    let d = read_bytes(&dat_bytes(), "x.dat", FileFormat::Dat, &ReadOptions::default()).unwrap().0;
    let text = rigdata::tydex::to_tydex(&d, "x");
    if foreign { text.replace("SEGMENT ", "SEGMENX ") } else { text }.into_bytes()
}

/// Reads; any outcome but a panic is fine, and errors must say where.
fn read_any(bytes: &[u8], format: FileFormat) {
    match read_bytes(bytes, "corrupt", format, &ReadOptions::default()) {
        Ok((d, r)) => {
            assert_eq!(d.segments.len(), r.sweeps.len());
            assert!(d.segments.iter().all(|s| s.samples.iter().all(|x| x.fz_n.is_finite())));
        }
        Err(e) => assert!(e.to_string().starts_with("corrupt"), "{e}"),
    }
}

#[derive(Debug, Clone)]
enum Damage {
    Truncate(f64),
    Flip(Vec<(f64, u8)>),
    /// A u32 at a 4-aligned offset set to a huge or odd value (dimension, byte count, type).
    Word(f64, u32),
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        (0.0..1.0f64).prop_map(Damage::Truncate),
        prop::collection::vec((0.0..1.0f64, any::<u8>()), 1..8).prop_map(Damage::Flip),
        (
            0.0..1.0f64,
            prop_oneof![Just(u32::MAX), Just(0x7fff_ffff), Just(0xffff_0000), Just(0x0004_0009), Just(0), any::<u32>()]
        )
            .prop_map(|(at, w)| Damage::Word(at, w)),
    ]
}

fn apply(mut b: Vec<u8>, d: &Damage) -> Vec<u8> {
    let n = b.len();
    match d {
        Damage::Truncate(f) => b.truncate((f * n as f64) as usize),
        Damage::Flip(v) => {
            for (at, x) in v {
                let i = ((at * n as f64) as usize).min(n - 1);
                b[i] ^= x | 1;
            }
        }
        Damage::Word(at, w) => {
            let i = (((at * n as f64) as usize) / 4 * 4).min(n.saturating_sub(4));
            b[i..i + 4].copy_from_slice(&w.to_le_bytes());
        }
    }
    b
}

/// Text damage: lines swapped, a value replaced, a unit replaced.
#[derive(Debug, Clone)]
enum TextDamage {
    Swap(f64, f64),
    Value(f64, f64, &'static str),
    Unit(f64, &'static str),
}

fn text_damage() -> impl Strategy<Value = TextDamage> {
    let words = prop_oneof![Just("NaN"), Just("abc"), Just(""), Just("1e308"), Just("-inf"), Just("\t\t"), Just("€")];
    let units = prop_oneof![Just("furlong"), Just("N"), Just("kPa"), Just(""), Just("degF"), Just("µm")];
    prop_oneof![
        (0.0..1.0f64, 0.0..1.0f64).prop_map(|(a, b)| TextDamage::Swap(a, b)),
        (0.0..1.0f64, 0.0..1.0f64, words).prop_map(|(a, b, w)| TextDamage::Value(a, b, w)),
        (0.0..1.0f64, units).prop_map(|(a, u)| TextDamage::Unit(a, u)),
    ]
}

fn apply_text(text: &str, d: &TextDamage) -> Vec<u8> {
    let mut lines: Vec<String> = text.split('\n').map(str::to_owned).collect();
    let n = lines.len();
    let pick = |f: f64| ((f * n as f64) as usize).min(n - 1);
    match d {
        TextDamage::Swap(a, b) => lines.swap(pick(*a), pick(*b)),
        TextDamage::Value(a, b, w) => {
            let l = pick(*a);
            let mut f: Vec<String> = lines[l].split('\t').map(str::to_owned).collect();
            let k = ((b * f.len() as f64) as usize).min(f.len() - 1);
            f[k] = (*w).to_owned();
            lines[l] = f.join("\t");
        }
        TextDamage::Unit(a, u) => {
            let mut f: Vec<String> = lines[2].split('\t').map(str::to_owned).collect();
            let k = ((a * f.len() as f64) as usize).min(f.len() - 1);
            f[k] = (*u).to_owned();
            lines[2] = f.join("\t");
        }
    }
    lines.join("\n").into_bytes()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn corrupted_mat_never_panics(d in damage(), compress in any::<bool>(), in_struct in any::<bool>()) {
        read_any(&apply(mat_bytes(compress, in_struct), &d), FileFormat::Mat);
    }

    #[test]
    fn corrupted_dat_never_panics(d in damage(), t in text_damage()) {
        let text = String::from_utf8(dat_bytes()).unwrap();
        read_any(&apply_text(&text, &t), FileFormat::Dat);
        read_any(&apply(text.into_bytes(), &d), FileFormat::Dat);
    }

    #[test]
    fn corrupted_tdx_never_panics(d in damage(), t in text_damage(), foreign in any::<bool>()) {
        let text = String::from_utf8(tdx_bytes(foreign)).unwrap();
        read_any(&apply_text(&text, &t), FileFormat::Tdx);
        read_any(&apply(text.into_bytes(), &d), FileFormat::Tdx);
    }

    #[test]
    fn arbitrary_bytes_never_panic(b in prop::collection::vec(any::<u8>(), 0..600)) {
        for f in [FileFormat::Mat, FileFormat::Dat, FileFormat::Tdx] {
            read_any(&b, f);
        }
        // Behind a valid Level 5 header too.
        let mut m = mat_bytes(false, false)[..128].to_vec();
        m.extend_from_slice(&b);
        read_any(&m, FileFormat::Mat);
    }
}

#[test]
fn huge_dimensions_are_an_error_not_an_allocation() {
    // One uncompressed variable with its dimensions set to 2^31-1 × 2^31-1.
    let b = mat_bytes(false, false);
    // Layout after the 128-byte header: tag (8), flags element (16), dims tag (8), dims (8).
    let mut bad = b.clone();
    bad[128 + 8 + 16 + 8..128 + 8 + 16 + 16].copy_from_slice(&[0xff, 0xff, 0xff, 0x7f, 0xff, 0xff, 0xff, 0x7f]);
    let w = rigdata::mat::parse_mat(&bad, "huge.mat").map(|m| m.warnings).unwrap_or_default();
    assert!(w.iter().any(|w| w.message.contains("dimensions")), "{w:?}");
    // And a byte count beyond the file.
    let mut bad = b;
    bad[132..136].copy_from_slice(&u32::MAX.to_le_bytes());
    let m = rigdata::mat::parse_mat(&bad, "count.mat");
    assert!(m.is_err() || m.unwrap().warnings.iter().any(|w| w.message.contains("claims")));
}
