//! The one TOML family of vibrofem's input files (scenes, designs, studies, machines): the same
//! versioning (`version = 1`, refused otherwise with one message), the same strictness (unknown
//! keys are errors) and the same error style — [`crate::Error::Input`] naming the file, the line
//! and the key.
//!
//! Every room reads its files through here:
//! - [`read`]: the text of a file, without a UTF-8 byte-order mark;
//! - [`parse`]: strict deserialisation, a syntax or schema error naming file and line;
//! - [`line_of`] (a byte offset, e.g. a `toml::Spanned` span's start) and [`line_of_key`] /
//!   [`line_of_table_key`] (a key as written) for the line of a message;
//! - [`key_error`], [`bad_value`] + [`locate`], [`file_error`]: the typed errors.

use crate::{Error, Result};
use serde::de::DeserializeOwned;
use std::path::Path;

/// The format version every file kind reads.
pub const VERSION: i64 = 1;

/// The UTF-8 byte-order mark some editors (Excel's "CSV UTF-8", Notepad) write first.
pub const BOM: char = '\u{feff}';

/// Read a file's text, without a leading byte-order mark (so that line scans see the first line
/// as written).
pub fn read(path: &Path) -> Result<String> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    Ok(match text.strip_prefix(BOM) {
        Some(t) => t.to_string(),
        None => text,
    })
}

/// 1-based line of byte `offset` in `text`.
pub fn line_of(text: &str, offset: usize) -> usize {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    text[..end].matches('\n').count() + 1
}

/// Deserialize `text` (the contents of `path`) strictly; a syntax or schema error names the
/// file and the line.
pub fn parse<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    parse_named(&path.display().to_string(), text)
}

/// [`parse`] for a text named `file` in messages (a built-in file, a generated scene).
pub fn parse_named<T: DeserializeOwned>(file: &str, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| {
        let mut msg = e.message().trim().to_string();
        // The parser says "duplicate key" alone; its span is the key as written.
        let written = e.span().and_then(|s| text.get(s)).map(str::trim);
        if let Some(k) = written.filter(|k| !k.is_empty() && k.len() <= 200 && !k.contains('\n')) {
            if msg.starts_with("duplicate") && !msg.contains(k) {
                msg = format!("{msg} '{k}'");
            }
        }
        Error::Input {
            file: file.to_string(),
            line: e.span().map(|s| line_of(text, s.start)),
            key: None,
            msg,
        }
    })
}

/// Refuse any `version` but [`VERSION`]; `what` names the file kind ("design", "[study]").
pub fn check_version(path: &Path, text: &str, what: &str, version: i64) -> Result<()> {
    if version == VERSION {
        return Ok(());
    }
    Err(key_error(
        path,
        text,
        "version",
        format!("unsupported {what} version {version} (this vibrofem reads version {VERSION})"),
    ))
}

/// Where a key is set: the line of `key = …`, and the line of its table's header.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KeyLine {
    /// The line of `key = …`, if it is written in the table.
    pub key: Option<usize>,
    /// The line of the table's header (`[table]` or the `index`-th `[[table]]`), if any.
    pub header: Option<usize>,
}

/// The line where `key` is set inside the `index`-th (0-based) `[table]` / `[[table]]` of
/// `text` (`table = ""`: the top of the file, before any header), and the line of that table's
/// header. Comments are ignored; a quoted key (`"key" = …`) is found too.
pub fn line_of_table_key(text: &str, table: &str, index: usize, key: &str) -> KeyLine {
    let mut current: (String, usize) = (String::new(), 0);
    let mut counts: Vec<(String, usize)> = Vec::new();
    let mut found = KeyLine::default();
    for (i, raw) in text.lines().enumerate() {
        let l = raw.split('#').next().unwrap_or("").trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|r| r.strip_suffix("]]")) {
            let name = name.trim().to_string();
            let c = match counts.iter_mut().find(|(n, _)| *n == name) {
                Some((_, c)) => {
                    *c += 1;
                    *c
                }
                None => {
                    counts.push((name.clone(), 0));
                    0
                }
            };
            current = (name, c);
        } else if let Some(name) = l.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            current = (name.trim().to_string(), 0);
        } else if let Some((k, _)) = l.split_once('=')
            && k.trim().trim_matches('"') == key
            && current.0 == table
            && current.1 == index
        {
            found.key = Some(i + 1);
            return found;
        }
        if found.header.is_none() && !table.is_empty() && current.0 == table && current.1 == index {
            found.header = Some(i + 1);
        }
    }
    found
}

/// The line where the dotted `key` (`table.sub.name`) is set in `text`, if it can be found: the
/// `name = …` line inside the `[table.sub]` section (or at the top for an undotted key).
pub fn line_of_key(text: &str, key: &str) -> Option<usize> {
    let (table, name) = key.rsplit_once('.').unwrap_or(("", key));
    line_of_table_key(text, table, 0, name).key
}

/// An error at the dotted `key` of the file `path` (text `text`): `file, line L, key 'k': msg`
/// (the line where the key is written, if found).
pub fn key_error(path: &Path, text: &str, key: &str, msg: impl Into<String>) -> Error {
    Error::key(path.display().to_string(), line_of_key(text, key), key, msg)
}

/// An error in the file `file` at `line` (where known) that concerns no single key:
/// `file, line L: msg`.
pub fn file_error(file: impl Into<String>, line: Option<usize>, msg: impl Into<String>) -> Error {
    Error::Input {
        file: file.into(),
        line,
        key: None,
        msg: msg.into(),
    }
}

/// Give a validation error of a file's values (`Error::Input` with the key and no file) the
/// file and the line of its key.
pub fn locate(path: &Path, text: &str, e: Error) -> Error {
    match e {
        Error::Input {
            key: Some(key),
            msg,
            line: None,
            ..
        } => Error::Input {
            file: path.display().to_string(),
            line: line_of_key(text, &key),
            key: Some(key),
            msg,
        },
        Error::InvalidInput(msg) => file_error(path.display().to_string(), None, msg),
        e => e,
    }
}

/// A parameter error ([`Error::param`], as the generators and builders report them) as its
/// file key `key_of(name)` and its message; any other error back as it is.
pub fn param_as_key(e: Error, key_of: impl FnOnce(String) -> String) -> std::result::Result<(String, String), Error> {
    match e {
        Error::Invalid {
            at: crate::At::Param { name },
            msg,
        } => Ok((key_of(name), msg)),
        e => Err(e),
    }
}

/// A validation error for `key` (located later by [`locate`]).
pub fn bad_value(key: &str, msg: impl std::fmt::Display) -> Error {
    Error::key(String::new(), None, key, msg.to_string())
}
