//! Batch runs: a template scene over the meshes matched by a glob, in parallel (capped by a
//! memory budget), with resume (a case whose result file was computed from the same mesh,
//! template and version is not rerun), shards of the sorted file list, and a CSV/JSON summary.

use super::scene::{MeshSource, Scene, SceneReport};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Does `name` match the glob `pat` (`*` any run of characters, `?` one character)?
pub fn glob_match(pat: &str, name: &str) -> bool {
    let p: Vec<char> = pat.chars().collect();
    let n: Vec<char> = name.chars().collect();
    let (mut pi, mut ni) = (0, 0);
    let (mut star, mut mark) = (None, 0);
    while ni < n.len() {
        if pi < p.len() && (p[pi] == '?' || p[pi] == n[ni]) {
            pi += 1;
            ni += 1;
        } else if pi < p.len() && p[pi] == '*' {
            star = Some(pi);
            mark = ni;
            pi += 1;
        } else if let Some(s) = star {
            pi = s + 1;
            mark += 1;
            ni = mark;
        } else {
            return false;
        }
    }
    while pi < p.len() && p[pi] == '*' {
        pi += 1;
    }
    pi == p.len()
}

/// The files matching a glob whose wildcards (`*`, `?`) are in the file name only, sorted.
pub fn glob_files(pattern: &str) -> Result<Vec<PathBuf>> {
    let path = Path::new(pattern);
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .ok_or_else(|| Error::param("pattern", format!("batch: '{pattern}' names no file")))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if dir.to_string_lossy().contains(['*', '?']) {
        return Err(Error::param(
            "pattern",
            format!("batch: '{pattern}': wildcards are allowed in the file name only"),
        ));
    }
    let rd = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut out = Vec::new();
    for e in rd.flatten() {
        let f = e.file_name().to_string_lossy().into_owned();
        if glob_match(&name, &f) && e.path().is_file() {
            out.push(if path.parent().is_some_and(|d| !d.as_os_str().is_empty()) {
                dir.join(&f)
            } else {
                PathBuf::from(&f)
            });
        }
    }
    out.sort();
    Ok(out)
}

/// Parse `I/N` (1-based shard `I` of `N`).
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || {
        Error::option(
            "--shard",
            format!("--shard '{s}': expected I/N with 1 ≤ I ≤ N, e.g. 2/8"),
        )
    };
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if n == 0 || i == 0 || i > n {
        return Err(bad());
    }
    Ok((i, n))
}

/// Shard `i` of `n` (1-based) of a sorted list: every n-th file starting at the i-th.
pub fn shard<T: Clone>(items: &[T], i: usize, n: usize) -> Vec<T> {
    items
        .iter()
        .enumerate()
        .filter(|(k, _)| k % n == i - 1)
        .map(|(_, x)| x.clone())
        .collect()
}

/// Options of a batch run.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// Glob of mesh files (wildcards in the file name).
    pub pattern: String,
    /// The template scene; each mesh replaces its `[mesh]`.
    pub template: PathBuf,
    /// Output folder (per-case `<stem>.json`, `summary.csv`, `summary.json`).
    pub out: PathBuf,
    /// Concurrent cases at most (further capped by memory).
    pub jobs: usize,
    /// Rerun cases whose result file exists.
    pub force: bool,
    /// Only shard `(i, n)` of the sorted file list.
    pub shard: Option<(usize, usize)>,
    /// Show a progress bar (a terminal); otherwise one line per case on stderr.
    pub progress_bar: bool,
}

/// One row of the batch summary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BatchRow {
    /// Mesh file.
    pub file: String,
    /// `ok`, `failed`, `unverified` (modal check failed) or `resumed` (result file existed).
    pub status: String,
    /// Error message of a failed case.
    pub error: Option<String>,
    /// Free DOFs.
    pub dofs: Option<usize>,
    /// Model mass (modal runs), kg.
    pub mass_kg: Option<f64>,
    /// Frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// First elastic (non-rigid-body) frequency, Hz.
    pub first_elastic_hz: Option<f64>,
    /// Stiffness along the first guided axis, load case 1 (N/m).
    pub stiffness: Option<f64>,
    /// Largest displacement, load case 1 (m).
    pub max_displacement: Option<f64>,
    /// Largest von Mises stress, load case 1 (Pa).
    pub max_von_mises: Option<f64>,
    /// Wall time, s.
    pub time_s: f64,
}

