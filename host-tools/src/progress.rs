//! A progress line on standard error for the long `learn` commands (training, evaluation,
//! calibration): position and length, elapsed time, time left and a message, redrawn in place
//! at most ten times a second on a terminal, and silent elsewhere (a log then gets the
//! commands' own periodic lines).
//!
//! Written here rather than taken from `indicatif`: that crate turns on features of
//! `portable-atomic` that burn also depends on, so a build with `learn` recompiled the whole
//! burn stack that the same workspace had already built without it (six minutes of CI).

use std::cell::{Cell, RefCell};
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Least time between two redraws.
const REDRAW: Duration = Duration::from_millis(100);

/// One progress line; every method takes `&self`, so a callback can move it.
pub struct Progress {
    unit: &'static str,
    len: Cell<u64>,
    pos: Cell<u64>,
    first: Cell<u64>,
    message: RefCell<String>,
    start: Instant,
    drawn: Cell<Option<Instant>>,
    shown: bool,
}

impl Progress {
    /// A line counting `len` `unit`s, from 0.
    pub fn new(len: u64, unit: &'static str) -> Progress {
        Progress {
            unit,
            len: Cell::new(len),
            pos: Cell::new(0),
            first: Cell::new(0),
            message: RefCell::new(String::new()),
            start: Instant::now(),
            drawn: Cell::new(None),
            shown: std::io::stderr().is_terminal(),
        }
    }

    /// The same line starting at `pos` (a resumed run): time left counts from there.
    pub fn at(self, pos: u64) -> Progress {
        self.pos.set(pos);
        self.first.set(pos);
        self
    }

    /// Whether nothing is drawn (standard error is not a terminal).
    pub fn is_hidden(&self) -> bool {
        !self.shown
    }

    /// Sets the length.
    pub fn set_length(&self, len: u64) {
        self.len.set(len);
        self.draw(false);
    }

    /// Sets the position.
    pub fn set_position(&self, pos: u64) {
        self.pos.set(pos);
        self.draw(false);
    }

    /// One more done.
    pub fn inc(&self) {
        self.pos.set(self.pos.get() + 1);
        self.draw(false);
    }

    /// Sets the text after the counts.
    pub fn set_message(&self, message: impl Into<String>) {
        *self.message.borrow_mut() = message.into();
        self.draw(true);
    }

    /// Prints `line` above the progress line (or alone, when hidden).
    pub fn println(&self, line: &str) {
        if self.shown {
            eprint!("\r\x1b[2K{line}\n");
            self.draw(true);
        } else {
            eprintln!("{line}");
        }
    }

    /// Clears the line.
    pub fn finish_and_clear(&self) {
        if self.shown {
            eprint!("\r\x1b[2K");
            let _ = std::io::stderr().flush();
        }
    }

    fn draw(&self, now: bool) {
        let at = Instant::now();
        if !self.shown || !(now || self.drawn.get().is_none_or(|t| at - t >= REDRAW)) {
            return;
        }
        self.drawn.set(Some(at));
        let (len, pos) = (self.len.get(), self.pos.get());
        let elapsed = self.start.elapsed().as_secs_f64();
        let done = pos.saturating_sub(self.first.get());
        let left = match done {
            0 => 0.0,
            _ => elapsed / done as f64 * len.saturating_sub(pos) as f64,
        };
        eprint!(
            "\r\x1b[2K{pos}/{len} {} {} (left {}) {}",
            self.unit,
            clock(elapsed),
            clock(left),
            self.message.borrow()
        );
        let _ = std::io::stderr().flush();
    }
}

/// `seconds` as hours:minutes:seconds.
fn clock(seconds: f64) -> String {
    let s = seconds as u64;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clocks_read_as_hours_minutes_seconds() {
        assert_eq!(clock(0.0), "00:00:00");
        assert_eq!(clock(3725.9), "01:02:05");
    }
}
