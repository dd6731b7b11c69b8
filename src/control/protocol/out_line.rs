//! [`OutLine`]: the buffer the control loop builds its output lines in.

use super::number::TextOut;
use super::Overflow;

/// A bounded line of ASCII text: a byte array and a length. The control
/// loop builds every output line in one (a `heapless::String` works too,
/// see [`TextOut`], but its safe API appends one byte at a time with the
/// length stored after each: three times the instructions per byte on the
/// lx106). Anything not ASCII is stored as `?`, so the text is always valid
/// UTF-8 (and one line: the protocol writes no control bytes).
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct OutLine<const N: usize> {
    buf: [u8; N],
    /// Bytes used, `<= N`.
    len: usize,
}

impl<const N: usize> Default for OutLine<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> OutLine<N> {
    pub const fn new() -> Self {
        OutLine { buf: [0; N], len: 0 }
    }
    pub fn clear(&mut self) {
        self.len = 0;
    }
    pub fn len(&self) -> usize {
        self.len
    }
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }
    /// The text. Every byte is ASCII (`put_byte` and `put_ascii`, the only
    /// writers of `buf`, store anything else as `?`), so it is valid UTF-8
    /// and the empty fallback is never taken.
    pub fn as_str(&self) -> &str {
        core::str::from_utf8(self.as_bytes()).unwrap_or("")
    }
}

impl<const N: usize> core::ops::Deref for OutLine<N> {
    type Target = str;
    fn deref(&self) -> &str {
        self.as_str()
    }
}

impl<const N: usize> TextOut for OutLine<N> {
    /// Appends `s` byte by byte (a non-ASCII byte is stored as `?`).
    fn put_str(&mut self, s: &str) -> Result<(), Overflow> {
        self.put_ascii(s.as_bytes())
    }
    fn put_byte(&mut self, b: u8) -> Result<(), Overflow> {
        let slot = self.buf.get_mut(self.len).ok_or(Overflow)?;
        *slot = if b.is_ascii() { b } else { b'?' };
        self.len = self.len.saturating_add(1); // < N before
        Ok(())
    }
    fn put_ascii(&mut self, bytes: &[u8]) -> Result<(), Overflow> {
        let free = self.buf.get_mut(self.len..).unwrap_or(&mut []);
        let n = bytes.len().min(free.len());
        for (d, &s) in free.iter_mut().zip(bytes) {
            *d = if s.is_ascii() { s } else { b'?' };
        }
        self.len = self.len.saturating_add(n); // n <= N - len
        if n == bytes.len() {
            Ok(())
        } else {
            Err(Overflow)
        }
    }
}
