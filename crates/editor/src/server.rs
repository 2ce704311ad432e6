//! The local web server: the page, its WebSocket, a few JSON endpoints, and the actor thread
//! that owns the [`Session`] (Cordonnier et al. 2018, Section 3: one shared scene that the user
//! directs interactively).
//!
//! - `GET /` and `GET /<file>`: the page ([`crate::assets`]).
//! - `GET /ws`: the WebSocket. On connect the tab gets the state and every channel in full;
//!   then every change, as JSON text ([`crate::protocol`]) and binary tile frames
//!   ([`crate::wire`]). Every tab sees the same state: changes are broadcast to all.
//! - `GET /api/state`: the state summary; `GET /api/cell?col=C&row=R`: values at a cell;
//!   `GET /api/parameters`: every scenario parameter with its help, range and choices
//!   ([`snowscape_season::parameter_catalogue`], generated from the parameter types);
//!   `GET /api/projects`: the saved projects (name, day); `GET /api/export/<name>`: an export's
//!   files as one zip, streamed as it is deflated, [`MAX_CONCURRENT_EXPORTS`] at once (429
//!   beyond), at most [`MAX_DOWNLOAD`] bytes of files; `POST /api/dem?name=FILE.ext`: a DEM
//!   uploaded from the page, at most [`MAX_DEM_UPLOAD`] bytes (413 from its `Content-Length`
//!   or as soon as the body passes it), [`MAX_CONCURRENT_UPLOADS`] at once (429 beyond),
//!   written to the project folder as it arrives and imported by a job (the season of the
//!   current scenario restarts on it); an upload that is refused (busy: 409) or fails is
//!   removed.
//! - `GET /files/<path>`: a file of the project folder (exports), read-only.
//!
//! **Who may talk to it** ([`crate::access`]): every request must name the served address in
//! its `Host` header and come from one of its pages when it carries an `Origin`; a request
//! another site makes (`Sec-Fetch-Site` other than `same-origin`, or `none` for anything but
//! the page itself) is refused, GETs included; every request for the data (`/api`, `/files`,
//! `/ws`) must carry the server's access token (the cookie the page's response sets, the
//! query `token=` of the printed URL, or the `X-Snowscape-Token` header), loopback included,
//! and bound beyond loopback the page needs it too. Others get 403. Every response carries
//! `Cross-Origin-Resource-Policy: same-origin`, `X-Content-Type-Options: nosniff` and
//! `Referrer-Policy: no-referrer`.
//!
//! At most [`MAX_CONNECTIONS`] tabs are connected at once (more get 503); sockets send with
//! `TCP_NODELAY`.
//!
//! One actor thread owns the session: messages are handled in order, and a live avalanche or
//! skier advances one frame per loop turn between messages. Long work (a season step, a
//! scenario change, a load, an export) runs on a worker thread ([`crate::job`]): the actor
//! goes on answering every tab (state, cell values, resync; mutating requests get `busy`),
//! broadcasts the job's progress, and installs its outcome when it ends; `cancel` stops it. A tab that falls behind the
//! broadcast (its queue overflows) is sent the whole state again; one that lets
//! [`MAX_PENDING_REPLIES`] of its own replies pile up, or does not take a message within
//! [`SEND_TIMEOUT`], is dropped (memory per tab stays bounded).

use crate::access::{
    AccessToken, Admitted, Credentials, Gate, Resource, SECURITY_HEADERS, TOKEN_HEADER,
    token_required,
};
use crate::assets::{Assets, BUILD_HINT};
use crate::job::{Job, JobOutcome, JobProgress};
use crate::project::{ProjectDir, ProjectError};
use crate::protocol::{
    ClientMessage, ErrorCode, MAX_MESSAGE_BYTES, RATE_BURST, RATE_PER_S, RateLimiter,
    ServerMessage, decode,
};
use crate::session::{
    CellValues, Exporter, Out, Outgoing, Refusal, Session, Started, StateSummary,
};
use axum::Router;
use axum::extract::Request;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Query, State};
use axum::http::{StatusCode, Uri, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::serve::ListenerExt;
use std::net::{IpAddr, SocketAddr};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};
use thiserror::Error;
use tokio::sync::{broadcast, mpsc, oneshot};

