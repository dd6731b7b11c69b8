//! Assembling received bytes into bounded lines.

use heapless::Vec;

use super::command::{parse, Command, ParseError};
use super::MAX_LINE;

/// One received line, without its terminator (at most [`MAX_LINE`] bytes).
#[derive(Clone, PartialEq, Eq, Debug, Default)]
pub struct Line(Vec<u8, MAX_LINE>);

impl Line {
    /// A line from bytes; `None` if longer than [`MAX_LINE`].
    pub fn from_bytes(bytes: &[u8]) -> Option<Line> {
        Vec::from_slice(bytes).ok().map(Line)
    }
    pub fn as_bytes(&self) -> &[u8] {
        &self.0
    }
    /// [`parse`] of this line.
    pub fn parse(&self) -> Result<Command, ParseError> {
        parse(&self.0)
    }
}

/// Collects bytes from the UART into lines. A line ends at `\n`; `\r` is
/// dropped wherever it appears (so `\r\n` ends a line once, and a terminal
/// must send `\n` or `\r\n`: e.g. `picocom --omap crlf`). A line longer than
/// [`MAX_LINE`] is dropped and reported once, as [`ParseError::TooLong`] at
/// its terminator; the next line starts clean (resync).
#[derive(Clone, Debug, Default)]
pub struct LineBuffer {
    buf: Vec<u8, MAX_LINE>,
    overflowed: bool,
}

impl LineBuffer {
    pub const fn new() -> Self {
        LineBuffer { buf: Vec::new(), overflowed: false }
    }

    /// Takes one received byte; returns a finished line (or its error) at `\n`.
    pub fn push(&mut self, byte: u8) -> Option<Result<Line, ParseError>> {
        match byte {
            b'\r' => None,
            b'\n' => {
                let line = core::mem::take(&mut self.buf);
                if core::mem::replace(&mut self.overflowed, false) {
                    Some(Err(ParseError::TooLong))
                } else {
                    Some(Ok(Line(line)))
                }
            }
            _ => {
                if !self.overflowed && self.buf.push(byte).is_err() {
                    self.overflowed = true;
                    self.buf.clear();
                }
                None
            }
        }
    }

    /// Drops a partial line (e.g. after a UART framing error).
    pub fn clear(&mut self) {
        self.buf.clear();
        self.overflowed = false;
    }

    /// Bytes of the partial line held so far (0 while discarding an over-long one).
    pub fn len(&self) -> usize {
        self.buf.len()
    }
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }
}
