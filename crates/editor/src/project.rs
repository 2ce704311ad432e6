//! The project folder: the only place the server reads and writes.
//!
//! A project saved under `NAME` is the folder `projects/NAME/` holding `bedrock.tif` (the
//! terrain), `scenario.toml`, `checkpoint.bin` (the season's state: snow layers, clock,
//! scheduler, budget, as `snowscape run --resume` uses them), `avalanche_probability.tif` and
//! `ski_area.tif` (the painted maps) and `history.json` (what the user did, and the
//! timeline's snapshot days). Exports go to `exports/NAME/`.
//!
//! Every path is checked by [`ProjectDir::resolve`]: relative, no `..`, no root or prefix,
//! and once resolved (symbolic links followed) still inside the canonical project folder.
//! The paths a scenario names (`forcing`) are held to the same rule, relative to the
//! project's folder, when it is saved and loaded ([`ProjectError::ScenarioPath`]).

use crate::brush::PaintMaps;
use crate::history::{Action, ProjectHistory};
use crate::session::Session;
use snowscape::season_run::{CHECKPOINT, RESOLVED_SCENARIO};
use snowscape_io::{ReadOptions, read_dem, read_terrain, write_bytes_atomic, write_geotiff};
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::LayeredTerrain;
use std::path::{Component, Path, PathBuf};
use thiserror::Error;

/// A project-folder error; each names the offending path or value.
#[derive(Debug, Error)]
pub enum ProjectError {
    #[error("path {0:?} is not allowed: it must be relative and stay inside the project folder")]
    BadPath(String),
    #[error("path {0:?} leaves the project folder (through a symbolic link)")]
    Escapes(String),
    #[error("project {0:?} does not exist in the project folder")]
    NotFound(String),
    #[error("cannot use the project folder {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error(transparent)]
    ScenarioPath(#[from] crate::page_scenario::ScenarioPathError),
    #[error("{what} {path}: {reason}")]
    Content {
        what: &'static str,
        path: String,
        reason: String,
    },
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ProjectError + '_ {
    move |source| ProjectError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// A saved project, as listed for the page.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SavedProject {
    pub name: String,
    /// The season day it was saved at.
    pub day: Option<f64>,
}

/// The project folder.
#[derive(Debug, Clone)]
pub struct ProjectDir {
    root: PathBuf,
}

/// What a project saves, copied out of a session so that the files are written off the
/// request path (a save is a job: [`crate::job`]).
pub struct ProjectContents {
    pub winter: Winter,
    pub paint: PaintMaps,
    /// Where the session's terrain came from.
    pub source: String,
    pub snapshot_days: Vec<f64>,
    pub history: Vec<Action>,
}

impl ProjectContents {
    /// A copy of what `session` would save now.
    pub fn of(session: &Session) -> Self {
        Self {
            winter: session.winter().clone(),
            paint: session.paint().clone(),
            source: session.summary().source,
            snapshot_days: session.timeline.days(),
            history: session.history.clone(),
        }
    }
}

impl ProjectDir {
    /// Opens (creating if missing) the project folder `dir`.
    pub fn open(dir: &Path) -> Result<Self, ProjectError> {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let root = dir.canonicalize().map_err(io_err(dir))?;
        Ok(Self { root })
    }

    /// The canonical folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The path of `rel` inside the project folder. Refuses absolute paths, `..`, and paths
    /// whose existing part resolves (through symbolic links) outside the folder.
    pub fn resolve(&self, rel: &str) -> Result<PathBuf, ProjectError> {
        let p = Path::new(rel);
        if rel.is_empty()
            || rel.len() > 512
            || rel.contains('\0')
            || rel.contains('\\')
            || !p.components().all(|c| matches!(c, Component::Normal(_)))
        {
            return Err(ProjectError::BadPath(rel.chars().take(200).collect()));
        }
        let full = self.root.join(p);
        // The deepest existing ancestor must resolve inside the root.
        let mut existing = full.as_path();
        while !existing.exists() {
            match existing.parent() {
                Some(parent) => existing = parent,
                None => break,
            }
        }
        let canon = existing.canonicalize().map_err(io_err(existing))?;
        if !canon.starts_with(&self.root) {
            return Err(ProjectError::Escapes(rel.chars().take(200).collect()));
        }
        Ok(full)
    }