impl BatchRow {
    fn failed(file: &str, error: String, time_s: f64) -> BatchRow {
        BatchRow {
            file: file.to_string(),
            status: "failed".into(),
            error: Some(error),
            dofs: None,
            mass_kg: None,
            frequencies_hz: vec![],
            first_elastic_hz: None,
            stiffness: None,
            max_displacement: None,
            max_von_mises: None,
            time_s,
        }
    }

    fn from_report(file: &str, r: &SceneReport) -> BatchRow {
        BatchRow {
            file: file.to_string(),
            status: if r.verified() { "ok" } else { "unverified" }.into(),
            error: (!r.verified()).then(|| "the modal solution failed its Sturm or residual check".to_string()),
            dofs: r
                .modal
                .as_ref()
                .map(|m| m.dofs)
                .or(r.statics.as_ref().map(|s| s.dofs))
                .or(r.harmonic.as_ref().map(|h| h.dofs))
                .or(r.buckling.as_ref().map(|b| b.dofs)),
            mass_kg: r.modal.as_ref().map(|m| m.mass_kg),
            frequencies_hz: r.modal.as_ref().map(|m| m.frequencies_hz.clone()).unwrap_or_default(),
            first_elastic_hz: r.modal.as_ref().and_then(|m| m.elastic_frequencies().first().copied()),
            stiffness: r.stiffness(),
            max_displacement: r.max_displacement(),
            max_von_mises: r.max_von_mises(),
            time_s: r.time_s,
        }
    }

    /// The case did not produce results.
    pub fn is_failure(&self) -> bool {
        self.status == "failed" || self.status == "unverified"
    }
}

/// The outcome of a batch.
#[derive(Clone, Debug, Serialize)]
pub struct BatchSummary {
    /// One row per mesh, in sorted file order.
    pub rows: Vec<BatchRow>,
    /// Cases that failed.
    pub failed: usize,
    /// Cases taken from existing result files.
    pub resumed: usize,
    /// Concurrent cases allowed.
    pub jobs: usize,
    /// Hash of the template scene's text and the program version (`merge` refuses shards of
    /// different templates); absent in a merged summary of such shards' predecessors.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub template: Option<String>,
    /// `[I, N]`: shard I of N of the sorted file list (`batch --shard`), or the shards merged.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub shards: Vec<[usize; 2]>,
}

impl BatchSummary {
    /// The summary of `rows` (counting the failed and resumed cases).
    pub fn new(rows: Vec<BatchRow>, jobs: usize) -> Self {
        BatchSummary {
            failed: rows.iter().filter(|r| r.is_failure()).count(),
            resumed: rows.iter().filter(|r| r.status == "resumed").count(),
            rows,
            jobs,
            template: None,
            shards: Vec::new(),
        }
    }
}

/// The template's identity in a summary: a hash of its text and the program version.
pub fn template_hash(template_text: &[u8]) -> String {
    let h = fnv1a(0xcbf2_9ce4_8422_2325, env!("CARGO_PKG_VERSION").as_bytes());
    format!("{:016x}", fnv1a(h, template_text))
}

/// Memory available to new processes (bytes), from /proc/meminfo.
fn available_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let l = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    Some(l.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// Rough peak memory of one case from its mesh file size: 64 MiB + 150 × the file size (an
/// ASCII tet10 mesh of 55 k DOFs, 3 MB, peaks near 440 MiB).
pub fn estimate_case_memory(file: &Path) -> u64 {
    let size = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
    (64 << 20) + 150 * size
}

/// A counting budget of bytes shared by the workers.
struct MemoryBudget {
    limit: u64,
    used: std::sync::Mutex<u64>,
    freed: std::sync::Condvar,
}

impl MemoryBudget {
    fn acquire(&self, want: u64) -> u64 {
        let want = want.min(self.limit);
        let mut used = self.used.lock().unwrap_or_else(|e| e.into_inner());
        while *used > 0 && *used + want > self.limit {
            used = self.freed.wait(used).unwrap_or_else(|e| e.into_inner());
        }
        *used += want;
        want
    }
    fn release(&self, got: u64) {
        let mut used = self.used.lock().unwrap_or_else(|e| e.into_inner());
        *used = used.saturating_sub(got);
        self.freed.notify_all();
    }
}

/// A CSV field: quoted (quotes doubled, newlines as spaces) when it holds a comma, a quote or a
/// newline.
pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\"").replace('\n', " "))
    } else {
        s.to_string()
    }
}

