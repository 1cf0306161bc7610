//! How a command fails, for a person and for a program: the message on standard error, under
//! `--json` one object `{"error": {"kind": KIND, "message": TEXT}}` on standard output, and the
//! exit status.
//!
//! | status | `kind` | when |
//! | --- | --- | --- |
//! | 0 | | done |
//! | 1 | `bad_input` | a file missing, unreadable or not what it should be; anything not below |
//! | 2 | `usage` | a flag or argument wrong or missing |
//! | 3 | `nothing_found` | the input held no swing to score |
//!
//! A command that found nothing may still have its usual output (a replay's counters): it is
//! printed as on success, and only the status says that nothing was found.

use serde_json::{json, Value};
use std::fmt;

/// A flag or argument a command cannot take: the message says which and what it takes.
#[derive(Debug)]
pub struct Usage(pub String);

impl fmt::Display for Usage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// The input held no swing to score.
#[derive(Debug)]
pub struct NothingFound {
    /// What was looked at and why nothing was found.
    pub message: String,
    /// The command's usual output all the same (empty for none).
    pub output: String,
}

impl fmt::Display for NothingFound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for NothingFound {}

/// What kind of failure an error is (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Status 1.
    BadInput,
    /// Status 2.
    Usage,
    /// Status 3.
    NothingFound,
}

impl Kind {
    /// The kind of `error`, from the first error of its chain that is a [`Usage`] or a
    /// [`NothingFound`]; else bad input.
    pub fn of(error: &anyhow::Error) -> Kind {
        for cause in error.chain() {
            if cause.is::<Usage>() {
                return Kind::Usage;
            }
            if cause.is::<NothingFound>() {
                return Kind::NothingFound;
            }
        }
        Kind::BadInput
    }

    /// The name `error.kind` gives under `--json`.
    pub const fn name(self) -> &'static str {
        match self {
            Kind::BadInput => "bad_input",
            Kind::Usage => "usage",
            Kind::NothingFound => "nothing_found",
        }
    }

    /// The exit status.
    pub const fn status(self) -> u8 {
        match self {
            Kind::BadInput => 1,
            Kind::Usage => 2,
            Kind::NothingFound => 3,
        }
    }
}

/// `{"error": {"kind", "message"}}` for a failure of `kind` saying `message`.
pub fn to_json(kind: Kind, message: &str) -> Value {
    json!({"error": {"kind": kind.name(), "message": message}})
}

/// The output `error` carries, if it is a [`NothingFound`] with one.
pub fn output(error: &anyhow::Error) -> Option<&str> {
    error
        .chain()
        .find_map(|c| c.downcast_ref::<NothingFound>())
        .map(|n| n.output.as_str())
        .filter(|o| !o.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    #[test]
    fn the_kind_is_found_under_context() {
        let usage: anyhow::Result<()> =
            Err(Usage("--report takes .html or .json".into())).context("scoring");
        assert_eq!(Kind::of(&usage.unwrap_err()), Kind::Usage);
        let nothing = anyhow::Error::new(NothingFound {
            message: "no swing".into(),
            output: "counters\n".into(),
        })
        .context("replaying x.pclog");
        assert_eq!(Kind::of(&nothing), Kind::NothingFound);
        assert_eq!(output(&nothing), Some("counters\n"));
        let missing = anyhow::anyhow!("x.csv: No such file or directory");
        assert_eq!(Kind::of(&missing), Kind::BadInput);
        assert_eq!(output(&missing), None);
        assert_eq!(
            [Kind::BadInput, Kind::Usage, Kind::NothingFound].map(Kind::status),
            [1, 2, 3]
        );
    }
}
