//! The memory a job will take, checked against what the machine can give before any work
//! starts: a job that cannot fit is refused with both figures (exit 2), instead of aborting
//! part-way through an allocation or pushing the machine into swap.
//!
//! **The estimate** of a season (`run`, `demo`, the editor's and Python's seasons) is linear
//! in the cells, `bytes = SEASON_FIXED_BYTES + SEASON_BYTES_PER_CELL · cells`: the season's
//! state, its workspace (wind fields, weather maps, the sun of each month, a natural
//! avalanche's flow buffers) and the outputs written at the end all scale with the grid. The
//! two constants are measured, not derived: peak resident memory of `snowscape demo` (the
//! default 100-day winter, every phenomenon on) on the 2-core development VM, 2026-12-07:
//!
//! | cells | peak RSS | bytes a cell |
//! |---|---|---|
//! | 256² | 69 MB | 1050 |
//! | 512² | 274 MB | 1044 |
//! | 1024² | 815 MB | 777 |
//! | 2048² | 2.60 GB | 619 |
//! | 4096² | 8.62 GB | 514 |
//!
//! The per-cell figure is the slope between 1024² and 2048² (593), plus a margin; the
//! fixed part covers the smaller sizes (where per-run buffers of fixed size weigh more). A
//! test (`crates/cli/tests/memory_estimate.rs`) runs seasons and checks the estimate covers
//! their measured peak. Issue 50 brings the per-cell figure down; update the table with it.
//!
//! **What is available** is the smallest of: `MemAvailable` in `/proc/meminfo` (free memory
//! plus the page cache the kernel can drop), the cgroup's `memory.max − memory.current` (a
//! container's limit), and the address-space limit (`ulimit -v`) less what the process
//! already maps. Where none can be read (not Linux), nothing is checked.

use std::fmt;

/// Fixed part of a season's estimate, bytes (module docs).
pub const SEASON_FIXED_BYTES: u64 = 256 << 20;

/// Per-cell part of a season's estimate, bytes a cell (module docs).
pub const SEASON_BYTES_PER_CELL: u64 = 680;

/// Bytes a season on `cells` cells is estimated to take at its peak (module docs).
pub fn season_estimate_bytes(cells: usize) -> u64 {
    SEASON_FIXED_BYTES.saturating_add(SEASON_BYTES_PER_CELL.saturating_mul(cells as u64))
}

/// Where an amount of available memory was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MemorySource {
    /// `MemAvailable` in `/proc/meminfo`.
    MemAvailable,
    /// The cgroup's `memory.max` less its `memory.current`.
    Cgroup,
    /// The address-space limit (`ulimit -v`) less the process's mapped size.
    AddressSpaceLimit,
    /// A budget the user set (`--memory-budget`).
    Budget,
}

impl fmt::Display for MemorySource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::MemAvailable => "MemAvailable in /proc/meminfo",
            Self::Cgroup => "the cgroup's memory.max less memory.current",
            Self::AddressSpaceLimit => "the address-space limit (ulimit -v) less what is mapped",
            Self::Budget => "--memory-budget",
        })
    }
}

/// Memory a job may use, and where that figure came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Available {
    /// Bytes.
    pub bytes: u64,
    /// Where it was read.
    pub source: MemorySource,
}

/// A job that does not fit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "a {job} on {cells} cells needs about {} of memory, and {} is available ({source}); \
     use a smaller grid (or, to run anyway, --memory-budget with the GiB to allow)",
    gib(*needed), gib(available.bytes), source = available.source
)]
pub struct NotEnoughMemory {
    /// The job's name (`season`).
    pub job: &'static str,
    /// Cells of its grid.
    pub cells: usize,
    /// The estimate, bytes.
    pub needed: u64,
    /// What is available.
    pub available: Available,
}

/// `bytes` in GiB with one decimal, for messages.
pub fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / f64::from(1u32 << 30))
}