/// The summary as CSV: `file,status,error,dofs,mass_kg,stiffness_n_per_m,max_displacement_m,
/// max_von_mises_pa,time_s,f1_hz,…` (as many frequency columns as the longest row).
pub fn summary_csv(rows: &[BatchRow]) -> String {
    let nf = rows.iter().map(|r| r.frequencies_hz.len()).max().unwrap_or(0);
    let mut s =
        String::from("file,status,error,dofs,mass_kg,stiffness_n_per_m,max_displacement_m,max_von_mises_pa,time_s");
    for i in 1..=nf {
        s.push_str(&format!(",f{i}_hz"));
    }
    s.push('\n');
    let opt = |v: Option<f64>| v.map(|x| format!("{x:.9e}")).unwrap_or_default();
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{:.3}",
            csv_field(&r.file),
            r.status,
            csv_field(r.error.as_deref().unwrap_or("")),
            r.dofs.map(|d| d.to_string()).unwrap_or_default(),
            opt(r.mass_kg),
            opt(r.stiffness),
            opt(r.max_displacement),
            opt(r.max_von_mises),
            r.time_s
        ));
        for i in 0..nf {
            s.push(',');
            if let Some(f) = r.frequencies_hz.get(i) {
                s.push_str(&format!("{f:.9e}"));
            }
        }
        s.push('\n');
    }
    s
}

/// FNV-1a, 64 bits: a stable content hash (the same on every machine and Rust version).
fn fnv1a(h: u64, bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(h, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

/// What a batch result was computed from: the mesh's full path, and a hash of the mesh bytes,
/// the template scene's text and the program version. A result file is resumed only when both
/// match, so an edited template or mesh, or another mesh of the same name, is rerun.
fn case_key(template_text: &[u8], file: &Path) -> serde_json::Value {
    let path = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let mut h = fnv1a(0xcbf2_9ce4_8422_2325, env!("CARGO_PKG_VERSION").as_bytes());
    h = fnv1a(h, &(template_text.len() as u64).to_le_bytes());
    h = fnv1a(h, template_text);
    match std::fs::read(file) {
        Ok(bytes) => h = fnv1a(h, &bytes),
        // Unreadable: a key that matches nothing (the run reports the error).
        Err(_) => h = fnv1a(h, b"\0unreadable"),
    }
    serde_json::json!({ "path": path.display().to_string(), "hash": format!("{h:016x}") })
}

/// Result-file names of the cases: the file stem, or the whole file name where two meshes of
/// the batch share a stem (`m.msh` and `m.msh2`), so no case overwrites or resumes another;
/// a name still taken (`m.msh.msh`'s stem is `m.msh` too) or the batch's own `summary` gets
/// `-2`, `-3`, … (in the glob's order, the same on every run).
fn case_names(files: &[PathBuf]) -> Vec<String> {
    let mut used = std::collections::HashSet::new();
    first_names(files)
        .into_iter()
        .map(|n| {
            let mut name = n.clone();
            let mut k = 2;
            while name == "summary" || !used.insert(name.clone()) {
                name = format!("{n}-{k}");
                k += 1;
            }
            name
        })
        .collect()
}

/// The names [`case_names`] starts from: stems, file names where stems repeat.
fn first_names(files: &[PathBuf]) -> Vec<String> {
    let stem = |f: &PathBuf| {
        f.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let stems: Vec<String> = files.iter().map(stem).collect();
    files
        .iter()
        .zip(&stems)
        .map(|(f, s)| {
            if stems.iter().filter(|t| *t == s).count() > 1 {
                f.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_else(|| s.clone())
            } else {
                s.clone()
            }
        })
        .collect()
}

fn run_case(template: &Scene, template_text: &[u8], file: &Path, stem: &str, out: &Path, force: bool) -> BatchRow {
    let name = file.display().to_string();
    let result = out.join(format!("{stem}.json"));
    let key = case_key(template_text, file);
    if !force && result.is_file() {
        let doc = std::fs::read_to_string(&result)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok());
        let row = doc
            .as_ref()
            .filter(|d| d.get("key") == Some(&key))
            .and_then(|v| serde_json::from_value::<BatchRow>(v.get("row")?.clone()).ok());
        if let Some(mut row) = row {
            row.status = "resumed".into();
            return row;
        }
        if doc.is_some() {
            eprintln!(
                "note: {}: computed from another mesh, template or version; rerunning {name}",
                result.display()
            );
        }
    }
    let t = Instant::now();
    let mut scene = template.clone();
    scene.mesh = MeshSource::File(file.to_path_buf());
    let prefix = format!("{stem}_");
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| scene.run(Some((out, &prefix)))));
    match r {
        Ok(Ok(rep)) => {
            let row = BatchRow::from_report(&name, &rep);
            if !row.is_failure() {
                let doc = serde_json::json!({ "key": key, "row": row, "report": rep });
                if let Ok(text) = serde_json::to_string_pretty(&doc) {
                    let tmp = out.join(format!("{stem}.json.part"));
                    if std::fs::write(&tmp, text).is_ok() {
                        let _ = std::fs::rename(&tmp, &result);
                    }
                }
            }
            row
        }
        Ok(Err(e)) => BatchRow::failed(&name, e.to_string(), t.elapsed().as_secs_f64()),
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".into());
            BatchRow::failed(&name, format!("internal error: {msg}"), t.elapsed().as_secs_f64())
        }
    }
}

