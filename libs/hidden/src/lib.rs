//! hidden: known effects hidden in recorded virtual-rig logs, for judging a diagnosis.
//!
//! The doctor (`libs/doctor`) names effects a model is missing. To measure how often it names
//! the right one, effects must be hidden in logs with their truth known — and with forms the
//! doctor's candidates do not share, or the benchmark only tests that a form recognises itself.
//! This crate draws such effects ([`HiddenEffect::draw`]: thermal on a lagged bulk temperature
//! with an asymmetric friction optimum, wear with grip, stiffness, shape and radius, break-in
//! recovering by a power law or in two stages) and injects them into an MCAP log of the virtual
//! rig ([`inject`], [`inject_logs`]) physically consistently: the change is the run's true tyre
//! with the effect minus the same tyre without it, at the log's measured inputs, added to FX,
//! FYW and MZW; the radius change goes into DSTWOWHC. The [`InjectionReport`] says what was
//! injected and how big it is in the rig's noise; [`score`] scores a diagnosis against it.
//! See `docs/doctor-benchmark.md`.

pub mod effect;
pub mod factors;
mod inject;
pub mod report;
pub mod resolve;
pub mod score;
pub mod series;

use std::path::PathBuf;

pub use effect::{BreakInEffect, EffectKind, GripCurve, HiddenEffect, Recovery, ThermalEffect, WearEffect};
pub use inject::{inject, inject_logs};
pub use report::{ChangeSize, EffectReport, InjectionReport, LogReport, PerChannel};

/// Why an injection failed. Names the file.
#[derive(Debug, thiserror::Error)]
pub enum InjectError {
    /// A log could not be read.
    #[error("{path}: cannot read: {source}")]
    Read {
        /// The log.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A log is damaged or has no RigSamples.
    #[error("{path}: {detail}")]
    Log {
        /// The log.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
    /// A message did not decode.
    #[error("{path}: topic {topic:?}, message {index}: {source}")]
    Decode {
        /// The log.
        path: PathBuf,
        /// Its topic.
        topic: String,
        /// Its index on the topic.
        index: usize,
        /// The cause.
        #[source]
        source: Box<mcaplog::codec::CodecError>,
    },
    /// A changed RigSample did not encode.
    #[error("{path}: topic {topic:?}, message {index}: cannot encode the injected sample: {source}")]
    Encode {
        /// The log being written.
        path: PathBuf,
        /// Its topic.
        topic: String,
        /// Its index on the topic.
        index: usize,
        /// The cause.
        #[source]
        source: Box<mcaplog::codec::CodecError>,
    },
    /// The output log could not be written.
    #[error(transparent)]
    Write(#[from] mcaplog::LogWriteError),
    /// The output would overwrite its input.
    #[error("{path}: refusing to overwrite the input log; choose another output path")]
    SamePath {
        /// The input.
        path: PathBuf,
    },
}
