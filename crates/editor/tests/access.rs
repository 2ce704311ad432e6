//! The access token over real HTTP: a server bound to all interfaces (`0.0.0.0`, reached here
//! through 127.0.0.1: the bind address, not the client's, decides that a token is asked)
//! refuses every request without its token with 403 — the page, its files, the JSON
//! endpoints, project files and the WebSocket upgrade — and serves those that carry it in the
//! query (setting the cookie) or in the cookie. A loopback-bound server asks for none; one
//! bound to the machine's own network address asks for it.

mod common;

use snowscape_editor::{Assets, ProjectDir, ServeConfig, Served, serve_until};
use std::io::{Read, Write};
use std::net::{IpAddr, SocketAddr, TcpStream};
use std::time::Duration;

/// A running server and what stops it.
struct Running {
    served: Served,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
    _dir: tempfile::TempDir,
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn start(bind: &str) -> Running {
    let dir = tempfile::tempdir().expect("temp dir");
    let web = dir.path().join("web");
    std::fs::create_dir_all(&web).expect("web dir");
    std::fs::write(
        web.join("index.html"),
        "<!doctype html><title>editor</title>",
    )
    .expect("page");
    std::fs::write(web.join("main.js"), "// the page").expect("script");
    let config = ServeConfig {
        session: common::session(128, 10.0),
        project: ProjectDir::open(&dir.path().join("project")).expect("project"),
        bind: bind.parse::<IpAddr>().expect("address"),
        port: 0,
        assets: Assets::Folder(web),
        exporter: None,
        pace: false,
    };
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let thread = std::thread::spawn(move || {
        let r = serve_until(
            config,
            |s| {
                let _ = ready_tx.send(s.clone());
            },
            async move {
                let _ = stop_rx.await;
            },
        );
        assert!(r.is_ok(), "{r:?}");
    });
    let served = ready_rx
        .recv_timeout(Duration::from_secs(60))
        .expect("the server started");
    Running {
        served,
        stop: Some(stop_tx),
        thread: Some(thread),
        _dir: dir,
    }
}

/// The status and head of the response to `GET path` with `headers`, over loopback.
fn get(port: u16, path: &str, headers: &[(&str, &str)]) -> (u16, String) {
    get_at(SocketAddr::from(([127, 0, 0, 1], port)), path, headers)
}

/// The same to the server at `addr` (named in the `Host` header).
fn get_at(addr: SocketAddr, path: &str, headers: &[(&str, &str)]) -> (u16, String) {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(10))).ok();
    let mut req = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\n");
    if !headers.iter().any(|(k, _)| *k == "Connection") {
        req.push_str("Connection: close\r\n");
    }
    for (k, v) in headers {
        req.push_str(&format!("{k}: {v}\r\n"));
    }
    req.push_str("\r\n");
    s.write_all(req.as_bytes()).expect("send");
    let mut got = Vec::new();
    let mut buf = [0u8; 4096];
    // Up to the end of the head (an upgraded connection stays open after it).
    while !got.windows(4).any(|w| w == b"\r\n\r\n") {
        match s.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => got.extend_from_slice(&buf[..n]),
        }
    }
    let text = String::from_utf8_lossy(&got).to_string();
    let status = text
        .split(' ')
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    (status, text)
}

const UPGRADE: &[(&str, &str)] = &[
    ("Upgrade", "websocket"),
    ("Connection", "Upgrade"),
    ("Sec-WebSocket-Version", "13"),
    ("Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="),
];