/// Largest WebSocket message the socket layer reads (larger ones close the connection; the
/// decoder's own cap, [`MAX_MESSAGE_BYTES`], answers smaller oversized ones with an error).
pub const SOCKET_MAX_BYTES: usize = 1 << 20;
/// Shortest wall time between two frames of a live event when pacing (25 frames/s: an
/// avalanche at its real speed with [`crate::live::RECORD_INTERVAL_S`] records).
pub const FRAME_INTERVAL: Duration = Duration::from_millis(40);
/// Most replies waiting for one tab (a full state is a few dozen messages); a tab that lets
/// more pile up without reading them is dropped.
pub const MAX_PENDING_REPLIES: usize = 256;
/// Longest a send to one tab may wait (the tab's connection is full because it does not
/// read); the tab is then dropped.
pub const SEND_TIMEOUT: Duration = Duration::from_secs(10);
/// Most WebSocket connections at once (tabs); more are refused with 503.
pub const MAX_CONNECTIONS: usize = 16;

mod exports;
mod uploads;

pub use exports::{MAX_CONCURRENT_EXPORTS, MAX_DOWNLOAD, ZIP_BLOCK_BYTES};
pub use uploads::{MAX_CONCURRENT_UPLOADS, MAX_DEM_UPLOAD};

/// A server error.
#[derive(Debug, Error)]
pub enum ServeError {
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        addr: SocketAddr,
        source: std::io::Error,
    },
    #[error("cannot start the server runtime: {0}")]
    Runtime(std::io::Error),
    #[error("the server stopped: {0}")]
    Stopped(std::io::Error),
    #[error("{0}")]
    Token(String),
    #[error(transparent)]
    Project(#[from] ProjectError),
}

/// What to serve.
pub struct ServeConfig {
    pub session: Session,
    pub project: ProjectDir,
    pub bind: IpAddr,
    /// 0 picks a free port.
    pub port: u16,
    pub assets: Assets,
    pub exporter: Option<Arc<Exporter>>,
    /// Pace live events at [`FRAME_INTERVAL`] (off: as fast as they compute).
    pub pace: bool,
}

enum Command {
    Msg {
        msg: ClientMessage,
        reply: ReplyTo,
    },
    Join(oneshot::Sender<Vec<Outgoing>>),
    State(oneshot::Sender<StateSummary>),
    Probe(usize, usize, oneshot::Sender<Result<CellValues, Refusal>>),
    /// From a job's worker.
    JobProgress(JobProgress),
    JobDone {
        id: u64,
        outcome: JobOutcome,
    },
    /// A DEM uploaded to `path` (`POST /api/dem`): start its import job; the job's id.
    ImportDem {
        path: std::path::PathBuf,
        name: String,
        reply: oneshot::Sender<Result<u64, Refusal>>,
    },
}

/// Where the actor sends one tab's own replies: a bounded queue, and the flag it raises when
/// the queue is full (the tab is not reading) so that the tab is dropped.
#[derive(Clone)]
struct ReplyTo {
    tx: mpsc::Sender<Arc<Outgoing>>,
    overflow: Arc<std::sync::atomic::AtomicBool>,
}

impl ReplyTo {
    fn send(&self, m: Outgoing) {
        if self.tx.try_send(Arc::new(m)).is_err() {
            self.overflow.store(true, Ordering::SeqCst);
        }
    }
}

