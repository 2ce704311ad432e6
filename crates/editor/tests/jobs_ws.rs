//! Long work off the request path, over the WebSocket of a running server: while one tab's
//! season step runs, another tab's `probe` and `/api/state` are answered at once, its brush
//! gets `busy`, every tab sees the job's progress, and `cancel` stops the step with the
//! season left at the day it started from (a whole 365-day season is asked; the cancel goes
//! after the first progress report, 0.1 s and about 15 days in on the development machine).

mod common;

use snowscape_editor::{Assets, ProjectDir, ServeConfig, serve_until};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

/// A bare WebSocket client (RFC 6455: masked text frames out, whole frames in).
struct Tab(TcpStream);

impl Tab {
    fn open(port: u16, token: &str) -> Tab {
        let mut s = TcpStream::connect(SocketAddr::from(([127, 0, 0, 1], port))).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(60))).ok();
        let req = format!(
            "GET /ws?token={token} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
        );
        s.write_all(req.as_bytes()).expect("handshake");
        let mut head = Vec::new();
        let mut b = [0u8; 1];
        while !head.ends_with(b"\r\n\r\n") {
            s.read_exact(&mut b).expect("handshake reply");
            head.push(b[0]);
        }
        assert!(
            head.starts_with(b"HTTP/1.1 101"),
            "{}",
            String::from_utf8_lossy(&head)
        );
        Tab(s)
    }

    fn send(&mut self, text: &str) {
        let p = text.as_bytes();
        let mut f = vec![0x81u8];
        match p.len() {
            n if n < 126 => f.push(0x80 | n as u8),
            n => {
                f.push(0x80 | 126);
                f.extend_from_slice(&(n as u16).to_be_bytes());
            }
        }
        let mask = [7u8, 1, 9, 3];
        f.extend_from_slice(&mask);
        f.extend(p.iter().enumerate().map(|(i, b)| b ^ mask[i % 4]));
        self.0.write_all(&f).expect("send");
    }

    /// The next text message (binary frames skipped).
    fn next_text(&mut self) -> serde_json::Value {
        loop {
            let mut h = [0u8; 2];
            self.0.read_exact(&mut h).expect("a frame");
            let len = match h[1] & 0x7f {
                126 => {
                    let mut l = [0u8; 2];
                    self.0.read_exact(&mut l).expect("length");
                    u16::from_be_bytes(l) as usize
                }
                127 => {
                    let mut l = [0u8; 8];
                    self.0.read_exact(&mut l).expect("length");
                    u64::from_be_bytes(l) as usize
                }
                n => n as usize,
            };
            let mut payload = vec![0u8; len];
            self.0.read_exact(&mut payload).expect("payload");
            if h[0] & 0x0f == 1 {
                return serde_json::from_slice(&payload).expect("JSON");
            }
        }
    }

    /// Text messages up to and including the first that `stop` accepts.
    fn until(&mut self, stop: impl Fn(&serde_json::Value) -> bool) -> Vec<serde_json::Value> {
        let mut seen = Vec::new();
        loop {
            let m = self.next_text();
            let done = stop(&m);
            seen.push(m);
            if done {
                return seen;
            }
        }
    }
}

fn http_state(port: u16, token: &str) -> serde_json::Value {
    let mut s = TcpStream::connect(SocketAddr::from(([127, 0, 0, 1], port))).expect("connect");
    let req = format!(
        "GET /api/state HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nX-Snowscape-Token: {token}\r\nConnection: close\r\n\r\n"
    );
    s.write_all(req.as_bytes()).expect("send");
    let mut text = String::new();
    s.read_to_string(&mut text).expect("reply");
    let body = text.split("\r\n\r\n").nth(1).expect("a body");
    serde_json::from_str(body).expect("JSON state")
}

#[test]
fn other_tabs_are_answered_while_a_step_runs_and_cancel_stops_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let config = ServeConfig {
        session: common::session(256, 365.0),
        project: ProjectDir::open(dir.path()).expect("project"),
        bind: "127.0.0.1".parse().expect("address"),
        port: 0,
        assets: Assets::Missing,
        exporter: None,
        pace: false,
    };
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let server = std::thread::spawn(move || {
        serve_until(
            config,
            |s| {
                let _ = ready_tx.send((s.addr.port(), s.token.as_str().to_string()));
            },
            async move {
                let _ = stop_rx.await;
            },
        )
        .expect("the server ran");
    });
    let (port, token) = ready_rx
        .recv_timeout(Duration::from_secs(60))
        .expect("ready");

    let mut a = Tab::open(port, &token);
    let mut b = Tab::open(port, &token);
    for t in [&mut a, &mut b] {
        t.until(|m| m["type"] == "state");
    }
    let t0 = Instant::now();
    a.send(r#"{"type":"step","days":365}"#);
    a.until(|m| m["type"] == "job" && m["phase"] == "started");
    let is_end = |m: &serde_json::Value| {
        m["type"] == "job"
            && ["ended", "cancelled", "failed"].contains(&m["phase"].as_str().unwrap_or(""))
    };

    // Another tab is answered while the step runs.
    b.send(r#"{"type":"probe","col":100,"row":100}"#);
    let seen = b.until(|m| m["type"] == "cell");
    let probe_s = t0.elapsed().as_secs_f64();
    assert!(
        !seen.iter().any(is_end),
        "the step ended before the probe was answered"
    );
    let st = http_state(port, &token);
    assert_eq!(st["busy"], true);
    assert_eq!(st["job"]["kind"], "step");
    b.send(r#"{"type":"brush","stroke":1,"op":"add","target":"powder","col":50,"row":50,"radius_m":100,"strength":0.5}"#);
    let seen = b.until(|m| m["type"] == "error");
    assert!(
        !seen.iter().any(is_end),
        "the step ended before the brush was refused"
    );
    assert_eq!(seen.last().map(|m| m["code"].clone()), Some("busy".into()));

    // Progress reaches every tab; cancel stops the step.
    let progress = a.until(|m| (m["type"] == "job" && m["phase"] == "running") || is_end(m));
    let last = progress.last().expect("a message");
    assert_eq!(
        last["phase"], "running",
        "the step ended before it reported progress"
    );
    let done = last["done"].as_f64().unwrap_or(0.0);
    a.send(r#"{"type":"cancel"}"#);
    let seen = a.until(is_end);
    let cancel_s = t0.elapsed().as_secs_f64();
    assert_eq!(
        seen.last().map(|m| m["phase"].clone()),
        Some("cancelled".into())
    );
    let st = a.until(|m| m["type"] == "state");
    let st = st.last().expect("the state");
    assert_eq!(
        (st["day"].as_f64(), st["busy"].as_bool()),
        (Some(0.0), Some(false))
    );
    println!(
        "probe answered {probe_s:.3} s into the step; cancelled at {cancel_s:.2} s after {done:.2} days"
    );
    b.until(|m| m["type"] == "job" && m["phase"] == "cancelled");

    let _ = stop_tx.send(());
    drop((a, b));
    server.join().expect("the server stopped");
}