    /// Creates the folder `rel` inside the project folder.
    pub fn create_dir(&self, rel: &str) -> Result<PathBuf, ProjectError> {
        let p = self.resolve(rel)?;
        std::fs::create_dir_all(&p).map_err(io_err(&p))?;
        // Created folders may not replace a link planted meanwhile.
        let canon = p.canonicalize().map_err(io_err(&p))?;
        if !canon.starts_with(&self.root) {
            return Err(ProjectError::Escapes(rel.into()));
        }
        Ok(p)
    }

    /// Reads the file `rel` (for downloads), at most `max` bytes.
    pub fn read(&self, rel: &str, max: u64) -> Result<Vec<u8>, ProjectError> {
        let p = self.resolve(rel)?;
        let canon = p
            .canonicalize()
            .map_err(|_| ProjectError::NotFound(rel.into()))?;
        if !canon.starts_with(&self.root) {
            return Err(ProjectError::Escapes(rel.into()));
        }
        let meta = std::fs::metadata(&canon).map_err(io_err(&canon))?;
        if !meta.is_file() {
            return Err(ProjectError::NotFound(rel.into()));
        }
        if meta.len() > max {
            return Err(ProjectError::Content {
                what: "file",
                path: rel.into(),
                reason: format!("{} bytes is more than the {max} bytes served", meta.len()),
            });
        }
        std::fs::read(&canon).map_err(io_err(&canon))
    }

    /// The saved projects (folders under `projects/` holding a checkpoint), by name, each with
    /// the day it was saved at (from its history, when readable).
    pub fn list(&self) -> Vec<SavedProject> {
        let Ok(dir) = self.resolve("projects") else {
            return Vec::new();
        };
        let Ok(entries) = std::fs::read_dir(&dir) else {
            return Vec::new();
        };
        let mut out: Vec<SavedProject> = entries
            .filter_map(Result::ok)
            .filter_map(|e| {
                let name = e.file_name().into_string().ok()?;
                crate::protocol::check_name(&name).ok()?;
                let path = e.path();
                path.join(CHECKPOINT).is_file().then(|| {
                    let day = self
                        .read(&format!("projects/{name}/history.json"), 1 << 24)
                        .ok()
                        .and_then(|b| serde_json::from_slice::<ProjectHistory>(&b).ok())
                        .map(|h| h.day);
                    SavedProject { name, day }
                })
            })
            .collect();
        out.sort_by(|a, b| a.name.cmp(&b.name));
        out
    }

    /// The files of export `name` (`exports/<name>/`), for its zip: their paths relative to
    /// the project folder, checked through [`Self::resolve`] (no link leaves the folder), and
    /// at most `max` bytes in all. Refusals come before anything is sent.
    pub fn export_files(&self, name: &str, max: u64) -> Result<Vec<String>, ProjectError> {
        crate::protocol::check_name(name).map_err(|e| ProjectError::BadPath(e.to_string()))?;
        let rel = format!("exports/{name}");
        let dir = self.resolve(&rel)?;
        if !dir.is_dir() {
            return Err(ProjectError::NotFound(name.into()));
        }
        let mut files: Vec<String> = std::fs::read_dir(&dir)
            .map_err(io_err(&dir))?
            .filter_map(Result::ok)
            .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
            .filter_map(|e| e.file_name().into_string().ok())
            .map(|f| format!("{rel}/{f}"))
            .collect();
        files.sort();
        let mut total = 0u64;
        for f in &files {
            let (_, len) = self.open_file(f)?;
            total = total.saturating_add(len);
            if total > max {
                return Err(ProjectError::Content {
                    what: "export",
                    path: rel,
                    reason: format!("more than the {max} bytes served as one zip"),
                });
            }
        }
        Ok(files)
    }

    /// Opens the file `rel` for reading: checked as [`Self::read`] does; with its length.
    fn open_file(&self, rel: &str) -> Result<(std::fs::File, u64), ProjectError> {
        let p = self.resolve(rel)?;
        let canon = p
            .canonicalize()
            .map_err(|_| ProjectError::NotFound(rel.into()))?;
        if !canon.starts_with(&self.root) {
            return Err(ProjectError::Escapes(rel.into()));
        }
        let file = std::fs::File::open(&canon).map_err(io_err(&canon))?;
        let meta = file.metadata().map_err(io_err(&canon))?;
        if !meta.is_file() {
            return Err(ProjectError::NotFound(rel.into()));
        }
        Ok((file, meta.len()))
    }

