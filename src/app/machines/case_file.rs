//! The TOML case files of the machines (`[machine] version = 1, kind = "…"`): strict parsing
//! and value checks whose errors name the file, the line and the key ([`Error::key`]).
//!
//! Keys of a `[table]` are named `table.key`; keys of the n-th `[[table]]` are named
//! `table.key` with `[[table]] #n` at the head of the message.

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use serde::de::DeserializeOwned;

use crate::app::toml_file;
use crate::{Error, Result};

/// A TOML text with its file name, for messages that name the file, line and key.
pub(crate) struct Source<'a> {
    /// The file as named in messages.
    pub file: &'a str,
    /// Its text.
    pub text: &'a str,
}

impl<'a> Source<'a> {
    /// A source; a UTF-8 byte-order mark at the start is skipped.
    pub fn new(file: &'a str, text: &'a str) -> Self {
        Source {
            file,
            text: text.strip_prefix('\u{feff}').unwrap_or(text),
        }
    }

    fn line_of(&self, offset: usize) -> usize {
        toml_file::line_of(self.text, offset)
    }

    /// Line of `key` in the `index`-th `[table]` / `[[table]]` (0-based), or of the table header
    /// when the key is absent, or None.
    fn key_line(&self, table: &str, index: usize, key: &str) -> Option<usize> {
        let l = toml_file::line_of_table_key(self.text, table, index, key);
        l.key.or(l.header)
    }

    /// An error at `table.key` (`index`: the `[[table]]` number, 0-based).
    pub fn err(&self, table: &str, index: Option<usize>, key: &str, msg: impl std::fmt::Display) -> Error {
        let line = self.key_line(table, index.unwrap_or(0), key);
        let msg = match index {
            Some(i) => format!("[[{table}]] #{}: {msg}", i + 1),
            None => msg.to_string(),
        };
        Error::key(self.file, line, format!("{table}.{key}"), msg)
    }

    /// An error of the file as a whole (no single key).
    pub fn whole(&self, msg: impl std::fmt::Display) -> Error {
        Error::Input {
            file: self.file.to_string(),
            line: None,
            key: None,
            msg: msg.to_string(),
        }
    }

    /// Checks `[machine] version = 1, kind = KIND`, then parses strictly.
    pub fn parse<T: DeserializeOwned>(&self, kind: &str) -> Result<T> {
        let loose: toml::Table = toml::from_str(self.text).map_err(|e| self.toml_error(&e))?;
        let header = loose.get("machine").and_then(|m| m.as_table()).ok_or_else(|| {
            Error::key(
                self.file,
                None,
                "machine",
                format!("missing [machine] table (with version = 1 and kind = \"{kind}\")"),
            )
        })?;
        match header.get("version") {
            Some(toml::Value::Integer(1)) => {}
            Some(v) => {
                return Err(self.err(
                    "machine",
                    None,
                    "version",
                    format!("unsupported version {v} (this vibrofem reads version 1)"),
                ));
            }
            None => return Err(self.err("machine", None, "version", "missing (version = 1)")),
        }
        match header.get("kind") {
            Some(toml::Value::String(k)) if k == kind => {}
            Some(v) => {
                return Err(self.err(
                    "machine",
                    None,
                    "kind",
                    format!("this command reads kind = \"{kind}\", the file says {v}"),
                ));
            }
            None => return Err(self.err("machine", None, "kind", format!("missing (kind = \"{kind}\")"))),
        }
        toml::from_str(self.text).map_err(|e| self.toml_error(&e))
    }

    fn toml_error(&self, e: &toml::de::Error) -> Error {
        let msg = e.message().trim().to_string();
        let Some(s) = e.span() else {
            return self.whole(msg);
        };
        let line = self.line_of(s.start);
        // Name the key when the error points into a `key = value` line.
        let text_line = self.text.lines().nth(line - 1).unwrap_or("");
        let key = text_line
            .split('#')
            .next()
            .and_then(|l| l.split_once('='))
            .map(|(k, _)| k.trim().to_string())
            .filter(|k| !k.is_empty() && !k.starts_with('[') && !msg.contains(&format!("`{k}`")));
        Error::Input {
            file: self.file.to_string(),
            line: Some(line),
            key,
            msg,
        }
    }
}

/// Number checks that name the table, key and line.
pub(crate) struct Checks<'a, 'b> {
    /// The file.
    pub src: &'b Source<'a>,
    /// The table.
    pub table: &'b str,
    /// The `[[table]]` number (0-based), if an array of tables.
    pub index: Option<usize>,
}

impl<'a, 'b> Checks<'a, 'b> {
    /// Checks of `[table]`.
    pub fn table(src: &'b Source<'a>, table: &'b str) -> Self {
        Checks {
            src,
            table,
            index: None,
        }
    }

    /// Checks of the `index`-th `[[table]]`.
    pub fn item(src: &'b Source<'a>, table: &'b str, index: usize) -> Self {
        Checks {
            src,
            table,
            index: Some(index),
        }
    }

    /// An error at `key` of this table.
    pub fn err(&self, key: &str, msg: impl std::fmt::Display) -> Error {
        self.src.err(self.table, self.index, key, msg)
    }

    /// `v` if finite and `ok`, else an error saying it must be `want`.
    pub fn test(&self, key: &str, v: f64, ok: bool, want: &str) -> Result<f64> {
        if v.is_finite() && ok {
            Ok(v)
        } else {
            Err(self.err(key, format!("must be {want}, got {}", crate::io::fmt_plain(v))))
        }
    }

    /// A recording step `dt` (s): `default` when not given, else > 0 and at most `dt_max` (the
    /// samples the bound keeps said by `why`, as metrics read from samples need them); at most
    /// 2e6 samples over `duration` either way.
    pub fn recording_step(
        &self,
        given: Option<f64>,
        default: f64,
        dt_max: f64,
        why: &str,
        duration: f64,
    ) -> Result<f64> {
        let dt = self.test(
            "dt",
            given.unwrap_or(default),
            given.is_none_or(|v| v > 0.0 && v <= dt_max),
            &format!("> 0 and at most {} s ({why})", crate::io::fmt_short(dt_max, 3)),
        )?;
        if duration / dt > 2e6 {
            return Err(self.err("dt", format!("too small: {} samples", duration / dt)));
        }
        Ok(dt)
    }

    /// `v` if > 0.
    pub fn pos(&self, key: &str, v: f64) -> Result<f64> {
        self.test(key, v, v > 0.0, "> 0")
    }

    /// `v` if ≥ 0.
    pub fn nonneg(&self, key: &str, v: f64) -> Result<f64> {
        self.test(key, v, v >= 0.0, "≥ 0")
    }

    /// `v` if finite.
    pub fn finite(&self, key: &str, v: f64) -> Result<f64> {
        self.test(key, v, true, "finite")
    }
}