#[derive(Clone)]
struct AppState {
    commands: mpsc::UnboundedSender<Command>,
    updates: broadcast::Sender<Arc<Outgoing>>,
    project: ProjectDir,
    assets: Arc<Assets>,
    /// Open WebSocket connections.
    connections: Arc<std::sync::atomic::AtomicUsize>,
    /// [`MAX_CONCURRENT_EXPORTS`] permits.
    exports: Arc<tokio::sync::Semaphore>,
    /// [`MAX_CONCURRENT_UPLOADS`] permits.
    uploads: Arc<tokio::sync::Semaphore>,
}

/// Runs `job` on a worker thread that reports to the actor through `commands`.
fn spawn_job(job: Job, commands: mpsc::UnboundedSender<Command>) -> Result<(), String> {
    let id = job.id();
    std::thread::Builder::new()
        .name(format!("snowscape-job-{id}"))
        .spawn(move || {
            let progress = commands.clone();
            // A panic in the work must still end the job, or the session would stay busy.
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                job.run(&mut |p| {
                    let _ = progress.send(Command::JobProgress(p));
                })
            }))
            .unwrap_or_else(|_| {
                tracing::error!("job {id} stopped on an internal error (panic)");
                JobOutcome::Failed((
                    ErrorCode::Failed,
                    "the job stopped on an internal error; the session is unchanged".into(),
                ))
            });
            let _ = commands.send(Command::JobDone { id, outcome });
        })
        .map(|_| ())
        .map_err(|e| format!("cannot start a worker thread: {e}"))
}

/// Sends outputs: [`Out::All`] to every tab, [`Out::Sender`] to `reply_to`.
fn route(outs: Vec<Out>, updates: &broadcast::Sender<Arc<Outgoing>>, reply_to: Option<&ReplyTo>) {
    for o in outs {
        match o {
            Out::All(m) => {
                let _ = updates.send(Arc::new(m));
            }
            Out::Sender(m) => {
                if let Some(r) = reply_to {
                    r.send(m);
                }
            }
        }
    }
}

/// The actor: owns the session, handles commands in order, advances live events, and hands
/// long work to a worker ([`crate::job`]) whose progress and outcome come back as commands,
/// so that other tabs are answered while it runs.
fn actor(
    mut session: Session,
    mut commands: mpsc::UnboundedReceiver<Command>,
    to_self: mpsc::WeakUnboundedSender<Command>,
    updates: broadcast::Sender<Arc<Outgoing>>,
    project: ProjectDir,
    exporter: Option<Arc<Exporter>>,
    pace: bool,
) {
    let mut last_frame = Instant::now();
    // The tab that asked for the running job (its own replies, an export's files).
    let mut job_asker: Option<ReplyTo> = None;
    loop {
        let cmd = if session.live() {
            match commands.try_recv() {
                Ok(c) => Some(c),
                Err(mpsc::error::TryRecvError::Empty) => None,
                Err(mpsc::error::TryRecvError::Disconnected) => return,
            }
        } else {
            match commands.blocking_recv() {
                Some(c) => Some(c),
                None => return,
            }
        };
        match cmd {
            Some(Command::Msg { msg, reply }) => {
                let outs = match session.start(msg, Some(&project), exporter.as_ref()) {
                    Ok(Started::Done(o)) => o,
                    Ok(Started::Job(job, mut o)) => {
                        let id = job.id();
                        let spawned = to_self
                            .upgrade()
                            .ok_or_else(|| "the server is stopping".to_string())
                            .and_then(|tx| spawn_job(job, tx));
                        match spawned {
                            Ok(()) => job_asker = Some(reply.clone()),
                            Err(e) => o.extend(
                                session.finish_job(id, JobOutcome::Failed((ErrorCode::Failed, e))),
                            ),
                        }
                        o
                    }
                    Err((code, message)) => vec![Out::Sender(Outgoing::Text(
                        ServerMessage::error(code, message).to_json(),
                    ))],
                };
                route(outs, &updates, Some(&reply));
            }
            Some(Command::ImportDem { path, name, reply }) => {
                let answer = match session.import_dem_job(path, name) {
                    Ok((job, mut o)) => {
                        let id = job.id();
                        let spawned = to_self
                            .upgrade()
                            .ok_or_else(|| "the server is stopping".to_string())
                            .and_then(|tx| spawn_job(job, tx));
                        if let Err(e) = spawned {
                            o.extend(
                                session.finish_job(id, JobOutcome::Failed((ErrorCode::Failed, e))),
                            );
                        }
                        route(o, &updates, None);
                        Ok(id)
                    }
                    Err(r) => Err(r),
                };
                let _ = reply.send(answer);
            }
            Some(Command::Join(tx)) => {
                let _ = tx.send(session.full_state());
            }
            Some(Command::State(tx)) => {
                let _ = tx.send(session.summary());
            }
            Some(Command::Probe(c, r, tx)) => {
                let _ = tx.send(session.probe(c, r));
            }
            Some(Command::JobProgress(p)) => {
                route(
                    session.job_progress(p).into_iter().collect(),
                    &updates,
                    None,
                );
            }
            Some(Command::JobDone { id, outcome }) => {
                let outs = session.finish_job(id, outcome);
                route(outs, &updates, job_asker.take().as_ref());
            }
            None => {
                if pace {
                    let since = last_frame.elapsed();
                    if since < FRAME_INTERVAL {
                        std::thread::sleep(FRAME_INTERVAL - since);
                    }
                }
                last_frame = Instant::now();
                let outs = session.tick().unwrap_or_else(|(code, message)| {
                    vec![Out::All(Outgoing::Text(
                        ServerMessage::error(code, message).to_json(),
                    ))]
                });
                route(outs, &updates, None);
            }
        }
    }
}