#[test]
fn beyond_loopback_every_request_needs_the_token() {
    let server = start("0.0.0.0");
    let port = server.served.addr.port();
    let token = server
        .served
        .token
        .clone()
        .expect("bound to 0.0.0.0, a token is asked");
    let t = token.as_str();
    assert_eq!(t.len(), 32);
    let url = server.served.url();
    assert_eq!(url, format!("http://127.0.0.1:{port}/?token={t}"));
    let warning = server.served.network_warning().expect("a warning");
    assert!(warning.contains("reachable from the network"), "{warning}");

    // Nothing without the token.
    for path in [
        "/",
        "/main.js",
        "/api/state",
        "/api/cell?col=1&row=1",
        "/files/x",
    ] {
        let (status, head) = get(port, path, &[]);
        assert_eq!(status, 403, "{path}: {head}");
    }
    assert_eq!(get(port, "/ws", UPGRADE).0, 403, "the WebSocket upgrade");
    let wrong = "0".repeat(32);
    assert_eq!(get(port, &format!("/api/state?token={wrong}"), &[]).0, 403);
    let cookie_name = format!("snowscape_token_{port}");
    let wrong_cookie = format!("{cookie_name}={wrong}");
    assert_eq!(get(port, "/api/state", &[("Cookie", &wrong_cookie)]).0, 403);
    let short = &t[..16];
    assert_eq!(get(port, &format!("/?token={short}"), &[]).0, 403);

    // The printed URL: the page, and the cookie its own requests carry from then on.
    let (status, head) = get(port, &format!("/?token={t}"), &[]);
    assert_eq!(status, 200, "{head}");
    let set_cookie = head
        .lines()
        .find(|l| l.to_ascii_lowercase().starts_with("set-cookie:"))
        .expect("the page's response sets the cookie");
    assert!(
        set_cookie.contains(&format!("{cookie_name}={t}")),
        "{set_cookie}"
    );
    assert!(set_cookie.contains("HttpOnly") && set_cookie.contains("SameSite=Strict"));
    let cookie = format!("{cookie_name}={t}");
    for path in ["/main.js", "/api/state", "/api/cell?col=1&row=1"] {
        let (status, head) = get(port, path, &[("Cookie", &cookie)]);
        assert_eq!(status, 200, "{path}: {head}");
    }
    assert_eq!(get(port, "/files/x", &[("Cookie", &cookie)]).0, 404);
    let mut ws = UPGRADE.to_vec();
    ws.push(("Cookie", &cookie));
    assert_eq!(
        get(port, "/ws", &ws).0,
        101,
        "the page's WebSocket on the cookie"
    );
    assert_eq!(
        get(port, &format!("/ws?token={t}"), UPGRADE).0,
        101,
        "a WebSocket with the token in its URL"
    );
    // The Host and Origin checks still apply with the token.
    let origin = [
        ("Cookie", cookie.as_str()),
        ("Origin", "http://evil.example"),
    ];
    assert_eq!(get(port, "/api/state", &origin).0, 403);
}

#[test]
fn on_loopback_no_token_is_asked() {
    let server = start("127.0.0.1");
    let port = server.served.addr.port();
    assert!(server.served.token.is_none());
    assert!(server.served.network_warning().is_none());
    assert_eq!(server.served.url(), format!("http://127.0.0.1:{port}/"));
    let (status, head) = get(port, "/api/state", &[]);
    assert_eq!(status, 200, "{head}");
    assert!(!head.to_ascii_lowercase().contains("set-cookie"));
    assert_eq!(get(port, "/ws", UPGRADE).0, 101);
}

/// This machine's address on its network (the source address of a route out), if any.
fn own_network_address() -> Option<IpAddr> {
    let socket = std::net::UdpSocket::bind("0.0.0.0:0").ok()?;
    ["192.0.2.1:9", "10.255.255.254:9", "8.8.8.8:53"]
        .iter()
        .filter_map(|to| {
            socket
                .connect(to)
                .ok()
                .and_then(|()| socket.local_addr().ok())
        })
        .map(|a| a.ip())
        .find(|ip| !ip.is_loopback() && !ip.is_unspecified())
}

#[test]
fn bound_to_a_network_address_the_token_is_asked() {
    let Some(ip) = own_network_address() else {
        println!("skipped: this machine has no network address besides loopback");
        return;
    };
    let server = start(&ip.to_string());
    let addr = server.served.addr;
    assert_eq!(addr.ip(), ip);
    let token = server
        .served
        .token
        .clone()
        .expect("a token beyond loopback");
    assert_eq!(
        server.served.url(),
        format!("http://{addr}/?token={}", token.as_str())
    );
    assert_eq!(get_at(addr, "/api/state", &[]).0, 403);
    let (status, head) = get_at(addr, &format!("/api/state?token={}", token.as_str()), &[]);
    assert_eq!(status, 200, "{head}");
}
