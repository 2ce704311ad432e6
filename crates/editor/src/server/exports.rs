//! Downloads of the project's files: an export as one zip (`GET /api/export/<name>`),
//! streamed as it is deflated, [`MAX_CONCURRENT_EXPORTS`] at once, and a single file of the
//! project folder (`GET /files/<path>`), each at most [`MAX_DOWNLOAD`] bytes.

use super::{AppState, reply};
use crate::project::ProjectError;
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use tokio::sync::mpsc;

/// Largest project file served for download, and most bytes of files in one export zip.
pub const MAX_DOWNLOAD: u64 = 1 << 30;
/// Export zips sent at once (`GET /api/export/<name>`); more are refused with 429. Each is
/// streamed as it is deflated (a few blocks of [`ZIP_BLOCK_BYTES`] in memory, whatever its
/// size).
pub const MAX_CONCURRENT_EXPORTS: usize = 1;
/// Size of the blocks an export zip is sent in, bytes.
pub const ZIP_BLOCK_BYTES: usize = 64 << 10;

/// Where the zip writer's blocks go: a bounded channel to the response body, so that a slow
/// client holds the writer back rather than the blocks piling up in memory.
struct ChannelWriter {
    tx: mpsc::Sender<Result<axum::body::Bytes, std::io::Error>>,
    buf: Vec<u8>,
}

impl ChannelWriter {
    fn send_block(&mut self) -> std::io::Result<()> {
        if self.buf.is_empty() {
            return Ok(());
        }
        let block = std::mem::replace(&mut self.buf, Vec::with_capacity(ZIP_BLOCK_BYTES));
        self.tx
            .blocking_send(Ok(block.into()))
            .map_err(|_| std::io::Error::new(std::io::ErrorKind::BrokenPipe, "the client left"))
    }
}

impl std::io::Write for ChannelWriter {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        let n = data.len().min(ZIP_BLOCK_BYTES - self.buf.len());
        self.buf.extend_from_slice(&data[..n]);
        if self.buf.len() >= ZIP_BLOCK_BYTES {
            self.send_block()?;
        }
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.send_block()
    }
}

/// The response body of an export zip: the blocks the writer sends.
struct ZipBody(mpsc::Receiver<Result<axum::body::Bytes, std::io::Error>>);

impl futures_core::Stream for ZipBody {
    type Item = Result<axum::body::Bytes, std::io::Error>;

    fn poll_next(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<Option<Self::Item>> {
        self.0.poll_recv(cx)
    }
}

/// An export's files as one zip (`GET /api/export/<name>`, named `<name>.zip`), streamed as it
/// is deflated; [`MAX_CONCURRENT_EXPORTS`] at once (429 beyond), at most [`MAX_DOWNLOAD`]
/// bytes of files (400 beyond); 404 for no such export.
pub(super) async fn export_zip_handler(
    State(s): State<AppState>,
    axum::extract::Path(name): axum::extract::Path<String>,
) -> Response {
    let Ok(permit) = s.exports.clone().try_acquire_owned() else {
        return reply(
            StatusCode::TOO_MANY_REQUESTS,
            format!(
                "export {name:?}: another export zip is being sent (at most {MAX_CONCURRENT_EXPORTS} at a time); try again when it ends"
            ),
        );
    };
    let project = s.project.clone();
    let n = name.clone();
    // Refusals before anything is sent.
    match tokio::task::spawn_blocking(move || project.export_files(&n, MAX_DOWNLOAD)).await {
        Ok(Ok(_)) => {}
        Ok(Err(ProjectError::NotFound(n))) => {
            return reply(StatusCode::NOT_FOUND, format!("no export {n:?}"));
        }
        Ok(Err(e)) => return reply(StatusCode::BAD_REQUEST, e.to_string()),
        Err(_) => return StatusCode::INTERNAL_SERVER_ERROR.into_response(),
    }
    let (tx, rx) = mpsc::channel(4);
    let project = s.project.clone();
    let n = name.clone();
    tokio::task::spawn_blocking(move || {
        let _permit = permit;
        let mut out = ChannelWriter {
            tx: tx.clone(),
            buf: Vec::with_capacity(ZIP_BLOCK_BYTES),
        };
        let written = project
            .write_export_zip(&n, MAX_DOWNLOAD, &mut out)
            .and_then(|()| {
                std::io::Write::flush(&mut out).map_err(|e| ProjectError::Io {
                    path: format!("exports/{n}"),
                    source: e,
                })
            });
        if let Err(e) = written {
            tracing::warn!("the zip of export {n} stopped: {e}");
            let _ = tx.blocking_send(Err(std::io::Error::other(e.to_string())));
        }
    });
    (
        [
            (header::CONTENT_TYPE, "application/zip".to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{name}.zip\""),
            ),
        ],
        axum::body::Body::from_stream(ZipBody(rx)),
    )
        .into_response()
}

pub(super) async fn file_handler(
    State(s): State<AppState>,
    axum::extract::Path(path): axum::extract::Path<String>,
) -> Response {
    match s.project.read(&path, MAX_DOWNLOAD) {
        Ok(bytes) => {
            let name = path.rsplit('/').next().unwrap_or("file").to_string();
            (
                [
                    (header::CONTENT_TYPE, crate::assets::mime(&path).to_string()),
                    (
                        header::CONTENT_DISPOSITION,
                        format!("attachment; filename=\"{name}\""),
                    ),
                ],
                bytes,
            )
                .into_response()
        }
        Err(ProjectError::NotFound(_)) => (StatusCode::NOT_FOUND, "not found").into_response(),
        Err(e @ (ProjectError::BadPath(_) | ProjectError::Escapes(_))) => {
            (StatusCode::FORBIDDEN, e.to_string()).into_response()
        }
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response(),
    }
}
