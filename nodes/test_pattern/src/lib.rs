//! test_pattern: a test card for rig integrations — publishes every suite topic with
//! deterministic content in which every field differs, so any tool (a DDS peer, an MCAP reader,
//! a control-room bridge) can check it decodes every field of every type correctly.
//!
//! Topics: publishes every [`node_runtime::SuiteTopic`] (or the configured subset).
//!
//! ## The pattern
//! Message number `n` of a topic is filled depth-first over its fields in `.msg` order, with a
//! leaf counter `k` starting at 0 and advancing by one per leaf:
//! - floating point: `n + k/8` (exact in binary);
//! - integers (incl. `byte`): `(n + k) mod 2^(bits-1)` for signed, `mod 2^bits` for unsigned;
//! - `bool`: `(n + k)` is odd;
//! - `string`: `"{n}:{k}:ü"` (one non-ASCII character, to prove UTF-8 survives);
//! - unbounded array: length `(n + k) mod 3` (consuming one `k`), then its elements.
//!
//! Every suite message starts with a stamp whose `sec` is the first leaf, so `n` can be read
//! back from any message as `stamp.sec`.

pub mod pattern;
pub mod shell;

pub use pattern::pattern_message;
pub use shell::{TestPatternConfig, run};
