//! A client's bytes cut into lines, in bounded memory, however long a line it sends.

use std::io::{self, Read};

/// Longest line a client may send, bytes (the JSON of the largest message is under 4 KB).
pub const MAX_LINE: usize = 16 * 1024;
/// Bytes read from a socket at a time.
const CHUNK: usize = 4 * 1024;

/// What [`Lines::next`] took.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Line {
    /// A line of at most [`MAX_LINE`] bytes, now in the caller's buffer without its newline.
    Whole,
    /// A longer line: its bytes were dropped as they came.
    TooLong,
}

/// Bytes received and not yet taken as lines: never more than [`MAX_LINE`] and one read.
#[derive(Debug, Default)]
pub struct Lines {
    buf: Vec<u8>,
    /// Bytes at the start of `buf` known to hold no newline.
    scanned: usize,
    /// Within a line longer than [`MAX_LINE`], dropped up to its newline.
    skipping: bool,
    /// Lines taken so far: the number of the last one.
    taken: u64,
}

impl Lines {
    /// Reads once from `from`; the bytes read, 0 at its end.
    ///
    /// # Errors
    /// When reading fails or would block.
    pub fn fill(&mut self, from: &mut impl Read) -> io::Result<usize> {
        let start = self.buf.len();
        self.buf.resize(start + CHUNK, 0);
        let read = from.read(&mut self.buf[start..]);
        self.buf.truncate(start + read.as_ref().map_or(0, |&n| n));
        read
    }

    /// Takes the next complete line into `line` (emptied first): its number and whether it was
    /// whole; `None` until more bytes come.
    pub fn next(&mut self, line: &mut Vec<u8>) -> Option<(u64, Line)> {
        line.clear();
        let Some(at) = self.buf[self.scanned..].iter().position(|&b| b == b'\n') else {
            self.scanned = self.buf.len();
            if self.buf.len() > MAX_LINE {
                self.skipping = true;
                self.clear();
            }
            return None;
        };
        let end = self.scanned + at;
        let kind = match std::mem::take(&mut self.skipping) || end > MAX_LINE {
            true => Line::TooLong,
            false => {
                line.extend_from_slice(&self.buf[..end]);
                Line::Whole
            }
        };
        self.buf.drain(..=end);
        self.scanned = 0;
        self.taken += 1;
        Some((self.taken, kind))
    }

    /// At the end of the stream: its last line if it did not end with a newline.
    pub fn rest(&mut self, line: &mut Vec<u8>) -> Option<(u64, Line)> {
        if self.buf.is_empty() && !self.skipping {
            return None;
        }
        self.buf.push(b'\n');
        self.next(line)
    }

    /// Drops the bytes not yet taken.
    pub fn clear(&mut self) {
        self.buf.clear();
        self.scanned = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every line of `text`, read a chunk at a time, checking the memory held after each.
    fn all(text: &[u8]) -> Vec<(u64, Line, String)> {
        let mut reader = std::io::Cursor::new(text);
        let (mut lines, mut line, mut got) = (Lines::default(), Vec::new(), Vec::new());
        loop {
            while let Some((n, kind)) = lines.next(&mut line) {
                got.push((n, kind, String::from_utf8(line.clone()).unwrap()));
            }
            assert!(lines.buf.capacity() <= 2 * (MAX_LINE + CHUNK));
            if lines.fill(&mut reader).unwrap() == 0 {
                break;
            }
        }
        if let Some((n, kind)) = lines.rest(&mut line) {
            got.push((n, kind, String::from_utf8(line.clone()).unwrap()));
        }
        got
    }

    #[test]
    fn an_endless_line_is_dropped_in_bounded_memory_and_reading_goes_on() {
        let long = "x".repeat(3 * MAX_LINE);
        let got = all(format!("a\n{long}\n\nb").as_bytes());
        let expected = [
            (1, Line::Whole, "a"),
            (2, Line::TooLong, ""),
            (3, Line::Whole, ""),
            (4, Line::Whole, "b"),
        ];
        let expected: Vec<_> = expected
            .iter()
            .map(|&(n, kind, s)| (n, kind, s.to_string()))
            .collect();
        assert_eq!(got, expected);
    }

    #[test]
    fn a_line_of_the_longest_length_is_whole_and_one_more_byte_is_too_long() {
        let longest = "y".repeat(MAX_LINE);
        let got = all(format!("{longest}\n{longest}y\n").as_bytes());
        let kinds: Vec<_> = got.iter().map(|(_, kind, _)| *kind).collect();
        assert_eq!(kinds, [Line::Whole, Line::TooLong]);
        assert_eq!(got[0].2, longest);
    }

    #[test]
    fn an_unended_too_long_line_at_the_end_is_still_named() {
        let got = all("z".repeat(2 * MAX_LINE).as_bytes());
        assert_eq!(got, [(1, Line::TooLong, String::new())]);
    }
}
