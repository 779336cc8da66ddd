//! parser_fuzz: property-based fuzzing of the suite's parsers of user input, on stable Rust.
//!
//! [`fuzz`] takes seed inputs (real files of the kind the parser reads), mutates them the ways
//! files go wrong — flipped bytes, cut-off tails, deleted or repeated ranges, hostile tokens
//! (`NaN`, `1e308`, `18446744073709551616`, stray brackets and quotes) spliced in — and calls the
//! parser on each result with a fixed case budget (proptest, deterministic seed, so CI is
//! repeatable). A parser passes when every input gives a value or an error with a message; a
//! panic fails the case (proptest shrinks it to a small input and prints it). Memory is capped
//! for the whole test process ([`cap_memory`]): a parser that believes a length field and
//! allocates without bound aborts the run instead of passing.
//!
//! Adding a parser is one call in `tests/parsers.rs`:
//! `fuzz("name", seeds, CASES, |bytes| parse(bytes).map(|_| ()).map_err(|e| e.to_string()))`.

use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, RngAlgorithm, TestRng, TestRunner};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicU64, Ordering};

/// Tokens that break parsers: non-finite and extreme numbers, integer overflows, structure
/// characters, control and multi-byte characters.
pub const HOSTILE_TOKENS: &[&str] = &[
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "-0",
    "0",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775808",
    "4294967296",
    "-1",
    "\"",
    "'",
    "[",
    "]",
    "{",
    "}",
    "=",
    "\n",
    "\r\n",
    "\t",
    "\0",
    "é",
    "#",
    ",",
    "$",
    "[[",
    "]]",
    "\"\"\"",
    "999999999999",
];

/// One way to damage an input. Positions are [`proptest::sample::Index`]es, resolved against the
/// input's length when applied.
#[derive(Debug, Clone)]
pub enum Mutation {
    FlipBit(prop::sample::Index, u8),
    SetByte(prop::sample::Index, u8),
    Insert(prop::sample::Index, Vec<u8>),
    Token(prop::sample::Index, &'static str),
    Delete(prop::sample::Index, usize),
    Repeat(prop::sample::Index, usize, u8),
    Truncate(prop::sample::Index),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let idx = any::<prop::sample::Index>;
    prop_oneof![
        (idx(), 0u8..8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        (idx(), any::<u8>()).prop_map(|(i, b)| Mutation::SetByte(i, b)),
        (idx(), prop::collection::vec(any::<u8>(), 1..16)).prop_map(|(i, v)| Mutation::Insert(i, v)),
        (idx(), prop::sample::select(HOSTILE_TOKENS)).prop_map(|(i, t)| Mutation::Token(i, t)),
        (idx(), 1usize..64).prop_map(|(i, n)| Mutation::Delete(i, n)),
        (idx(), 1usize..64, 1u8..8).prop_map(|(i, n, k)| Mutation::Repeat(i, n, k)),
        idx().prop_map(Mutation::Truncate),
    ]
}

/// Applies `m` to `data`.
pub fn apply(data: &mut Vec<u8>, m: &Mutation) {
    let at = |i: &prop::sample::Index, len: usize| if len == 0 { 0 } else { i.index(len + 1) };
    match m {
        Mutation::FlipBit(i, b) if !data.is_empty() => {
            let p = i.index(data.len());
            data[p] ^= 1 << b;
        }
        Mutation::SetByte(i, v) if !data.is_empty() => {
            let p = i.index(data.len());
            data[p] = *v;
        }
        Mutation::Insert(i, v) => {
            let p = at(i, data.len());
            data.splice(p..p, v.iter().copied());
        }
        Mutation::Token(i, t) => {
            let p = at(i, data.len());
            data.splice(p..p, t.bytes());
        }
        Mutation::Delete(i, n) if !data.is_empty() => {
            let p = i.index(data.len());
            let end = (p + n).min(data.len());
            data.drain(p..end);
        }
        Mutation::Repeat(i, n, k) if !data.is_empty() => {
            let p = i.index(data.len());
            let end = (p + n).min(data.len());
            let piece = data[p..end].to_vec();
            for _ in 0..*k {
                data.splice(end..end, piece.iter().copied());
            }
        }
        Mutation::Truncate(i) => {
            let p = at(i, data.len());
            data.truncate(p);
        }
        _ => {}
    }
}

/// What a fuzz run did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FuzzStats {
    pub name: String,
    pub cases: u64,
    /// Inputs the parser accepted.
    pub accepted: u64,
    /// Inputs refused with an error message.
    pub refused: u64,
}

/// Caps the address space of this test process at its present size plus `headroom_bytes`, so
/// an unbounded allocation aborts the run (a failure) instead of passing or swapping. Called
/// once by [`fuzz`]; later calls keep the first cap.
pub fn cap_memory(headroom_bytes: u64) {
    static DONE: std::sync::Once = std::sync::Once::new();
    DONE.call_once(|| {
        let vm_bytes = std::fs::read_to_string("/proc/self/status")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("VmSize:"))
                    .and_then(|l| l.split_whitespace().nth(1).and_then(|kb| kb.parse::<u64>().ok()).map(|kb| kb * 1024))
            })
            .unwrap_or(0);
        let limit = rustix::process::Rlimit { current: Some(vm_bytes + headroom_bytes), maximum: None };
        if let Err(e) = rustix::process::setrlimit(rustix::process::Resource::As, limit) {
            eprintln!("parser_fuzz: cannot cap memory ({e}); unbounded allocations go undetected");
        }
    });
}

