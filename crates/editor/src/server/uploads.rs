//! DEM uploads from the page (`POST /api/dem?name=FILE.ext`): at most [`MAX_DEM_UPLOAD`]
//! bytes (413 from the `Content-Length`, or as soon as the body passes it),
//! [`MAX_CONCURRENT_UPLOADS`] at once (429 beyond), written to the project folder as they
//! arrive and imported by a job; an upload that is refused or fails is removed.

use super::{AppState, Command, ask, reply};
use crate::protocol::ErrorCode;
use axum::extract::{Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

/// Largest DEM upload, bytes (a 4096² float32 GeoTIFF is 64 MiB; ASCII grids take ~3 times as
/// much): refused with 413 from its `Content-Length`, or as soon as the body passes it.
pub const MAX_DEM_UPLOAD: usize = 256 << 20;
/// DEM uploads received at once; more are refused with 429. An upload is written to the
/// project folder as it arrives (never whole in memory).
pub const MAX_CONCURRENT_UPLOADS: usize = 1;

#[derive(serde::Deserialize)]
pub(super) struct DemQuery {
    name: String,
}

/// Removes a refused or failed upload (in the background; a file that is gone already is
/// fine).
fn discard_upload(path: std::path::PathBuf) {
    tokio::task::spawn_blocking(move || {
        if let Err(e) = std::fs::remove_file(&path)
            && e.kind() != std::io::ErrorKind::NotFound
        {
            tracing::warn!("cannot remove the upload {}: {e}", path.display());
        }
    });
}

/// A DEM uploaded from the page (`POST /api/dem?name=FILE.ext`, the file as the body, at most
/// [`MAX_DEM_UPLOAD`] bytes, [`MAX_CONCURRENT_UPLOADS`] at once): written as it arrives to a
/// temporary `imports/.upload-RANDOM-FILE.ext` in the project folder and imported by a job that
/// reads it as `snowscape run --dem` does and keeps it as `imports/FILE.ext` (`202` with the
/// job's id; `400` for a bad name or an empty or broken body, `409` while busy, `413` when too
/// large, `429` while another upload is received; the reader's errors come as the job's
/// failure). An upload that is refused or fails is removed.
pub(super) async fn import_dem_handler(
    State(s): State<AppState>,
    Query(q): Query<DemQuery>,
    headers: axum::http::HeaderMap,
    body: axum::body::Body,
) -> Response {
    let name = q.name.trim().to_string();
    let path = std::path::Path::new(&name);
    let stem_ok = path
        .file_stem()
        .and_then(|s| s.to_str())
        .is_some_and(|stem| crate::protocol::check_name(stem).is_ok());
    if path.file_name().and_then(|f| f.to_str()) != Some(name.as_str())
        || !stem_ok
        || snowscape_io::RasterFormat::from_path(path).is_none()
    {
        return reply(
            StatusCode::BAD_REQUEST,
            format!(
                "DEM name {:?}: a file name of letters, digits, '_' or '-' with a raster extension (.asc, .tif, .png, .raw, .r16, .npy, .exr)",
                name.chars().take(80).collect::<String>()
            ),
        );
    }
    let declared = headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok());
    match declared {
        Some(len) if len > MAX_DEM_UPLOAD as u64 => {
            return reply(
                StatusCode::PAYLOAD_TOO_LARGE,
                format!(
                    "DEM {name}: {len} bytes (Content-Length) is more than the {MAX_DEM_UPLOAD} bytes an upload may take"
                ),
            );
        }
        Some(0) => {
            return reply(
                StatusCode::BAD_REQUEST,
                format!("{name}: the file is empty"),
            );
        }
        _ => {}
    }
    let Ok(permit) = s.uploads.clone().try_acquire_owned() else {
        return reply(
            StatusCode::TOO_MANY_REQUESTS,
            format!(
                "DEM {name}: another upload is being received (at most {MAX_CONCURRENT_UPLOADS} at a time); try again when it ends"
            ),
        );
    };
    // A busy session refuses the import: say so before anything is received.
    if let Some(st) = ask(&s, Command::State).await
        && st.busy
    {
        return reply(
            StatusCode::CONFLICT,
            format!("DEM {name}: busy: wait for the running job or live event, or cancel it"),
        );
    }
    let mut tag = [0u8; 8];
    if getrandom::fill(&mut tag).is_err() {
        return reply(
            StatusCode::INTERNAL_SERVER_ERROR,
            "cannot name the upload's temporary file".into(),
        );
    }
    let tag: String = tag.iter().map(|b| format!("{b:02x}")).collect();
    let project = s.project.clone();
    let part_name = format!(".upload-{tag}-{name}");
    let created = tokio::task::spawn_blocking(move || {
        let dir = project.create_dir("imports").map_err(|e| e.to_string())?;
        let p = dir.join(&part_name);
        let f = std::fs::File::create_new(&p).map_err(|e| format!("{}: {e}", p.display()))?;
        Ok::<_, String>((p, f))
    })
    .await;
    let (part, file) = match created {
        Ok(Ok(x)) => x,
        Ok(Err(e)) => return reply(StatusCode::INTERNAL_SERVER_ERROR, e),
        Err(_) => return StatusCode::INTERNAL_SERVER_ERROR.into_response(),
    };
    let received = receive_upload(body, file, &name, MAX_DEM_UPLOAD as u64).await;
    let received = match received {
        Ok(n) => n,
        Err((code, message)) => {
            discard_upload(part);
            return reply(code, message);
        }
    };
    tracing::info!("DEM upload {name}: {received} bytes");
    let answer = ask(&s, |reply| Command::ImportDem {
        path: part.clone(),
        name: name.clone(),
        reply,
    })
    .await;
    drop(permit);
    match answer {
        Some(Ok(id)) => (
            StatusCode::ACCEPTED,
            axum::Json(serde_json::json!({ "job": id })),
        )
            .into_response(),
        Some(Err((code, m))) => {
            discard_upload(part);
            let status = if code == ErrorCode::Busy {
                StatusCode::CONFLICT
            } else {
                StatusCode::BAD_REQUEST
            };
            reply(status, format!("DEM {name}: {m}"))
        }
        None => {
            discard_upload(part);
            StatusCode::SERVICE_UNAVAILABLE.into_response()
        }
    }
}