/// Where the server listens, and the access token when it asks for one.
#[derive(Debug, Clone)]
pub struct Served {
    /// The address listened on.
    pub addr: SocketAddr,
    /// The token every request for the session's data must carry (bound beyond loopback,
    /// every request).
    pub token: AccessToken,
}

impl Served {
    /// The URL to open: on this machine (a loopback address when bound to all interfaces),
    /// with the token (a browser then keeps it in its cookie; scripts send it back).
    pub fn url(&self) -> String {
        let ip = match self.addr.ip() {
            IpAddr::V4(v4) if v4.is_unspecified() => IpAddr::V4(std::net::Ipv4Addr::LOCALHOST),
            IpAddr::V6(v6) if v6.is_unspecified() => IpAddr::V6(std::net::Ipv6Addr::LOCALHOST),
            ip => ip,
        };
        let addr = SocketAddr::new(ip, self.addr.port());
        format!("http://{addr}/?token={}", self.token.as_str())
    }

    /// The warning to print when the editor is reachable from the network, else `None`.
    pub fn network_warning(&self) -> Option<String> {
        if !token_required(self.addr.ip()) {
            return None;
        }
        let (ip, port) = (self.addr.ip(), self.addr.port());
        let from_elsewhere = if ip.is_unspecified() {
            format!(
                "from another machine use this machine's address with port {port} and the same ?token="
            )
        } else {
            "from another machine use the same URL".to_string()
        };
        Some(format!(
            "warning: bound to {ip}, the editor is reachable from the network: anyone who has the URL with its token can edit this session and download the project folder's files; {from_elsewhere}"
        ))
    }
}

/// Starts the server and blocks until Ctrl-C. `on_ready` gets where it listens.
pub fn serve_blocking(
    config: ServeConfig,
    on_ready: impl FnOnce(&Served),
) -> Result<(), ServeError> {
    serve_until(config, on_ready, async {
        let _ = tokio::signal::ctrl_c().await;
    })
}

