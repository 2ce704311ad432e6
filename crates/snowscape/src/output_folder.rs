//! The output folder of a job (`run`, `demo`, `avalanche`, `cover`, `transport`, `validate`):
//! what may be written or removed in it, and when.
//!
//! Rules (every front end goes through [`OutputFolder`]):
//! - **One job at a time.** Opening the folder takes an exclusive lock on it (an advisory
//!   `flock` on the folder itself); a second job into the same folder is refused with
//!   [`OutputError::Busy`] before it does any work.
//! - **Staged, then committed.** A job writes into a fresh staging folder inside the output
//!   folder ([`STAGING`]). Only when it has written everything does [`OutputFolder::commit`]
//!   move the files into place (renames within one file system), write `report.json` last and
//!   record the files in the folder's manifest ([`MANIFEST`]). A job that fails, or a process
//!   that dies, leaves the previous complete outputs as they were (the staging folder is removed
//!   on failure, or by the next job); it never leaves the files of two runs mixed. A commit
//!   first removes the previous `report.json`, so that a crash inside the commit itself (a
//!   handful of renames) leaves a folder visibly without a report rather than a plausible mix.
//! - **Nothing outside the folder.** Every path written is a plain relative name (no `..`, no
//!   absolute path) and no folder on the way to it may be a symbolic link: a subfolder such as
//!   `frames/` that is a link is refused with [`OutputError::UnsafePath`], never followed.
//! - **Only its own files are removed.** An earlier output that this job did not write again is
//!   removed only if the manifest records it (a file of this program's) and it still has the
//!   size and modification time recorded there. The outputs list of a `report.json` is never
//!   trusted (a prepared or downloaded folder cannot make a run delete anything), and files the
//!   manifest does not record, user files included, are left alone.

use crate::outputs::OutputError;
use serde::{Deserialize, Serialize};
use snowscape_io::write_bytes_atomic;
use std::fs::File;
use std::path::{Component, Path, PathBuf};

/// The manifest of a folder's outputs: name, size and modification time of each file the last
/// committed job wrote.
pub const MANIFEST: &str = ".snowscape-outputs.json";

/// The staging folder a job writes into before its commit.
pub const STAGING: &str = ".snowscape-staging";

/// The job's report, written last by a commit.
pub const REPORT: &str = "report.json";

/// The largest manifest read (a folder's outputs are a few thousand names at most).
const MAX_MANIFEST_BYTES: u64 = 16 << 20;

/// One output as the manifest records it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
struct Recorded {
    /// Relative name inside the folder (`/`-separated).
    name: String,
    /// Size in bytes.
    bytes: u64,
    /// Modification time, nanoseconds since the Unix epoch.
    modified_ns: u128,
}

#[derive(Debug, Serialize, Deserialize)]
struct Manifest {
    /// Always `snowscape-outputs`.
    format: String,
    files: Vec<Recorded>,
}

/// An output folder opened for one job (module docs): locked until dropped.
#[derive(Debug)]
pub struct OutputFolder {
    root: PathBuf,
    staging: PathBuf,
    earlier: Vec<Recorded>,
    /// Earlier outputs already removed by [`OutputFolder::place`].
    retired: Vec<String>,
    /// Files already moved into place by [`OutputFolder::place`].
    placed: Vec<String>,
    committed: bool,
    _lock: File,
}

/// Whether `name` is a plain relative path (only normal components, at least one).
pub fn is_plain_relative(name: &str) -> bool {
    let p = Path::new(name);
    !name.is_empty() && p.components().all(|c| matches!(c, Component::Normal(_)))
}

fn unsafe_path(path: PathBuf, reason: &'static str) -> OutputError {
    OutputError::UnsafePath { path, reason }
}