/// Run a template scene over the meshes matched by a glob. Failing cases are reported in their
/// row and skipped; the summary is written to `out/summary.csv` and `out/summary.json`.
pub fn run_batch(opts: &BatchOptions) -> Result<BatchSummary> {
    use rayon::prelude::*;
    let template = Scene::load(&opts.template)?;
    let template_text = std::fs::read(&opts.template).map_err(|e| Error::io(&opts.template, e))?;
    let mut files = glob_files(&opts.pattern)?;
    if files.is_empty() {
        return Err(Error::param(
            "pattern",
            format!("batch: no file matches '{}'", opts.pattern),
        ));
    }
    if let Some((i, n)) = opts.shard {
        files = shard(&files, i, n);
    }
    crate::io::create_dir(&opts.out)?;
    // More workers than cases, or far more than cores, only cost threads and memory.
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let cap = (4 * cores).min(files.len()).max(1);
    let jobs = opts.jobs.clamp(1, cap);
    if opts.jobs > cap {
        eprintln!(
            "note: --jobs {} capped at {cap} ({} cases, {cores} cores)",
            opts.jobs,
            files.len()
        );
    }
    let budget = MemoryBudget {
        limit: available_memory().map(|m| m / 10 * 7).unwrap_or(4 << 30).max(256 << 20),
        used: std::sync::Mutex::new(0),
        freed: std::sync::Condvar::new(),
    };
    let bar = if opts.progress_bar {
        let b = indicatif::ProgressBar::new(files.len() as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed} {msg}") {
            b.set_style(style);
        }
        Some(b)
    } else {
        None
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let total = files.len();
    let names = case_names(&files);
    let cases: Vec<(&PathBuf, &String)> = files.iter().zip(&names).collect();
    let one = |&(f, stem): &(&PathBuf, &String)| -> BatchRow {
        let got = budget.acquire(estimate_case_memory(f));
        let row = run_case(&template, &template_text, f, stem, &opts.out, opts.force);
        budget.release(got);
        let k = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        let line = format!(
            "[{k}/{total}] {} {}{}",
            row.file,
            row.status,
            row.error.as_ref().map(|e| format!(": {e}")).unwrap_or_default()
        );
        match &bar {
            Some(b) => {
                b.set_message(line);
                b.inc(1);
            }
            None => eprintln!("{line}"),
        }
        row
    };
    let rows: Vec<BatchRow> = if jobs == 1 {
        cases.iter().map(one).collect()
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(jobs)
            .build()
            .map_err(|e| Error::param("jobs", format!("batch: cannot start {jobs} workers: {e}")))?;
        pool.install(|| cases.par_iter().map(one).collect())
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let mut summary = BatchSummary::new(rows, jobs);
    summary.template = Some(template_hash(&template_text));
    summary.shards = opts.shard.map(|(i, n)| vec![[i, n]]).unwrap_or_default();
    write_summary(&summary, &opts.out)?;
    Ok(summary)
}

/// Write `summary.csv` and `summary.json` of a batch (or of merged shards) into `dir`.
pub fn write_summary(summary: &BatchSummary, dir: &Path) -> Result<()> {
    let csv = dir.join("summary.csv");
    std::fs::write(&csv, summary_csv(&summary.rows)).map_err(|e| Error::io(&csv, e))?;
    let js = dir.join("summary.json");
    let text = serde_json::to_string_pretty(summary).map_err(|e| Error::output("summary.json", e))?;
    std::fs::write(&js, text).map_err(|e| Error::io(&js, e))
}
