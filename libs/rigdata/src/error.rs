//! Errors and warnings of the readers: every one names the file and, where it applies, the line
//! (or row) and the channel, so a person can find the spot in the file.

use std::fmt;
use std::path::PathBuf;

use serde::Serialize;

/// Where in a file something was found.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize)]
pub struct Place {
    /// File (as given).
    pub file: String,
    /// 1-based line of a text file, or 1-based row of a `.mat` variable; `None` = whole file.
    pub line: Option<usize>,
    /// Channel (or `.mat` variable) concerned.
    pub channel: Option<String>,
}

impl Place {
    /// The whole file.
    pub fn file(file: &str) -> Self {
        Place { file: file.to_owned(), line: None, channel: None }
    }

    /// A line of the file.
    pub fn line(file: &str, line: usize) -> Self {
        Place { file: file.to_owned(), line: Some(line), channel: None }
    }

    /// The same place, about a channel.
    pub fn channel(mut self, channel: &str) -> Self {
        self.channel = Some(channel.to_owned());
        self
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        if let Some(c) = &self.channel {
            write!(f, ": channel {c}")?;
        }
        Ok(())
    }
}

/// Why a file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The content is not what the format allows (or not something the reader can use).
    #[error("{place}: {message}")]
    Format {
        /// Where.
        place: Place,
        /// What was found and what was expected.
        message: String,
    },
}

impl ReadError {
    /// A format error at `place`.
    pub fn at(place: Place, message: impl Into<String>) -> Self {
        ReadError::Format { place, message: message.into() }
    }
}

/// Something odd the reader coped with; the engineer should know.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// Where.
    pub place: Place,
    /// What was found and what the reader did about it.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.place, self.message)
    }
}

/// Collects warnings, keeping the first few of each kind and counting the rest, so a file with
/// 20,000 odd lines gives five examples and a count, not 20,000 lines of output.
#[derive(Debug, Clone, Default)]
pub struct Warnings {
    list: Vec<Warning>,
    kinds: Vec<(&'static str, usize)>,
}

/// Examples kept per kind of warning.
const EXAMPLES_PER_KIND: usize = 5;

impl Warnings {
    /// Adds a warning of `kind` (a short key such as `"blank line"`).
    pub fn push(&mut self, kind: &'static str, place: Place, message: impl Into<String>) {
        let n = match self.kinds.iter_mut().find(|(k, _)| *k == kind) {
            Some((_, n)) => {
                *n += 1;
                *n
            }
            None => {
                self.kinds.push((kind, 1));
                1
            }
        };
        if n <= EXAMPLES_PER_KIND {
            self.list.push(Warning { place, message: message.into() });
        }
    }

    /// The warnings, with one summary line per kind that had more than the examples kept.
    pub fn finish(self, file: &str) -> Vec<Warning> {
        let mut out = self.list;
        for (kind, n) in self.kinds {
            if n > EXAMPLES_PER_KIND {
                out.push(Warning {
                    place: Place::file(file),
                    message: format!("{} more of the same ({kind}; {n} in all)", n - EXAMPLES_PER_KIND),
                });
            }
        }
        out
    }

    /// Number of warnings pushed (all kinds, including those not kept).
    pub fn count(&self) -> usize {
        self.kinds.iter().map(|(_, n)| n).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warnings_keep_examples_and_count_the_rest() {
        let mut w = Warnings::default();
        for i in 0..8 {
            w.push("blank line", Place::line("a.dat", i + 4), "blank line skipped");
        }
        w.push("unit", Place::file("a.dat").channel("P"), "guessed");
        assert_eq!(w.count(), 9);
        let out = w.finish("a.dat");
        assert_eq!(out.len(), 7);
        assert_eq!(out[0].to_string(), "a.dat:4: blank line skipped");
        assert_eq!(out[5].to_string(), "a.dat: channel P: guessed");
        assert!(out[6].message.starts_with("3 more of the same (blank line; 8 in all)"));
    }
}