/// `root/name`, checking that `name` is plain and that no folder between `root` and the file
/// is a symbolic link or a non-folder; missing folders are created when `create` is set.
fn resolve_inside(root: &Path, name: &str, create: bool) -> Result<PathBuf, OutputError> {
    if !is_plain_relative(name) {
        return Err(unsafe_path(
            root.join(name),
            "is not a plain name inside the output folder",
        ));
    }
    let rel = Path::new(name);
    let mut path = root.to_path_buf();
    let count = rel.components().count();
    for (k, c) in rel.components().enumerate() {
        path.push(c);
        if k + 1 == count {
            break;
        }
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                return Err(unsafe_path(path, "is a symbolic link (never followed)"));
            }
            Ok(m) if !m.is_dir() => return Err(unsafe_path(path, "is not a folder")),
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && create => {
                std::fs::create_dir(&path).map_err(|source| OutputError::CreateFolder {
                    path: path.clone(),
                    source,
                })?;
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(source) => return Err(OutputError::CreateFolder { path, source }),
        }
    }
    Ok(path)
}

fn modified_ns(m: &std::fs::Metadata) -> u128 {
    m.modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos())
}

/// Locks `root` for this process (an exclusive advisory lock on the folder itself).
fn lock(root: &Path) -> Result<File, OutputError> {
    #[cfg(unix)]
    let file = File::open(root);
    #[cfg(not(unix))]
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(root.join(".snowscape-lock"));
    let file = file.map_err(|source| OutputError::NotWritable {
        path: root.to_path_buf(),
        source,
    })?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(std::fs::TryLockError::WouldBlock) => Err(OutputError::Busy {
            path: root.to_path_buf(),
        }),
        Err(std::fs::TryLockError::Error(source)) => Err(OutputError::NotWritable {
            path: root.to_path_buf(),
            source,
        }),
    }
}

/// Removes `path` whatever it is (a link is removed, not followed); missing is fine.
fn remove_any(path: &Path) -> std::io::Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path),
        Ok(_) => std::fs::remove_file(path),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
    }
}

fn read_manifest(root: &Path) -> Vec<Recorded> {
    let path = root.join(MANIFEST);
    let Ok(m) = std::fs::symlink_metadata(&path) else {
        return Vec::new();
    };
    if !m.is_file() || m.len() > MAX_MANIFEST_BYTES {
        tracing::warn!(
            "{}: not a regular file of at most {MAX_MANIFEST_BYTES} bytes; earlier outputs are left alone",
            path.display()
        );
        return Vec::new();
    }
    let parsed = std::fs::read(&path)
        .ok()
        .and_then(|b| serde_json::from_slice::<Manifest>(&b).ok())
        .filter(|m| m.format == "snowscape-outputs");
    match parsed {
        Some(m) => m
            .files
            .into_iter()
            .filter(|r| is_plain_relative(&r.name))
            .collect(),
        None => {
            tracing::warn!(
                "{}: unreadable manifest; earlier outputs are left alone",
                path.display()
            );
            Vec::new()
        }
    }
}

impl OutputFolder {
    /// Opens `root` for a job: creates it (and its parents), locks it, checks it can be
    /// written into, removes what an interrupted job left (its staging folder, the atomic
    /// writer's temporary files) and prepares a fresh staging folder.
    pub fn open(root: &Path) -> Result<Self, OutputError> {
        std::fs::create_dir_all(root).map_err(|source| OutputError::CreateFolder {
            path: root.to_path_buf(),
            source,
        })?;
        let lock = lock(root)?;
        crate::outputs::prepare_dir(root)?;
        let staging = root.join(STAGING);
        remove_any(&staging).map_err(|source| OutputError::NotWritable {
            path: staging.clone(),
            source,
        })?;
        std::fs::create_dir(&staging).map_err(|source| OutputError::NotWritable {
            path: staging.clone(),
            source,
        })?;
        Ok(Self {
            root: root.to_path_buf(),
            staging,
            earlier: read_manifest(root),
            retired: Vec::new(),
            placed: Vec::new(),
            committed: false,
            _lock: lock,
        })
    }

