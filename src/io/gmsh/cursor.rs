//! A cursor over the bytes of a gmsh file, shared by the MSH 2.2 and 4.1 readers.
//!
//! MSH files mix ASCII lines (section headers, `$PhysicalNames`, and in 2.2 binary files the
//! record counts) with, in binary files, raw little- or big-endian values. The cursor reads
//! both: the `tok_*` methods always read one whitespace-separated ASCII token, while
//! [`Cursor::int`], [`Cursor::size`] and [`Cursor::float`] read either a token or raw bytes,
//! depending on whether binary data mode is switched on ([`Cursor::set_binary`]).
//!
//! Every read is bounds-checked and reports a [`Error::MeshParse`] naming the current section
//! and, for ASCII files, the 1-based line of the offending token. Nothing here panics on any
//! input. Record counts read from the file are never trusted for allocation: readers reserve
//! at most [`Cursor::cap`] records, what the file's size could hold, so a header claiming
//! 10¹² nodes allocates nothing extra and fails at the end of the file.

use std::path::Path;
use std::str::FromStr;

use crate::Error;

/// How raw values are laid out in the binary sections of a file.
#[derive(Clone, Copy, Debug)]
pub(super) struct BinaryLayout {
    /// True for big-endian files (detected from the `1` written after the header line).
    pub big_endian: bool,
    /// Bytes of a `size_t` (MSH 4.1 `data-size`: 4 or 8).
    pub size_t: usize,
}