/// The memory available to this process now (module docs), or `None` where it cannot be read.
pub fn available() -> Option<Available> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    let limits = std::fs::read_to_string("/proc/self/limits").ok();
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let cgroup = cgroup_headroom();
    [
        meminfo
            .as_deref()
            .and_then(|m| kib_field(m, "MemAvailable:"))
            .map(|bytes| Available {
                bytes,
                source: MemorySource::MemAvailable,
            }),
        cgroup.map(|bytes| Available {
            bytes,
            source: MemorySource::Cgroup,
        }),
        limits
            .as_deref()
            .and_then(address_space_limit)
            .map(|limit| {
                let mapped = status
                    .as_deref()
                    .and_then(|s| kib_field(s, "VmSize:"))
                    .unwrap_or(0);
                Available {
                    bytes: limit.saturating_sub(mapped),
                    source: MemorySource::AddressSpaceLimit,
                }
            }),
    ]
    .into_iter()
    .flatten()
    .min_by_key(|a| a.bytes)
}

/// Refuses a job of `needed` bytes on `cells` cells when more than is available: `budget`
/// (bytes, the user's `--memory-budget`) when set, else [`available`].
pub fn check(
    job: &'static str,
    cells: usize,
    needed: u64,
    budget: Option<u64>,
) -> Result<(), NotEnoughMemory> {
    let available = match budget {
        Some(bytes) => Some(Available {
            bytes,
            source: MemorySource::Budget,
        }),
        None => available(),
    };
    match available {
        Some(available) if needed > available.bytes => Err(NotEnoughMemory {
            job,
            cells,
            needed,
            available,
        }),
        _ => Ok(()),
    }
}

/// Checks a season on `cells` cells ([`season_estimate_bytes`], [`check`]).
pub fn check_season(cells: usize, budget: Option<u64>) -> Result<(), NotEnoughMemory> {
    check("season", cells, season_estimate_bytes(cells), budget)
}

/// A `Name:   123 kB` field of a `/proc` file, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The soft "Max address space" of `/proc/self/limits`, bytes (`None` when unlimited).
fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The cgroup (v2, else v1) memory limit less its current use, bytes (`None` without a limit).
fn cgroup_headroom() -> Option<u64> {
    let read = |p: &str| -> Option<u64> { std::fs::read_to_string(p).ok()?.trim().parse().ok() };
    let (limit, used) = match read("/sys/fs/cgroup/memory.max") {
        Some(limit) => (limit, read("/sys/fs/cgroup/memory.current")?),
        None => (
            read("/sys/fs/cgroup/memory/memory.limit_in_bytes")?,
            read("/sys/fs/cgroup/memory/memory.usage_in_bytes")?,
        ),
    };
    // v1 reports "no limit" as a huge page-rounded number.
    (limit < 1 << 60).then(|| limit.saturating_sub(used))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_fields_are_read_in_bytes() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(kib_field(meminfo, "MemAvailable:"), Some(20_000_000 * 1024));
        assert_eq!(kib_field(meminfo, "VmSize:"), None);
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         1073741824           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(1 << 30));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_space_limit(unlimited), None);
    }

    #[test]
    fn a_budget_refuses_what_does_not_fit_and_names_both_figures() {
        let cells = 8192 * 8192;
        let e = check_season(cells, Some(4 << 30)).unwrap_err();
        assert_eq!(e.needed, season_estimate_bytes(cells));
        assert_eq!(e.available.source, MemorySource::Budget);
        let text = e.to_string();
        assert!(
            text.contains("67108864 cells") && text.contains("4.0 GiB"),
            "{text}"
        );
        assert!(check_season(512 * 512, Some(4 << 30)).is_ok());
        // The estimate grows with the cells and never overflows.
        assert!(season_estimate_bytes(2 * cells) > season_estimate_bytes(cells));
        assert_eq!(season_estimate_bytes(usize::MAX), u64::MAX);
    }

    #[test]
    fn this_machine_reports_some_memory() {
        if cfg!(target_os = "linux") {
            let a = available().expect("/proc/meminfo is readable on Linux");
            assert!(a.bytes > 0);
        }
    }
}