/// Starts the server and blocks until `stop` completes (then shuts down gracefully).
/// `on_ready` gets where it listens. The server draws an [`AccessToken`] that every request
/// for its data (beyond loopback: every request) must carry ([`crate::access`]).
pub fn serve_until(
    config: ServeConfig,
    on_ready: impl FnOnce(&Served),
    stop: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), ServeError> {
    let token = AccessToken::generate().map_err(ServeError::Token)?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(ServeError::Runtime)?;
    rt.block_on(async move {
        let addr = SocketAddr::new(config.bind, config.port);
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .map_err(|source| ServeError::Bind { addr, source })?;
        let local = listener
            .local_addr()
            .map_err(|source| ServeError::Bind { addr, source })?;
        let gate = Arc::new(Gate::new(config.bind, local.port(), token.clone()));
        let app = router(config, gate);
        on_ready(&Served { addr: local, token });
        // Small frames (a tile, a progress line) go out at once.
        let listener = listener.tap_io(|tcp| {
            let _ = tcp.set_nodelay(true);
        });
        axum::serve(listener, app)
            .with_graceful_shutdown(stop)
            .await
            .map_err(ServeError::Stopped)
    })
}

/// Refuses, with 403, a request whose `Host` or `Origin` is not this server's, that another
/// site made (`Sec-Fetch-Site`), or that lacks the access token where it is required
/// ([`Gate::admits`]); sets the token's cookie when it came in the query or the page was
/// opened on loopback. Every response gets the [`SECURITY_HEADERS`].
async fn guard(State(gate): State<Arc<Gate>>, req: Request, next: Next) -> Response {
    let verdict = {
        let headers = req.headers();
        let text = |v: &header::HeaderValue| v.to_str().unwrap_or("(not text)").to_string();
        let host = headers.get(header::HOST).map(text);
        let origin = headers.get(header::ORIGIN).map(text);
        let fetch_site = headers.get("sec-fetch-site").map(text);
        let token_header = headers.get(TOKEN_HEADER).map(text);
        let cookies: Vec<String> = headers.get_all(header::COOKIE).iter().map(text).collect();
        let cookies: Vec<&str> = cookies.iter().map(String::as_str).collect();
        gate.admits(
            Resource::of(req.method().as_str(), req.uri().path()),
            Credentials {
                host: host.as_deref(),
                origin: origin.as_deref(),
                fetch_site: fetch_site.as_deref(),
                query: req.uri().query(),
                cookies: &cookies,
                token_header: token_header.as_deref(),
            },
        )
    };
    let mut res = match verdict {
        Ok(Admitted::Open) => next.run(req).await,
        Ok(Admitted::SetCookie(cookie)) => {
            let mut res = next.run(req).await;
            if let Ok(v) = header::HeaderValue::from_str(&cookie) {
                res.headers_mut().append(header::SET_COOKIE, v);
            }
            res
        }
        Err(why) => (StatusCode::FORBIDDEN, format!("snowscape serve: {why}\n")).into_response(),
    };
    for (k, v) in SECURITY_HEADERS {
        res.headers_mut()
            .insert(k, header::HeaderValue::from_static(v));
    }
    res
}

/// The router, with the actor thread started.
fn router(config: ServeConfig, gate: Arc<Gate>) -> Router {
    let (tx, rx) = mpsc::unbounded_channel();
    let (updates, _) = broadcast::channel(4096);
    let state = AppState {
        commands: tx,
        updates: updates.clone(),
        project: config.project.clone(),
        assets: Arc::new(config.assets),
        connections: Arc::default(),
        exports: Arc::new(tokio::sync::Semaphore::new(MAX_CONCURRENT_EXPORTS)),
        uploads: Arc::new(tokio::sync::Semaphore::new(MAX_CONCURRENT_UPLOADS)),
    };
    let (session, project, exporter, pace) =
        (config.session, config.project, config.exporter, config.pace);
    let to_self = state.commands.downgrade();
    std::thread::Builder::new()
        .name("snowscape-editor".into())
        .spawn(move || actor(session, rx, to_self, updates, project, exporter, pace))
        .ok();
    Router::new()
        .route("/ws", get(ws_handler))
        .route("/api/state", get(state_handler))
        .route("/api/cell", get(cell_handler))
        .route("/api/parameters", get(parameters_handler))
        .route("/api/protocol", get(protocol_handler))
        .route("/api/projects", get(projects_handler))
        .route("/api/export/{name}", get(exports::export_zip_handler))
        .route("/api/dem", axum::routing::post(uploads::import_dem_handler))
        .route("/files/{*path}", get(exports::file_handler))
        .fallback(get(asset_handler))
        .with_state(state)
        .layer(middleware::from_fn_with_state(gate, guard))
}

