//! The one TOML family of vibrofem's input files (scenes, designs, studies, machines): the same
//! versioning (`version = 1`, refused otherwise with one message), the same strictness (unknown
//! keys are errors) and the same error style — [`crate::Error::Input`] naming the file, the line
//! and the key.

use crate::{Error, Result};
use serde::de::DeserializeOwned;
use std::path::Path;

/// The format version every file kind reads.
pub const VERSION: i64 = 1;

/// Read a file's text.
pub fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

/// 1-based line of byte `offset` in `text`.
pub fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// Deserialize `text` (the contents of `path`) strictly; a syntax or schema error names the
/// file and the line.
pub fn parse<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| Error::Input {
        file: path.display().to_string(),
        line: e.span().map(|s| line_of(text, s.start)),
        key: None,
        msg: e.message().trim().to_string(),
    })
}

/// Refuse any `version` but [`VERSION`]; `what` names the file kind ("design", "[study]").
pub fn check_version(path: &Path, text: &str, what: &str, version: i64) -> Result<()> {
    if version == VERSION {
        return Ok(());
    }
    Err(Error::Input {
        file: path.display().to_string(),
        line: line_of_key(text, "version"),
        key: Some("version".into()),
        msg: format!("unsupported {what} version {version} (this vibrofem reads version {VERSION})"),
    })
}

/// The line where the dotted `key` (`table.sub.name`) is set in `text`, if it can be found: the
/// `name = …` line inside the `[table.sub]` section (or at the top for an undotted key).
pub fn line_of_key(text: &str, key: &str) -> Option<usize> {
    let (table, name) = key.rsplit_once('.').unwrap_or(("", key));
    let mut current = String::new();
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim();
        if let Some(h) = l.strip_prefix('[') {
            current = h.trim_start_matches('[').trim_end_matches(']').trim().to_string();
            continue;
        }
        if current == table {
            if let Some(rest) = l.strip_prefix(name) {
                if rest.trim_start().starts_with('=') {
                    return Some(i + 1);
                }
            }
        }
    }
    None
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
        Error::InvalidInput(msg) => Error::Input {
            file: path.display().to_string(),
            line: None,
            key: None,
            msg,
        },
        e => e,
    }
}

/// A validation error for `key` (located later by [`locate`]).
pub fn bad_value(key: &str, msg: impl std::fmt::Display) -> Error {
    Error::Input {
        file: String::new(),
        line: None,
        key: Some(key.into()),
        msg: msg.to_string(),
    }
}