    /// The output folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The folder this job writes into (moved into place by [`OutputFolder::commit`]).
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// Checks, before any work, that the job can write the subfolder `name` of the output folder:
    /// absent, or a real folder (a symbolic link is refused, never followed).
    pub fn check_subfolder(&self, name: &str) -> Result<(), OutputError> {
        let path = self.root.join(name);
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                Err(unsafe_path(path, "is a symbolic link (never followed)"))
            }
            Ok(m) if !m.is_dir() => Err(unsafe_path(path, "is not a folder")),
            _ => Ok(()),
        }
    }

    /// The staging path of `name`, its folders created (a plain relative name).
    pub fn staged(&self, name: &str) -> Result<PathBuf, OutputError> {
        resolve_inside(&self.staging, name, true)
    }

    /// The outputs the last committed job recorded in this folder.
    pub fn earlier(&self) -> Vec<String> {
        self.earlier.iter().map(|r| r.name.clone()).collect()
    }

    /// The earlier outputs a commit of `files` would remove: recorded, not written again, and
    /// still the file that was recorded (same size and modification time).
    pub fn stale(&self, files: &[String]) -> Vec<String> {
        let now: std::collections::HashSet<&str> = files.iter().map(String::as_str).collect();
        let mut stale: Vec<String> = self
            .retired
            .iter()
            .filter(|n| !now.contains(n.as_str()))
            .cloned()
            .collect();
        stale.extend(
            self.earlier
                .iter()
                .filter(|r| !now.contains(r.name.as_str()) && r.name != REPORT)
                .filter(|r| self.still_recorded(r))
                .map(|r| r.name.clone()),
        );
        stale
    }

    /// Moves the staged `files` into place before the job ends (a periodic checkpoint and the
    /// frames it resumes with, so that a run killed later can resume). The first call retires
    /// the previous run: its report and its recorded outputs are removed, so the folder never
    /// holds a mix of the two runs (it holds this run's files so far and no report).
    pub fn place(&mut self, files: &[String]) -> Result<(), OutputError> {
        let moves = self.checked_moves(files)?;
        if self.placed.is_empty() {
            self.remove_report()?;
            let earlier = std::mem::take(&mut self.earlier);
            for r in earlier.iter().filter(|r| r.name != REPORT) {
                if self.still_recorded(r) {
                    self.remove_output(&r.name);
                    self.retired.push(r.name.clone());
                }
            }
        }
        for (name, from, to) in moves {
            std::fs::rename(&from, &to)
                .map_err(|source| OutputError::Commit { path: to, source })?;
            if !self.placed.contains(&name) {
                self.placed.push(name);
            }
        }
        let placed = self.placed.clone();
        self.write_manifest(&placed)
    }

    /// The (name, staged path, final path) of each of `files` that is staged, every target
    /// checked; `files` already placed and not staged again are skipped.
    fn checked_moves(
        &self,
        files: &[String],
    ) -> Result<Vec<(String, PathBuf, PathBuf)>, OutputError> {
        let mut names: Vec<&str> = files
            .iter()
            .map(String::as_str)
            .filter(|&n| n != REPORT)
            .collect();
        names.sort_unstable();
        names.dedup();
        let mut moves = Vec::with_capacity(names.len());
        for name in names {
            let from = resolve_inside(&self.staging, name, false)?;
            if !std::fs::symlink_metadata(&from).is_ok_and(|m| m.is_file()) {
                if self.placed.iter().any(|p| p == name) {
                    continue;
                }
                return Err(OutputError::NotStaged {
                    path: from,
                    name: name.to_string(),
                });
            }
            let to = resolve_inside(&self.root, name, true)?;
            if std::fs::symlink_metadata(&to).is_ok_and(|m| m.is_dir()) {
                return Err(unsafe_path(to, "is a folder where an output file goes"));
            }
            moves.push((name.to_string(), from, to));
        }
        Ok(moves)
    }

    /// Removes the folder's `report.json` (a link is removed, not followed).
    fn remove_report(&self) -> Result<(), OutputError> {
        let path = self.root.join(REPORT);
        if std::fs::symlink_metadata(&path).is_ok_and(|m| !m.is_dir()) {
            remove_any(&path).map_err(|source| OutputError::NotWritable { path, source })?;
        }
        Ok(())
    }

    /// Removes the earlier output `name` (checked by the caller against its record).
    fn remove_output(&self, name: &str) {
        let Ok(path) = resolve_inside(&self.root, name, false) else {
            return;
        };
        match std::fs::remove_file(&path) {
            Ok(()) => tracing::info!("removed stale output {}", path.display()),
            Err(e) => tracing::warn!("cannot remove stale output {}: {e}", path.display()),
        }
    }

    /// Records `names` (files in place in the folder) in the manifest.
    fn write_manifest(&self, names: &[String]) -> Result<(), OutputError> {
        let files = names
            .iter()
            .filter_map(|name| {
                let m = std::fs::symlink_metadata(self.root.join(name)).ok()?;
                Some(Recorded {
                    name: name.clone(),
                    bytes: m.len(),
                    modified_ns: modified_ns(&m),
                })
            })
            .collect();
        let manifest = Manifest {
            format: "snowscape-outputs".into(),
            files,
        };
        let text = serde_json::to_vec_pretty(&manifest).map_err(OutputError::Report)?;
        write_bytes_atomic(&self.root.join(MANIFEST), &text)?;
        Ok(())
    }

    fn still_recorded(&self, r: &Recorded) -> bool {
        let Ok(path) = resolve_inside(&self.root, &r.name, false) else {
            return false;
        };
        std::fs::symlink_metadata(&path)
            .is_ok_and(|m| m.is_file() && m.len() == r.bytes && modified_ns(&m) == r.modified_ns)
    }

    /// Moves the staged `files` (relative names, in the staging folder) into the output folder,
    /// writes `report` as `report.json` when given (or moves a staged `report.json` that `files`
    /// lists, last), records them all in the manifest and removes
    /// the earlier outputs that are [stale](OutputFolder::stale) (a report lists them from
    /// [`OutputFolder::stale`] before the commit). Every target is checked before anything
    /// moves.
    pub fn commit(mut self, files: &[String], report: Option<&[u8]>) -> Result<(), OutputError> {
        let moves = self.checked_moves(files)?;
        let stale = self.stale(files);
        self.remove_report()?;
        for (_, from, to) in moves {
            std::fs::rename(&from, &to)
                .map_err(|source| OutputError::Commit { path: to, source })?;
        }
        let mut recorded: Vec<String> = files.iter().filter(|n| *n != REPORT).cloned().collect();
        recorded.sort_unstable();
        recorded.dedup();
        let staged_report = self.staging.join(REPORT);
        if let Some(bytes) = report {
            write_bytes_atomic(&self.root.join(REPORT), bytes)?;
            recorded.push(REPORT.to_string());
        } else if files.iter().any(|n| n == REPORT)
            && std::fs::symlink_metadata(&staged_report).is_ok_and(|m| m.is_file())
        {
            // A report the job wrote itself goes last.
            let to = self.root.join(REPORT);
            std::fs::rename(&staged_report, &to)
                .map_err(|source| OutputError::Commit { path: to, source })?;
            recorded.push(REPORT.to_string());
        }
        self.write_manifest(&recorded)?;
        for name in stale.iter().filter(|n| !self.retired.contains(n)) {
            self.remove_output(name);
        }
        self.committed = true;
        if let Err(e) = std::fs::remove_dir_all(&self.staging) {
            tracing::warn!("cannot remove {}: {e}", self.staging.display());
        }
        Ok(())
    }
}

impl Drop for OutputFolder {
    fn drop(&mut self) {
        if !self.committed {
            let _ = remove_any(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests;
