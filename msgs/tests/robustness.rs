//! Hostile input must give errors, never panics: random and mutated CDR payloads, and mutated
//! `.msg` text. A small fixed-seed generator keeps the runs reproducible without extra crates.

use tyre_msgs::cdr::{from_cdr_with_header, to_cdr_with_header};
use tyre_msgs::diagnostic_msgs::DiagnosticArray;
use tyre_msgs::introspect::exemplar;
use tyre_msgs::msgdef::parse_msg;
use tyre_msgs::schema::DEFINITIONS;
use tyre_msgs::{QualityReport, RigSample};

/// xorshift64*: deterministic, good enough to scatter bytes.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

#[test]
fn mutated_cdr_payloads_never_panic() {
    let mut rng = Rng(0x7157_0e1d);
    let seeds = [
        to_cdr_with_header(&exemplar::<QualityReport>(3).unwrap()).unwrap(),
        to_cdr_with_header(&exemplar::<DiagnosticArray>(2).unwrap()).unwrap(),
        to_cdr_with_header(&exemplar::<RigSample>(1).unwrap()).unwrap(),
    ];
    for round in 0..3000 {
        let mut bytes = seeds[round % seeds.len()].clone();
        for _ in 0..1 + rng.below(4) {
            let i = rng.below(bytes.len());
            // Often hit length fields with huge values, the classic way to make decoders allocate.
            bytes[i] = if rng.below(2) == 0 { 0xff } else { rng.next() as u8 };
        }
        if rng.below(4) == 0 {
            bytes.truncate(rng.below(bytes.len()));
        }
        let _ = from_cdr_with_header::<QualityReport>(&bytes);
        let _ = from_cdr_with_header::<DiagnosticArray>(&bytes);
        let _ = from_cdr_with_header::<RigSample>(&bytes);
    }
}

#[test]
fn random_bytes_never_panic() {
    let mut rng = Rng(42);
    for _ in 0..2000 {
        let len = rng.below(64);
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
        if bytes.len() >= 2 {
            bytes[0] = 0;
            bytes[1] = 1;
        }
        let _ = from_cdr_with_header::<QualityReport>(&bytes);
    }
}

#[test]
fn mutated_msg_text_never_panics() {
    let mut rng = Rng(7);
    let inserts = ["[", "]", "<=", "=", "#", "\"", "'", "/", "é", "🛞", " ", "\n", "[<=", "\\"];
    for round in 0..3000 {
        let def = &DEFINITIONS[round % DEFINITIONS.len()];
        let mut text: Vec<char> = def.text.chars().collect();
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(text.len() + 1);
            match rng.below(3) {
                0 if !text.is_empty() && at < text.len() => {
                    text.remove(at);
                }
                _ => {
                    let s = inserts[rng.below(inserts.len())];
                    for (k, c) in s.chars().enumerate() {
                        text.insert(at + k, c);
                    }
                }
            }
        }
        let text: String = text.into_iter().collect();
        if let Err(e) = parse_msg(def.package, def.name, def.path, &text) {
            // Errors must point into the file.
            assert!(e.line >= 1 && e.line <= text.lines().count(), "{e}");
        }
    }
}