/// Writes the upload's body into `file` block by block, at most `max` bytes (the body is
/// refused as soon as it passes them, whatever its `Content-Length` said); the bytes
/// received, or the refusal.
async fn receive_upload(
    body: axum::body::Body,
    file: std::fs::File,
    name: &str,
    max: u64,
) -> Result<u64, (StatusCode, String)> {
    use futures_core::Stream;
    use std::io::Write;
    let mut stream = body.into_data_stream();
    let mut file = Some(file);
    let mut total = 0u64;
    loop {
        let chunk = std::future::poll_fn(|cx| std::pin::Pin::new(&mut stream).poll_next(cx)).await;
        let chunk = match chunk {
            None => break,
            Some(Ok(c)) => c,
            Some(Err(e)) => {
                return Err((
                    StatusCode::BAD_REQUEST,
                    format!("DEM {name}: the upload broke off after {total} bytes: {e}"),
                ));
            }
        };
        total += chunk.len() as u64;
        if total > max {
            return Err((
                StatusCode::PAYLOAD_TOO_LARGE,
                format!("DEM {name}: more than the {max} bytes an upload may take"),
            ));
        }
        let Some(mut f) = file.take() else {
            break;
        };
        let written = tokio::task::spawn_blocking(move || f.write_all(&chunk).map(|()| f)).await;
        match written {
            Ok(Ok(f)) => file = Some(f),
            Ok(Err(e)) => {
                return Err((
                    StatusCode::INTERNAL_SERVER_ERROR,
                    format!("DEM {name}: cannot write the upload: {e}"),
                ));
            }
            Err(_) => {
                return Err((
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "upload writer stopped".into(),
                ));
            }
        }
    }
    if total == 0 {
        return Err((
            StatusCode::BAD_REQUEST,
            format!("{name}: the file is empty"),
        ));
    }
    if let Some(f) = file {
        let synced = tokio::task::spawn_blocking(move || f.sync_all()).await;
        if !matches!(synced, Ok(Ok(()))) {
            return Err((
                StatusCode::INTERNAL_SERVER_ERROR,
                format!("DEM {name}: cannot write the upload"),
            ));
        }
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body of `blocks` blocks of `size` bytes, without a length (chunked).
    fn stream_body(blocks: usize, size: usize) -> axum::body::Body {
        struct Blocks(usize, usize);
        impl futures_core::Stream for Blocks {
            type Item = Result<axum::body::Bytes, std::io::Error>;
            fn poll_next(
                mut self: std::pin::Pin<&mut Self>,
                _: &mut std::task::Context<'_>,
            ) -> std::task::Poll<Option<Self::Item>> {
                if self.0 == 0 {
                    return std::task::Poll::Ready(None);
                }
                self.0 -= 1;
                std::task::Poll::Ready(Some(Ok(vec![7u8; self.1].into())))
            }
        }
        axum::body::Body::from_stream(Blocks(blocks, size))
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn uploads_are_bounded_while_they_stream() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("up.asc");
        // Within the bound: every byte written.
        let f = std::fs::File::create(&path).unwrap();
        let n = receive_upload(stream_body(10, 1000), f, "up.asc", 10_000)
            .await
            .unwrap();
        assert_eq!(n, 10_000);
        assert_eq!(std::fs::metadata(&path).unwrap().len(), 10_000);
        // A body without a length that passes the bound is refused as soon as it does, and
        // no more than the bound is written.
        let f = std::fs::File::create(&path).unwrap();
        let (code, message) = receive_upload(stream_body(1000, 1000), f, "up.asc", 10_000)
            .await
            .unwrap_err();
        assert_eq!(code, StatusCode::PAYLOAD_TOO_LARGE);
        assert!(
            message.contains("10000 bytes") && message.contains("up.asc"),
            "{message}"
        );
        assert!(std::fs::metadata(&path).unwrap().len() <= 10_000);
        // An empty body is refused.
        let f = std::fs::File::create(&path).unwrap();
        let (code, _) = receive_upload(stream_body(0, 0), f, "up.asc", 10_000)
            .await
            .unwrap_err();
        assert_eq!(code, StatusCode::BAD_REQUEST);
    }
}