async fn asset_handler(State(s): State<AppState>, uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    match s.assets.get(path) {
        Some((bytes, mime)) => ([(header::CONTENT_TYPE, mime)], bytes.into_owned()).into_response(),
        None if matches!(*s.assets, Assets::Missing) => (
            StatusCode::SERVICE_UNAVAILABLE,
            [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
            format!("snowscape serve: {BUILD_HINT}\n"),
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, format!("no file {path:?}\n")).into_response(),
    }
}

async fn ask<T>(s: &AppState, make: impl FnOnce(oneshot::Sender<T>) -> Command) -> Option<T> {
    let (tx, rx) = oneshot::channel();
    s.commands.send(make(tx)).ok()?;
    rx.await.ok()
}

async fn state_handler(State(s): State<AppState>) -> Response {
    match ask(&s, Command::State).await {
        Some(st) => axum::Json(st).into_response(),
        None => StatusCode::SERVICE_UNAVAILABLE.into_response(),
    }
}

async fn projects_handler(State(s): State<AppState>) -> Response {
    let project = s.project.clone();
    match tokio::task::spawn_blocking(move || project.list()).await {
        Ok(list) => axum::Json(list).into_response(),
        Err(_) => StatusCode::INTERNAL_SERVER_ERROR.into_response(),
    }
}

/// A plain-text reply.
fn reply(code: StatusCode, message: String) -> Response {
    (
        code,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        format!("snowscape serve: {message}\n"),
    )
        .into_response()
}

/// The parameter catalogue (built once, on first use, off the async workers: its ranges are
/// found by a few thousand validations).
async fn protocol_handler() -> Response {
    axum::Json(crate::page_protocol::PageProtocol::new()).into_response()
}

async fn parameters_handler() -> Response {
    match tokio::task::spawn_blocking(snowscape_season::parameter_catalogue::parameter_catalogue)
        .await
    {
        Ok(list) => axum::Json(list).into_response(),
        Err(_) => StatusCode::INTERNAL_SERVER_ERROR.into_response(),
    }
}

#[derive(serde::Deserialize)]
struct CellQuery {
    col: usize,
    row: usize,
}

async fn cell_handler(State(s): State<AppState>, Query(q): Query<CellQuery>) -> Response {
    match ask(&s, |tx| Command::Probe(q.col, q.row, tx)).await {
        Some(Ok(v)) => axum::Json(v).into_response(),
        Some(Err((_, m))) => (StatusCode::BAD_REQUEST, m).into_response(),
        None => StatusCode::SERVICE_UNAVAILABLE.into_response(),
    }
}

async fn ws_handler(State(s): State<AppState>, ws: WebSocketUpgrade) -> Response {
    // A slot for this tab, or 503 when MAX_CONNECTIONS are open.
    let open = s.connections.fetch_add(1, Ordering::SeqCst);
    if open >= MAX_CONNECTIONS {
        s.connections.fetch_sub(1, Ordering::SeqCst);
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            format!("snowscape serve: {open} tabs are connected, the most it serves is {MAX_CONNECTIONS}\n"),
        )
            .into_response();
    }
    // Released when the connection ends, or when the upgrade never completes.
    let slot = Slot(s.connections.clone());
    ws.max_message_size(SOCKET_MAX_BYTES)
        .max_frame_size(SOCKET_MAX_BYTES)
        .on_upgrade(move |socket| async move {
            connection(socket, s).await;
            drop(slot);
        })
}

