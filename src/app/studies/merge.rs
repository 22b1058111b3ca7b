//! Merging of batch shards (`vibrofem merge`): the `summary.json` of the folders that
//! `vibrofem batch --shard I/N` wrote, joined into one summary sorted by file.

use super::batch::{BatchRow, BatchSummary, write_summary};
use crate::app::toml_file::file_error;
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// Rows equal as results (status `resumed` equals `ok`; wall time ignored).
fn same_result(a: &BatchRow, b: &BatchRow) -> bool {
    let st = |s: &str| {
        if s == "resumed" {
            "ok".to_string()
        } else {
            s.to_string()
        }
    };
    st(&a.status) == st(&b.status)
        && a.error == b.error
        && a.dofs == b.dofs
        && a.mass_kg == b.mass_kg
        && a.frequencies_hz == b.frequencies_hz
        && a.first_elastic_hz == b.first_elastic_hz
        && a.stiffness == b.stiffness
        && a.max_displacement == b.max_displacement
        && a.max_von_mises == b.max_von_mises
}

/// Join the `summary.json` of batch shard folders into one summary sorted by file; a case in
/// several folders must have the same results there (else an error naming it). Writes
/// `out/summary.csv` and `out/summary.json` when `out` is given.
pub fn merge(dirs: &[PathBuf], out: Option<&Path>) -> Result<BatchSummary> {
    if dirs.is_empty() {
        return Err(Error::param("dirs", "merge: no input folder"));
    }
    let mut rows: Vec<(BatchRow, PathBuf)> = Vec::new();
    let mut jobs = 1;
    let mut template: Option<(String, &PathBuf)> = None;
    let mut shards: Vec<[usize; 2]> = Vec::new();
    for d in dirs {
        let p = d.join("summary.json");
        let text = std::fs::read_to_string(&p).map_err(|e| Error::io(&p, e))?;
        let bad = |msg: String| file_error(p.display().to_string(), None, msg);
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        let rows_json = v
            .get("rows")
            .cloned()
            .ok_or_else(|| bad("no 'rows' (not a batch summary)".into()))?;
        let r: Vec<BatchRow> = serde_json::from_value(rows_json).map_err(|e| bad(e.to_string()))?;
        jobs = jobs.max(v.get("jobs").and_then(|j| j.as_u64()).unwrap_or(1) as usize);
        // Shards of one batch come from one template (summaries from before this field have
        // none and are taken as they are).
        if let Some(t) = v.get("template").and_then(|t| t.as_str()) {
            match &template {
                Some((first, fd)) if first != t => {
                    return Err(Error::param(
                        "dirs",
                        format!(
                            "merge: {} and {} were run with different template scenes (or program versions): \
                             their rows are not one study",
                            fd.display(),
                            d.display()
                        ),
                    ));
                }
                Some(_) => {}
                None => template = Some((t.to_string(), d)),
            }
        }
        if let Some(list) = v.get("shards") {
            let s: Vec<[usize; 2]> = serde_json::from_value(list.clone()).map_err(|e| bad(e.to_string()))?;
            shards.extend(s);
        }
        rows.extend(r.into_iter().map(|r| (r, d.clone())));
    }
    rows.sort_by(|a, b| a.0.file.cmp(&b.0.file));
    let mut merged: Vec<(BatchRow, PathBuf)> = Vec::new();
    for (r, d) in rows {
        if let Some((last, ld)) = merged.last()
            && last.file == r.file
        {
            if !same_result(last, &r) {
                return Err(Error::param(
                    "dirs",
                    format!(
                        "merge: case '{}' is in {} and {} with different results",
                        r.file,
                        ld.display(),
                        d.display()
                    ),
                ));
            }
            continue;
        }
        merged.push((r, d));
    }
    let mut summary = BatchSummary::new(merged.into_iter().map(|(r, _)| r).collect(), jobs);
    summary.template = template.map(|t| t.0);
    shards.sort_unstable();
    shards.dedup();
    summary.shards = shards;
    if let Some(out) = out {
        crate::io::create_dir(out)?;
        write_summary(&summary, out)?;
    }
    Ok(summary)
}

/// The shards of `summary.shards` missing from a complete set, as `I/N` (empty: complete, or
/// no shard information). Shards of different counts N are listed as they are.
pub fn missing_shards(summary: &BatchSummary) -> Vec<String> {
    let mut ns: Vec<usize> = summary.shards.iter().map(|s| s[1]).collect();
    ns.sort_unstable();
    ns.dedup();
    let mut out = Vec::new();
    for n in ns {
        for i in 1..=n {
            if !summary.shards.contains(&[i, n]) {
                out.push(format!("{i}/{n}"));
            }
        }
    }
    out
}
