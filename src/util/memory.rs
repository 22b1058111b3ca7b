//! The memory of this process and the limits on it (Linux /proc and cgroups): what is
//! resident, the peak, what may still be allocated, and giving freed heap back.

/// The memory a model may use: `--max-memory` when given, otherwise what the system has
/// available ([`memory_budget`] without a limit); with a description for messages.
pub struct MemoryBudget {
    /// Bytes.
    pub bytes: u64,
    /// Where the figure comes from, e.g. "--max-memory is" or "ulimit -v leaves".
    pub what: String,
}

/// The memory budget: the smallest of `limit` (else MemAvailable), the cgroup's memory limit
/// less its usage, and the address-space and data limits (`ulimit -v`, `ulimit -d`) less what
/// the process already uses. `None` when nothing is known.
pub fn memory_budget(limit: Option<u64>) -> Option<MemoryBudget> {
    // An explicit limit replaces MemAvailable (which swap or reclaim may exceed), but the hard
    // limits of ulimit and the cgroup still apply: beyond them an allocation fails for sure.
    let mut sources = memory_sources();
    if let Some(l) = limit {
        sources.retain(|(_, what)| *what != MEMINFO);
        sources.push((l, "--max-memory is"));
    }
    sources
        .into_iter()
        .min_by_key(|(b, _)| *b)
        .map(|(bytes, what)| MemoryBudget {
            bytes,
            what: what.into(),
        })
}

const MEMINFO: &str = "the system has available";

/// Every memory limit that applies to this process: (bytes still usable, description).
fn memory_sources() -> Vec<(u64, &'static str)> {
    let mut out = Vec::new();
    if let Some(a) = meminfo_available() {
        out.push((a, MEMINFO));
    }
    if let Some(c) = cgroup_available() {
        out.push((c, "the cgroup memory limit leaves"));
    }
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let status_kb = |key: &str| -> u64 {
        status
            .lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<u64>().ok())
            .unwrap_or(0)
            * 1024
    };
    if let Ok(limits) = std::fs::read_to_string("/proc/self/limits") {
        // "Max address space   unlimited   unlimited   bytes": the soft limit is the first value.
        let soft = |name: &str| -> Option<u64> {
            let l = limits.lines().find(|l| l.starts_with(name))?;
            l[name.len()..].split_whitespace().next()?.parse().ok()
        };
        if let Some(l) = soft("Max address space") {
            out.push((l.saturating_sub(status_kb("VmSize:")), "ulimit -v leaves"));
        }
        if let Some(l) = soft("Max data size") {
            out.push((l.saturating_sub(status_kb("VmData:")), "ulimit -d leaves"));
        }
    }
    out
}

/// The cgroup (v2, else v1) memory limit of this process less its current usage, if limited.
fn cgroup_available() -> Option<u64> {
    let read = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|s| s.trim().parse::<u64>().ok())
    };
    let cg = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    let mut dirs = Vec::new();
    for line in cg.lines() {
        let mut parts = line.splitn(3, ':');
        let (id, ctrl, path) = (parts.next()?, parts.next()?, parts.next()?);
        if id == "0" && ctrl.is_empty() {
            dirs.push((format!("/sys/fs/cgroup{path}"), "memory.max", "memory.current"));
        } else if ctrl.split(',').any(|c| c == "memory") {
            dirs.push((
                format!("/sys/fs/cgroup/memory{path}"),
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            ));
        }
    }
    dirs.push(("/sys/fs/cgroup".into(), "memory.max", "memory.current"));
    dirs.push((
        "/sys/fs/cgroup/memory".into(),
        "memory.limit_in_bytes",
        "memory.usage_in_bytes",
    ));
    for (dir, max, cur) in dirs {
        // v2 writes "max" when unlimited (not a number: skipped); v1 a huge number.
        if let Some(limit) = read(&format!("{dir}/{max}")) {
            if limit >= 1 << 60 {
                continue;
            }
            let used = read(&format!("{dir}/{cur}")).unwrap_or(0);
            return Some(limit.saturating_sub(used));
        }
    }
    None
}

/// Give the heap's free memory back to the system. The allocator keeps what a phase freed (the
/// graph, the assembly's scratch, a coarse model) for later requests, spread over the heaps of
/// the worker threads; the large buffers that follow (the factor, the Lanczos basis) are
/// mapped separately and cannot reuse it, so it would only raise the peak. A no-op off glibc.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        unsafe extern "C" {
            fn malloc_trim(pad: usize) -> i32;
        }
        // SAFETY: malloc_trim only returns unused heap pages to the system; any thread may call it.
        unsafe {
            malloc_trim(0);
        }
    }
}

/// Drop `v` on a thread of its own, so that unmapping a large buffer (the 620 MB factor of a
/// 119k-DOF model: ~0.04 s) overlaps the work that follows instead of delaying it; dropped
/// here when no thread can be started.
pub fn drop_in_background<T: Send + 'static>(v: T) {
    // On failure `spawn` drops the closure, and `v` with it, on this thread.
    let _ = std::thread::Builder::new()
        .name("vibrofem-free".into())
        .spawn(move || drop(v));
}

/// Lower the calling thread's scheduling priority to the least (nice 19), so that it runs on
/// cores the others leave idle. Best effort: nothing happens where that is not supported.
pub fn lower_thread_priority() {
    #[cfg(target_os = "linux")]
    {
        unsafe extern "C" {
            fn setpriority(which: i32, who: u32, prio: i32) -> i32;
            fn gettid() -> i32;
        }
        // SAFETY: PRIO_PROCESS (0) with a thread id changes that thread's nice value only.
        unsafe {
            let tid = gettid();
            let _ = setpriority(0, tid as u32, 19);
        }
    }
}

/// Resident set size of this process now (bytes), from /proc/self/status.
pub fn resident_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Peak resident set size of this process (bytes), from /proc/self/status.
pub fn peak_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Memory this process can still use, bytes: the smallest of Linux MemAvailable, the cgroup
/// limit less its usage, and `ulimit -v`/`-d` less the process's size ([`memory_budget`]).
pub fn available_memory() -> Option<u64> {
    memory_budget(None).map(|b| b.bytes)
}

/// Linux MemAvailable, bytes.
fn meminfo_available() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