/// Reading position in a mesh file.
pub(super) struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    /// 1-based line number at `pos` (meaningful for ASCII files only).
    line: usize,
    /// Line where the last token started, used in error messages.
    tok_line: usize,
    path: &'a Path,
    /// The section being read, for messages (`$Nodes`, ...).
    section: String,
    /// Whether the whole file is binary: then line numbers are meaningless and errors give
    /// the byte offset instead.
    file_binary: bool,
    /// Binary data mode: `Some` while reading the raw part of a binary section.
    bin: Option<BinaryLayout>,
    /// A record count read from the file that the file is too small to hold: a corrupt
    /// header or a truncated file. Mentioned if the file then ends early.
    overclaim: Option<String>,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `data`.
    pub fn new(data: &'a [u8], path: &'a Path) -> Self {
        Cursor {
            data,
            pos: 0,
            line: 1,
            tok_line: 1,
            path,
            section: "$MeshFormat".into(),
            file_binary: false,
            bin: None,
            overclaim: None,
        }
    }

    /// Name the section being read, for messages.
    pub fn set_section(&mut self, name: &str) {
        self.section.clear();
        self.section.push_str(name);
    }

    /// The file's path (for messages).
    pub fn path(&self) -> &'a Path {
        self.path
    }

    /// Mark the file as binary (errors then report byte offsets, not lines).
    pub fn set_file_binary(&mut self, binary: bool) {
        self.file_binary = binary;
    }

    /// Switch binary data mode on (`Some`) or off (`None`) for [`Cursor::int`] & co.
    pub fn set_binary(&mut self, layout: Option<BinaryLayout>) {
        self.bin = layout;
    }

    /// A [`Error::MeshParse`] at the current token.
    pub fn err(&self, msg: impl Into<String>) -> Error {
        let mut msg = msg.into();
        let line = if self.file_binary {
            msg.push_str(&format!(" (byte offset {})", self.pos));
            None
        } else {
            Some(self.tok_line)
        };
        Error::MeshParse {
            path: self.path.to_path_buf(),
            section: self.section.clone(),
            line,
            msg,
        }
    }

    /// The error for running out of data.
    fn eof_err(&self, what: &str) -> Error {
        let mut msg = format!("unexpected end of file while reading {what} (file truncated?)");
        if let Some(claim) = &self.overclaim {
            msg.push_str("; ");
            msg.push_str(claim);
        }
        self.err(msg)
    }

    fn skip_ws(&mut self) {
        while let Some(&b) = self.data.get(self.pos) {
            match b {
                b'\n' => self.line += 1,
                b' ' | b'\t' | b'\r' | b'\x0c' => {}
                _ => break,
            }
            self.pos += 1;
        }
    }

    /// Whether the current line has no token left (blanks skipped, the newline not consumed):
    /// for records that must fit one line.
    pub fn line_ends(&mut self) -> bool {
        while let Some(&b) = self.data.get(self.pos) {
            match b {
                b' ' | b'\t' | b'\r' | b'\x0c' => self.pos += 1,
                _ => return b == b'\n',
            }
        }
        true
    }

    /// In ASCII data, an error unless another token follows on the current line: records that
    /// must fit one line (a node's coordinates, an element's nodes) are then reported at their
    /// own line, not where the next line's tokens stop fitting. `what` names what is missing.
    pub fn more_on_line(&mut self, what: impl FnOnce() -> String) -> crate::Result<()> {
        if self.bin.is_some() || self.file_binary || !self.line_ends() {
            return Ok(());
        }
        Err(self.err(what()))
    }

    /// In ASCII data, an error unless the current line ends here: `msg` makes its message from
    /// the first extra value.
    pub fn line_done(&mut self, msg: impl FnOnce(&str) -> String) -> crate::Result<()> {
        if self.bin.is_some() || self.file_binary || self.line_ends() {
            return Ok(());
        }
        let extra = self.next_token().map(shown).unwrap_or_default();
        Err(self.err(msg(&extra)))
    }

    /// The next whitespace-separated ASCII token, or `None` at the end of the file.
    ///
    /// At the end of the file, the line of errors stays that of the last token read, i.e. the
    /// last line with content, which is where a truncated file was cut.
    pub fn next_token(&mut self) -> Option<&'a [u8]> {
        self.skip_ws();
        let start = self.pos;
        while let Some(&b) = self.data.get(self.pos) {
            if b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        if self.pos == start {
            None
        } else {
            self.tok_line = self.line;
            self.data.get(start..self.pos)
        }
    }

    /// The next ASCII token; `what` names it in the end-of-file error.
    pub fn token(&mut self, what: &str) -> crate::Result<&'a [u8]> {
        self.next_token().ok_or_else(|| self.eof_err(what))
    }

    /// Parse the next ASCII token as a `T`.
    fn tok_parse<T: FromStr>(&mut self, what: &str) -> crate::Result<T> {
        let tok = self.token(what)?;
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<T>().ok())
            .ok_or_else(|| {
                let mut msg = format!("expected {what}, found '{}'", shown(tok));
                // A section tag where a value should be: the section holds fewer records than
                // its counts say.
                if let (Some(b'$'), Some(claim)) = (tok.first(), &self.overclaim) {
                    msg.push_str("; ");
                    msg.push_str(claim);
                }
                self.err(msg)
            })
    }

    /// The next ASCII token as an unsigned integer.
    pub fn tok_u64(&mut self, what: &str) -> crate::Result<u64> {
        self.tok_parse(what)
    }

    /// The next ASCII token as a signed integer.
    pub fn tok_i32(&mut self, what: &str) -> crate::Result<i32> {
        self.tok_parse(what)
    }

    /// The rest of the current line, trimmed (used for quoted physical names).
    pub fn rest_of_line(&mut self) -> &'a [u8] {
        let start = self.pos;
        while let Some(&b) = self.data.get(self.pos) {
            if b == b'\n' {
                break;
            }
            self.pos += 1;
        }
        let s = self.data.get(start..self.pos).unwrap_or(&[]);
        s.trim_ascii()
    }

    /// Skip blanks up to and including the end of the current line. In binary files the raw
    /// data starts right after the newline that ends an ASCII line.
    pub fn end_of_line(&mut self) -> crate::Result<()> {
        while let Some(&b) = self.data.get(self.pos) {
            self.pos += 1;
            match b {
                b' ' | b'\t' | b'\r' => {}
                b'\n' => {
                    self.line += 1;
                    return Ok(());
                }
                _ => {
                    self.pos -= 1;
                    return Err(self.err(format!(
                        "unexpected '{}' at the end of a line",
                        shown(self.data.get(self.pos..self.pos + 1).unwrap_or(&[]))
                    )));
                }
            }
        }
        Err(self.eof_err("the end of a line"))
    }

    /// Expect the ASCII token `word` (e.g. `$EndNodes`).
    pub fn expect(&mut self, word: &str) -> crate::Result<()> {
        match self.next_token() {
            Some(t) if t == word.as_bytes() => Ok(()),
            Some(t) => Err(self.err(format!("expected {word}, found '{}'", shown(t)))),
            None => Err(self.eof_err(word)),
        }
    }

    /// Skip an unknown section up to and including `$End<name>`.
    pub fn skip_section(&mut self, name: &str) -> crate::Result<()> {
        let end = format!("$End{name}");
        let rest = self.data.get(self.pos..).unwrap_or(&[]);
        match find(rest, end.as_bytes()) {
            Some(off) => {
                let skipped = rest.get(..off + end.len()).unwrap_or(&[]);
                self.line += skipped.iter().filter(|&&b| b == b'\n').count();
                self.pos += off + end.len();
                Ok(())
            }
            None => Err(self.err(format!("section ${name} has no {end} (file truncated?)"))),
        }
    }

    /// Read a record count (a `size_t`) of records of at least `min_bytes` bytes each.
    ///
    /// A count larger than the whole file could hold is returned as read (a truncated file
    /// then fails at the line where it was cut) but remembered for the end-of-file message;
    /// callers reserve memory with [`Cursor::cap`], never with the count itself.
    pub fn count(&mut self, what: &str, min_bytes: usize) -> crate::Result<usize> {
        let n = self.size(&format!("number of {what}"))?;
        self.check_count(n, what, min_bytes)
    }

    /// Like [`Cursor::count`] for an ASCII count (MSH 2.2 record counts, `$PhysicalNames`).
    pub fn tok_count(&mut self, what: &str, min_bytes: usize) -> crate::Result<usize> {
        let n = self.tok_u64(&format!("number of {what}"))?;
        self.check_count(n, what, min_bytes)
    }

    /// Convert a count read from the file, noting it if the file is too small for it.
    pub fn check_count(&mut self, n: u64, what: &str, min_bytes: usize) -> crate::Result<usize> {
        if n > self.max_records(min_bytes) as u64 {
            let where_ = if self.file_binary {
                String::new()
            } else {
                format!(" on line {}", self.tok_line)
            };
            self.overclaim = Some(format!(
                "the count{where_} announced {n} {what}, more than a file of {} bytes can hold",
                self.data.len()
            ));
        }
        usize::try_from(n).map_err(|_| self.err(format!("too many {what}: {n}")))
    }

    /// Most records of at least `min_bytes` bytes the whole file could hold.
    fn max_records(&self, min_bytes: usize) -> usize {
        (self.data.len() + 1) / min_bytes.max(1)
    }

    /// `n` capped to what the file could hold: the capacity to reserve for `n` records, so
    /// that a corrupt count never allocates more than a small multiple of the file size.
    pub fn cap(&self, n: usize, min_bytes: usize) -> usize {
        n.min(self.max_records(min_bytes))
    }

    /// Minimum size in bytes of one `int` value in the current mode (a digit and a blank in
    /// ASCII).
    pub fn int_bytes(&self) -> usize {
        if self.bin.is_some() { 4 } else { 2 }
    }

    /// Minimum size in bytes of one `size_t` value in the current mode.
    pub fn size_bytes(&self) -> usize {
        self.bin.map_or(2, |b| b.size_t)
    }

    /// Minimum size in bytes of one `double` value in the current mode.
    pub fn float_bytes(&self) -> usize {
        if self.bin.is_some() { 8 } else { 2 }
    }

    /// `n` raw bytes.
    fn raw<const N: usize>(&mut self, what: &str) -> crate::Result<[u8; N]> {
        let bytes = self
            .data
            .get(self.pos..self.pos + N)
            .ok_or_else(|| self.eof_err(what))?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        self.pos += N;
        Ok(out)
    }

    /// A raw 4-byte integer in the file's byte order (binary mode required by the caller).
    fn raw_i32(&mut self, big_endian: bool, what: &str) -> crate::Result<i32> {
        let b = self.raw::<4>(what)?;
        Ok(if big_endian {
            i32::from_be_bytes(b)
        } else {
            i32::from_le_bytes(b)
        })
    }

    /// Read the binary endianness marker (an `int` equal to 1) that follows a binary header
    /// line; returns true for big-endian.
    pub fn endianness(&mut self) -> crate::Result<bool> {
        let b = self.raw::<4>("the binary endianness marker")?;
        if i32::from_le_bytes(b) == 1 {
            Ok(false)
        } else if i32::from_be_bytes(b) == 1 {
            Ok(true)
        } else {
            Err(self.err("binary endianness marker is not the integer 1"))
        }
    }

    /// An `int` value (ASCII token or 4 raw bytes).
    pub fn int(&mut self, what: &str) -> crate::Result<i32> {
        self.tok_line = self.line;
        match self.bin {
            None => self.tok_i32(what),
            Some(b) => self.raw_i32(b.big_endian, what),
        }
    }

    /// A `size_t` value (ASCII token, or 4/8 raw bytes in MSH 4.1 binary).
    pub fn size(&mut self, what: &str) -> crate::Result<u64> {
        self.tok_line = self.line;
        match self.bin {
            None => self.tok_u64(what),
            Some(b) if b.size_t == 4 => {
                let v = self.raw::<4>(what)?;
                Ok(u64::from(if b.big_endian {
                    u32::from_be_bytes(v)
                } else {
                    u32::from_le_bytes(v)
                }))
            }
            Some(b) => {
                let v = self.raw::<8>(what)?;
                Ok(if b.big_endian {
                    u64::from_be_bytes(v)
                } else {
                    u64::from_le_bytes(v)
                })
            }
        }
    }

    /// A non-negative `int` used as a tag (MSH 2.2 binary stores tags as `int`).
    pub fn int_tag(&mut self, what: &str) -> crate::Result<u64> {
        match self.bin {
            None => self.size(what),
            Some(_) => {
                let v = self.int(what)?;
                u64::try_from(v).map_err(|_| self.err(format!("negative {what} {v}")))
            }
        }
    }

    /// A `double` value (ASCII token or 8 raw bytes).
    pub fn float(&mut self, what: &str) -> crate::Result<f64> {
        self.tok_line = self.line;
        match self.bin {
            None => self.tok_parse(what),
            Some(b) => {
                let v = self.raw::<8>(what)?;
                Ok(if b.big_endian {
                    f64::from_be_bytes(v)
                } else {
                    f64::from_le_bytes(v)
                })
            }
        }
    }

    /// A finite coordinate.
    pub fn coord(&mut self, what: &str) -> crate::Result<f64> {
        let v = self.float(what)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(format!("{what} is not finite ({v})")))
        }
    }
}

/// A token for an error message: lossy UTF-8, cut to 40 characters.
pub(super) fn shown(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(tok);
    let mut out: String = s.chars().take(40).collect();
    if s.chars().count() > 40 {
        out.push('…');
    }
    out
}

/// Position of `needle` in `hay`.
fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() {
        return Some(0);
    }
    hay.windows(needle.len()).position(|w| w == needle)
}
