//! The page's files: embedded in the binary at build time from `web/dist` (when the page was
//! built before the binary), else read from a folder given on the command line or found
//! beside the binary (`<binary dir>/web`). The editor of Cordonnier et al. 2018, Section 3 runs
//! in the browser; its JavaScript is built by `npm run build` in `web/`.

use rust_embed::RustEmbed;
use std::borrow::Cow;
use std::path::{Component, Path, PathBuf};

#[derive(RustEmbed)]
#[folder = "../../web/dist/"]
#[allow_missing = true]
struct Embedded;

/// How to build the page, printed when no page is found.
pub const BUILD_HINT: &str = "the editor page is not built: run `bash scripts/serve.sh` (or `cd web && npm ci && npm run build`, then rebuild snowscape or pass --web-dir web/dist)";

/// Where the page's files come from.
#[derive(Debug, Clone)]
pub enum Assets {
    /// Embedded in the binary.
    Embedded,
    /// A folder on disk.
    Folder(PathBuf),
    /// Nowhere: the server answers with [`BUILD_HINT`].
    Missing,
}

impl Assets {
    /// The folder `dir` if given, else the embedded files, else `web/` or `web/dist/` beside
    /// the binary.
    pub fn find(dir: Option<&Path>) -> Assets {
        if let Some(d) = dir {
            return if d.join("index.html").is_file() {
                Assets::Folder(d.to_path_buf())
            } else {
                Assets::Missing
            };
        }
        if Embedded::get("index.html").is_some() {
            return Assets::Embedded;
        }
        if let Some(exe_dir) = std::env::current_exe()
            .ok()
            .and_then(|e| e.parent().map(Path::to_path_buf))
        {
            for d in [exe_dir.join("web"), exe_dir.join("web/dist")] {
                if d.join("index.html").is_file() {
                    return Assets::Folder(d);
                }
            }
        }
        Assets::Missing
    }

    /// The bytes and MIME type of `path` (relative, `/`-separated; empty for the index).
    pub fn get(&self, path: &str) -> Option<(Cow<'static, [u8]>, &'static str)> {
        let path = if path.is_empty() { "index.html" } else { path };
        let p = Path::new(path);
        if !p.components().all(|c| matches!(c, Component::Normal(_))) {
            return None;
        }
        let bytes = match self {
            Assets::Embedded => Embedded::get(path)?.data,
            Assets::Folder(d) => {
                let full = d.join(p);
                let canon = full.canonicalize().ok()?;
                if !canon.starts_with(d.canonicalize().ok()?) || !canon.is_file() {
                    return None;
                }
                Cow::Owned(std::fs::read(canon).ok()?)
            }
            Assets::Missing => return None,
        };
        Some((bytes, mime(path)))
    }
}

/// The MIME type of a file name.
pub fn mime(path: &str) -> &'static str {
    match path.rsplit('.').next().unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" | "map" => "application/json",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "ico" => "image/x-icon",
        "wasm" => "application/wasm",
        "tif" | "tiff" => "image/tiff",
        "gif" => "image/gif",
        "glb" => "model/gltf-binary",
        "toml" | "txt" | "geojson" => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}