/// Address space every fuzz target shares beyond what the test process had when fuzzing began.
pub const MEMORY_HEADROOM_BYTES: u64 = 3 << 30;

/// Fuzzes `parse` with `cases` mutated copies of `seeds` (each also tried unmutated first).
/// `parse` returns `Err(message)` for an input it refuses; the message must say something.
/// Panics (failing the test) on the first input that makes `parse` panic or refuse in silence.
pub fn fuzz(name: &str, seeds: Vec<Vec<u8>>, cases: u32, parse: impl Fn(&[u8]) -> Result<(), String>) -> FuzzStats {
    assert!(!seeds.is_empty(), "{name}: no seeds");
    cap_memory(MEMORY_HEADROOM_BYTES);
    for (i, seed) in seeds.iter().enumerate() {
        if let Err(e) = parse(seed) {
            panic!("{name}: seed {i} is refused ({e}); seeds must be valid inputs");
        }
    }
    let accepted = AtomicU64::new(0);
    let refused = AtomicU64::new(0);
    let config = Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        // Shrinking a parser panic can take many steps; the first small example is enough.
        max_shrink_iters: 2000,
        ..Config::default()
    };
    // A fixed seed per target: CI runs the same cases every time.
    let mut rng_seed = [0u8; 32];
    for (i, b) in name.bytes().enumerate() {
        rng_seed[i % 32] ^= b;
    }
    let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &rng_seed));
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..8));
    let result = runner.run(&strategy, |(seed, mutations)| {
        let mut data = seeds[seed].clone();
        for m in &mutations {
            apply(&mut data, m);
        }
        match catch_unwind(AssertUnwindSafe(|| parse(&data))) {
            Ok(Ok(())) => {
                accepted.fetch_add(1, Ordering::Relaxed);
            }
            Ok(Err(msg)) => {
                prop_assert!(!msg.trim().is_empty(), "refused without a message");
                refused.fetch_add(1, Ordering::Relaxed);
            }
            Err(panic) => {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                    .unwrap_or_default();
                let shown = String::from_utf8_lossy(&data[..data.len().min(2000)]).into_owned();
                prop_assert!(false, "{name}: panicked: {what}\ninput ({} bytes): {shown:?}", data.len());
            }
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    let stats = FuzzStats {
        name: name.to_owned(),
        cases: u64::from(cases),
        accepted: accepted.into_inner(),
        refused: refused.into_inner(),
    };
    println!(
        "fuzz {}: {} cases, {} accepted, {} refused with an error, 0 panics",
        name, cases, stats.accepted, stats.refused
    );
    stats
}

/// UTF-8 text of `bytes` for text parsers (invalid sequences replaced, as a reader that reads a
/// file into a `String` would refuse them anyway).
pub fn text(bytes: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::strategy::ValueTree;

    #[test]
    fn a_panicking_parser_is_caught() {
        let r = std::panic::catch_unwind(|| {
            fuzz("demo", vec![b"ok".to_vec()], 64, |b| {
                if b.len() > 3 {
                    panic!("too long");
                }
                Ok(())
            })
        });
        assert!(r.is_err(), "the harness must fail on a parser that panics");
    }

    #[test]
    fn a_silent_refusal_is_caught() {
        let r = std::panic::catch_unwind(|| {
            fuzz("silent", vec![b"ok".to_vec()], 64, |b| if b == b"ok" { Ok(()) } else { Err(String::new()) })
        });
        assert!(r.is_err());
    }

    #[test]
    fn mutations_stay_in_bounds() {
        let mut runner = TestRunner::deterministic();
        for _ in 0..2000 {
            let ms = prop::collection::vec(mutation(), 1..8).new_tree(&mut runner).expect("tree").current();
            let mut d = b"[section]\nkey = 1.0\n".to_vec();
            for m in &ms {
                apply(&mut d, m);
            }
            let mut empty = Vec::new();
            for m in &ms {
                apply(&mut empty, m);
            }
        }
    }
}