    /// Writes export `name` as one zip archive to `out` as it goes (deflated; `out` need not
    /// seek, so the archive streams to the network and is never whole in memory): the files
    /// [`Self::export_files`] lists, each copied in small blocks, at most `max` bytes in all
    /// (a file that grew meanwhile is cut there and the archive refused).
    pub fn write_export_zip(
        &self,
        name: &str,
        max: u64,
        out: impl std::io::Write,
    ) -> Result<(), ProjectError> {
        use std::io::Read;
        let files = self.export_files(name, max)?;
        let mut zip = zip::ZipWriter::new_stream(out);
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated)
            .large_file(max >= u64::from(u32::MAX));
        let zip_err = |e: zip::result::ZipError| ProjectError::Content {
            what: "zip",
            path: format!("exports/{name}"),
            reason: e.to_string(),
        };
        let mut left = max;
        for f in files {
            let (file, _) = self.open_file(&f)?;
            let short = f.rsplit('/').next().unwrap_or(&f);
            zip.start_file(format!("{name}/{short}"), options)
                .map_err(zip_err)?;
            let copied = std::io::copy(&mut file.take(left.saturating_add(1)), &mut zip)
                .map_err(io_err(Path::new(&f)))?;
            if copied > left {
                return Err(ProjectError::Content {
                    what: "export",
                    path: f,
                    reason: format!("more than the {max} bytes served as one zip"),
                });
            }
            left -= copied;
        }
        zip.finish().map_err(zip_err)?;
        Ok(())
    }

    /// Export `name` as one zip archive in memory ([`Self::write_export_zip`]; tests).
    pub fn export_zip(&self, name: &str, max: u64) -> Result<Vec<u8>, ProjectError> {
        let mut out = Vec::new();
        self.write_export_zip(name, max, &mut out)?;
        Ok(out)
    }