/// One of the [`MAX_CONNECTIONS`] slots, given back when dropped.
struct Slot(Arc<std::sync::atomic::AtomicUsize>);

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

fn to_message(o: &Outgoing) -> Message {
    match o {
        Outgoing::Text(t) => Message::text(t.clone()),
        Outgoing::Binary(b) => Message::binary(b.clone()),
    }
}

fn error_message(code: ErrorCode, message: impl Into<String>) -> Message {
    Message::text(ServerMessage::error(code, message).to_json())
}

/// Sends `m`, waiting at most [`SEND_TIMEOUT`]; false when the tab is gone or not reading.
async fn send_within(socket: &mut WebSocket, m: Message) -> bool {
    matches!(
        tokio::time::timeout(SEND_TIMEOUT, socket.send(m)).await,
        Ok(Ok(()))
    )
}

/// One tab: its messages go to the actor; the broadcast and its own replies come back.
async fn connection(mut socket: WebSocket, s: AppState) {
    let mut updates = s.updates.subscribe();
    let (tx, mut replies) = mpsc::channel::<Arc<Outgoing>>(MAX_PENDING_REPLIES);
    let reply_tx = ReplyTo {
        tx,
        overflow: Arc::default(),
    };
    let Some(initial) = ask(&s, Command::Join).await else {
        return;
    };
    for o in &initial {
        if !send_within(&mut socket, to_message(o)).await {
            return;
        }
    }
    let mut limiter = RateLimiter::new(RATE_PER_S, RATE_BURST);
    loop {
        if reply_tx.overflow.load(Ordering::SeqCst) {
            // More than MAX_PENDING_REPLIES replies unread: drop the tab.
            tracing::warn!("a tab that stopped reading its replies was dropped");
            break;
        }
        tokio::select! {
            incoming = socket.recv() => {
                let reply = match incoming {
                    None | Some(Err(_)) | Some(Ok(Message::Close(_))) => break,
                    Some(Ok(Message::Ping(_) | Message::Pong(_))) => continue,
                    Some(Ok(Message::Binary(b))) => Some(error_message(
                        ErrorCode::BinaryNotAccepted,
                        format!("binary messages ({} bytes) are not accepted; send JSON text", b.len()),
                    )),
                    Some(Ok(Message::Text(t))) => {
                        if !limiter.allow(Instant::now()) {
                            Some(error_message(
                                ErrorCode::RateLimited,
                                format!("more than {RATE_PER_S} messages per second; message dropped"),
                            ))
                        } else {
                            match decode(t.as_bytes(), MAX_MESSAGE_BYTES) {
                                Ok(msg) => {
                                    if s.commands.send(Command::Msg { msg, reply: reply_tx.clone() }).is_err() {
                                        break;
                                    }
                                    None
                                }
                                Err(e) => Some(error_message(e.code(), e.to_string())),
                            }
                        }
                    }
                };
                if let Some(r) = reply
                    && !send_within(&mut socket, r).await
                {
                    break;
                }
            }
            update = updates.recv() => {
                let sent = match update {
                    Ok(o) => send_within(&mut socket, to_message(&o)).await,
                    Err(broadcast::error::RecvError::Lagged(_)) => {
                        let Some(all) = ask(&s, Command::Join).await else { break };
                        let mut r = true;
                        for o in &all {
                            r = send_within(&mut socket, to_message(o)).await;
                            if !r { break; }
                        }
                        r
                    }
                    Err(broadcast::error::RecvError::Closed) => break,
                };
                if !sent {
                    break;
                }
            }
            Some(reply) = replies.recv() => {
                if !send_within(&mut socket, to_message(&reply)).await {
                    break;
                }
            }
        }
    }
}