    /// Saves the session as project `name`; returns the written files (relative).
    pub fn save(&self, name: &str, s: &ProjectContents) -> Result<Vec<String>, ProjectError> {
        crate::protocol::check_name(name).map_err(|e| ProjectError::BadPath(e.to_string()))?;
        let dir_rel = format!("projects/{name}");
        let dir = self.create_dir(&dir_rel)?;
        let w = &s.winter;
        let t = &w.terrain;
        let content = |what: &'static str, path: &Path| {
            let path = path.display().to_string();
            move |e: String| ProjectError::Content {
                what,
                path,
                reason: e,
            }
        };
        let mut files = Vec::new();
        let mut put = |file: &str| {
            files.push(format!("{dir_rel}/{file}"));
            dir.join(file)
        };
        let p = put("bedrock.tif");
        let grid = t
            .to_grid(t.bedrock.clone())
            .map_err(|e| content("terrain", &p)(e.to_string()))?;
        write_geotiff(&p, &grid).map_err(|e| content("terrain", &p)(e.to_string()))?;
        for (file, values) in [
            ("avalanche_probability.tif", &s.paint.avalanche_probability),
            ("ski_area.tif", &s.paint.ski_area),
        ] {
            let p = put(file);
            let grid = t
                .to_grid(values.clone())
                .map_err(|e| content("map", &p)(e.to_string()))?;
            write_geotiff(&p, &grid).map_err(|e| content("map", &p)(e.to_string()))?;
        }
        crate::page_scenario::check_scenario_paths(w.scenario(), Some((self, &dir_rel)))?;
        let p = put(RESOLVED_SCENARIO);
        let text =
            toml::to_string(w.scenario()).map_err(|e| content("scenario", &p)(e.to_string()))?;
        write_bytes_atomic(&p, text.as_bytes())
            .map_err(|e| content("scenario", &p)(e.to_string()))?;
        let p = put(CHECKPOINT);
        let mut bytes = Vec::new();
        w.write_checkpoint(&mut bytes)
            .map_err(|e| content("checkpoint", &p)(e.to_string()))?;
        write_bytes_atomic(&p, &bytes).map_err(|e| content("checkpoint", &p)(e.to_string()))?;
        let p = put("history.json");
        let history = ProjectHistory {
            source: s.source.clone(),
            day: w.day(),
            snapshot_days: s.snapshot_days.clone(),
            actions: s.history.clone(),
        };
        let text = serde_json::to_vec_pretty(&history)
            .map_err(|e| content("history", &p)(e.to_string()))?;
        write_bytes_atomic(&p, &text).map_err(|e| content("history", &p)(e.to_string()))?;
        Ok(files)
    }

    /// Loads project `name` (its season at the saved day; the timeline starts there).
    pub fn load(&self, name: &str) -> Result<Session, ProjectError> {
        crate::protocol::check_name(name).map_err(|e| ProjectError::BadPath(e.to_string()))?;
        let dir = self.resolve(&format!("projects/{name}"))?;
        if !dir.join(CHECKPOINT).is_file() {
            return Err(ProjectError::NotFound(name.into()));
        }
        let file = |f: &str| self.resolve(&format!("projects/{name}/{f}"));
        let bad = |what: &'static str, p: &Path, e: String| ProjectError::Content {
            what,
            path: p.display().to_string(),
            reason: e,
        };
        let p = file("bedrock.tif")?;
        let bedrock = read_terrain(&p, &ReadOptions::default())
            .map_err(|e| bad("terrain", &p, e.to_string()))?;
        let p = file(RESOLVED_SCENARIO)?;
        let text = std::fs::read_to_string(&p).map_err(io_err(&p))?;
        let scenario = Scenario::from_toml(&text, &p.display().to_string())
            .map_err(|e| bad("scenario", &p, e.to_string()))?;
        crate::page_scenario::check_scenario_paths(
            &scenario,
            Some((self, &format!("projects/{name}"))),
        )?;
        let p = file(CHECKPOINT)?;
        let terrain = LayeredTerrain::from_bedrock(bedrock);
        let n = terrain.geometry().len();
        // Only a regular file of at most the terrain's largest checkpoint is read.
        let winter = Winter::resume_from_file(scenario, terrain, None, &p)
            .map_err(|e| bad("checkpoint", &p, e.to_string()))?;
        let mut paint = PaintMaps::new(n);
        for (f, dst) in [
            (
                "avalanche_probability.tif",
                &mut paint.avalanche_probability,
            ),
            ("ski_area.tif", &mut paint.ski_area),
        ] {
            let p = file(f)?;
            let g =
                read_dem(&p, &ReadOptions::default()).map_err(|e| bad("map", &p, e.to_string()))?;
            if g.data().len() != n {
                return Err(bad(
                    "map",
                    &p,
                    format!("{} cells, the terrain has {n}", g.data().len()),
                ));
            }
            for (d, v) in dst.iter_mut().zip(g.data()) {
                *d = if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    0.0
                };
            }
        }
        let p = file("history.json")?;
        // The history is a record, not the state: one that cannot be read (an older or edited
        // file) starts afresh rather than refusing the project.
        let history: Option<ProjectHistory> = std::fs::read(&p)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok());
        let source = history
            .as_ref()
            .map_or_else(|| name.to_string(), |h| h.source.clone());
        let mut s = Session::with_paint(winter, paint, source);
        if let Some(h) = history {
            s.history = h.actions;
        }
        s.history.push(Action::Load {
            name: name.to_string(),
        });
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_refuses_traversal_absolute_and_links_out() {
        let tmp = tempfile::tempdir().unwrap();
        let pd = ProjectDir::open(&tmp.path().join("proj")).unwrap();
        assert!(
            pd.resolve("projects/a/b.tif")
                .unwrap()
                .starts_with(pd.root())
        );
        for bad in [
            "../x",
            "a/../../x",
            "/etc/passwd",
            "",
            "a\\..\\b",
            "./a",
            "a//../b",
        ] {
            assert!(pd.resolve(bad).is_err(), "{bad:?} was accepted");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(tmp.path(), pd.root().join("out")).unwrap();
            assert!(matches!(
                pd.resolve("out/secret"),
                Err(ProjectError::Escapes(_))
            ));
            assert!(pd.read("out/secret", 1000).is_err());
        }
        assert!(matches!(
            pd.read("nothing.txt", 1000),
            Err(ProjectError::NotFound(_))
        ));
    }
}
