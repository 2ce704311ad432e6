//! Who may talk to the editor: the `Host`, `Origin` and `Sec-Fetch-Site` checks on every
//! request, and the per-session access token every request for the session's data must carry.
//!
//! **Host and Origin.** Every request must name the served address in its `Host` header
//! (`127.0.0.1:PORT`, `localhost:PORT`, `[::1]:PORT`, the `--bind` address; any IP literal
//! when bound to all interfaces), and a request that carries an `Origin` (every browser
//! WebSocket upgrade and cross-site fetch does) must come from a page of such an address.
//! This keeps other sites the artist visits, pages served from other local ports and
//! DNS-rebinding names away from the session and the project files.
//!
//! **Cross-site requests.** A page on another site can make the browser send a GET without an
//! `Origin` (`<img>`, `<script>`, a `no-cors` fetch). Browsers name such a request's initiator
//! in `Sec-Fetch-Site`: a request whose `Sec-Fetch-Site` is present and is neither
//! `same-origin` nor `none` is refused; `none` (a typed URL, a bookmark) is accepted only for
//! a GET of the page itself (`/` or an `.html` file), never for its scripts, `/api`, `/files`
//! or `/ws`. Every response, refusals included, carries `Cross-Origin-Resource-Policy:
//! same-origin`, `X-Content-Type-Options: nosniff` and `Referrer-Policy: no-referrer`
//! ([`SECURITY_HEADERS`]).
//!
//! **Access token.** Every server draws a 128-bit [`AccessToken`] from the operating system's
//! random source at start. Every request for the session's data (`/api/…`, `/files/…`, the
//! WebSocket `/ws`; [`Resource::Data`]) must carry it, from any client, loopback included:
//! in the cookie `snowscape_token_PORT` (what the page's own requests, downloads and WebSocket
//! carry), as the query parameter `token=` (the URL the server prints), or in the header
//! [`TOKEN_HEADER`] (scripts). The server sets the cookie (`HttpOnly`, `SameSite=Strict`, so
//! the browser never sends it with a request another site makes) on the response to a request
//! whose query carried the token and, bound to loopback, on the response to a GET of the page
//! itself. Where the server is bound decides what the page and its scripts ask: bound to a
//! loopback address the page is served without a token (only this machine can connect; the
//! page then runs on the cookie it set); bound to anything else (`0.0.0.0`, a LAN address,
//! `::`) every request, the page included, needs the token ([`token_required`]: loopback
//! clients cannot be told apart from forwarded connections). Tokens are compared in constant
//! time. Any refusal is a 403 whose message names the refused header or value (never the
//! token).

use std::net::{IpAddr, SocketAddr};

/// The header a script may carry the access token in (the page uses the cookie).
pub const TOKEN_HEADER: &str = "x-snowscape-token";

/// Headers set on every response: no other site may embed or read it, nothing is
/// content-sniffed, and no URL (with its `?token=`) leaks in a `Referer`.
pub const SECURITY_HEADERS: [(&str, &str); 3] = [
    ("cross-origin-resource-policy", "same-origin"),
    ("x-content-type-options", "nosniff"),
    ("referrer-policy", "no-referrer"),
];

/// Whether a server bound to `bind` asks for the access token for its page too (not only for
/// its data): any address but loopback.
pub fn token_required(bind: IpAddr) -> bool {
    !bind.is_loopback()
}

/// What a request asks for, as the gate sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resource {
    /// A GET of the page itself (`/`, an `.html` file): the only thing a typed URL or a
    /// bookmark (`Sec-Fetch-Site: none`) may open.
    Page,
    /// The page's other files (scripts, styles).
    Asset,
    /// The session's data: `/api/…`, `/files/…`, `/ws`. Always needs the token.
    Data,
}

impl Resource {
    /// The resource a request for `path` with `method` asks for.
    pub fn of(method: &str, path: &str) -> Self {
        // Leading slashes repeated or not, any case: never less than the data.
        let p = path.trim_start_matches('/').to_ascii_lowercase();
        let under = |dir: &str| p == dir || p.starts_with(&format!("{dir}/"));
        if under("ws") || under("api") || under("files") {
            Resource::Data
        } else if (method == "GET" || method == "HEAD") && (p.is_empty() || p.ends_with(".html")) {
            Resource::Page
        } else {
            Resource::Asset
        }
    }
}

/// The access token of a server: 128 bits from the OS, as 32 lowercase hexadecimal digits.
#[derive(Clone, PartialEq, Eq)]
pub struct AccessToken(String);

impl std::fmt::Debug for AccessToken {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("AccessToken(..)")
    }
}

impl AccessToken {
    /// A fresh token from the operating system's random source.
    pub fn generate() -> Result<Self, String> {
        let mut bytes = [0u8; 16];
        getrandom::fill(&mut bytes)
            .map_err(|e| format!("cannot draw an access token from the OS: {e}"))?;
        Ok(Self(bytes.iter().map(|b| format!("{b:02x}")).collect()))
    }

    /// The token's text (what the URL carries).
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Whether `candidate` is this token, in time independent of where they differ.
    pub fn matches(&self, candidate: &str) -> bool {
        let (a, b) = (self.0.as_bytes(), candidate.as_bytes());
        if a.len() != b.len() {
            return false;
        }
        let diff = a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y));
        std::hint::black_box(diff) == 0
    }
}

/// The addresses the editor is served at, for the `Host` and `Origin` checks.
#[derive(Debug, Clone)]
pub struct AllowedHosts {
    /// `host:port` authorities, lowercase.
    names: Vec<String>,
    port: u16,
    /// Bound to all interfaces: any IP literal (never a DNS name) with the port.
    any_ip: bool,
}

impl AllowedHosts {
    /// The loopback names and the bind address, on `port`.
    pub fn new(bind: IpAddr, port: u16) -> Self {
        let authority = |ip: IpAddr| match ip {
            IpAddr::V4(v4) => format!("{v4}:{port}"),
            IpAddr::V6(v6) => format!("[{v6}]:{port}"),
        };
        let mut names = vec![
            format!("127.0.0.1:{port}"),
            format!("localhost:{port}"),
            format!("[::1]:{port}"),
        ];
        if !bind.is_unspecified() {
            names.push(authority(bind));
        }
        Self {
            names,
            port,
            any_ip: bind.is_unspecified(),
        }
    }

    /// Whether `authority` (`host:port`) names this server.
    fn names(&self, authority: &str) -> bool {
        let a = authority.to_ascii_lowercase();
        if self.names.contains(&a) {
            return true;
        }
        self.any_ip
            && a.parse::<SocketAddr>()
                .is_ok_and(|addr| addr.port() == self.port)
    }

    /// Whether a request with these `Host` and `Origin` headers may be served; the refusal
    /// names the header and its value.
    pub fn admits(&self, host: Option<&str>, origin: Option<&str>) -> Result<(), String> {
        match host {
            Some(h) if self.names(h) => {}
            Some(h) => return Err(format!("Host {h:?} is not this editor's address")),
            None => return Err("no Host header".into()),
        }
        if let Some(o) = origin {
            let authority = o
                .strip_prefix("http://")
                .or_else(|| o.strip_prefix("https://"))
                .unwrap_or("");
            if !self.names(authority) {
                return Err(format!("Origin {o:?} is not this editor's page"));
            }
        }
        Ok(())
    }
}

/// What a request shows of itself to the gate.
#[derive(Debug, Default, Clone, Copy)]
pub struct Credentials<'a> {
    pub host: Option<&'a str>,
    pub origin: Option<&'a str>,
    /// The `Sec-Fetch-Site` header.
    pub fetch_site: Option<&'a str>,
    /// The URL's query (after `?`).
    pub query: Option<&'a str>,
    /// The values of its `Cookie` headers.
    pub cookies: &'a [&'a str],
    /// The [`TOKEN_HEADER`] header.
    pub token_header: Option<&'a str>,
}

/// The gate's verdict on an admitted request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Admitted {
    /// Served as it is.
    Open,
    /// Served, and the response sets this `Set-Cookie` value (the token came in the query, or
    /// the page was opened on loopback).
    SetCookie(String),
}

/// The Host/Origin and `Sec-Fetch-Site` checks and the access token.
#[derive(Debug, Clone)]
pub struct Gate {
    hosts: AllowedHosts,
    token: AccessToken,
    /// Bound beyond loopback: the page and its files need the token too.
    page_needs_token: bool,
    cookie: String,
}

impl Gate {
    /// The gate of a server bound to `bind` on `port` whose token is `token`.
    pub fn new(bind: IpAddr, port: u16, token: AccessToken) -> Self {
        Self {
            hosts: AllowedHosts::new(bind, port),
            token,
            page_needs_token: token_required(bind),
            cookie: format!("snowscape_token_{port}"),
        }
    }

    /// The token requests must carry.
    pub fn token(&self) -> &AccessToken {
        &self.token
    }

    /// The name of the cookie that carries the token.
    pub fn cookie_name(&self) -> &str {
        &self.cookie
    }

    fn set_cookie(&self) -> Admitted {
        Admitted::SetCookie(format!(
            "{}={}; Path=/; HttpOnly; SameSite=Strict",
            self.cookie,
            self.token.as_str()
        ))
    }

    /// Whether a request for `what` may be served; a refusal says why (never the token).
    pub fn admits(&self, what: Resource, req: Credentials<'_>) -> Result<Admitted, String> {
        self.hosts.admits(req.host, req.origin)?;
        match req.fetch_site {
            None | Some("same-origin") => {}
            Some("none") if what == Resource::Page => {}
            Some("none") => {
                return Err(
                    "Sec-Fetch-Site \"none\": only the page itself may be opened from a typed URL or a bookmark, not its data or files; open the page"
                        .into(),
                );
            }
            Some(other) => {
                return Err(format!(
                    "Sec-Fetch-Site {other:?}: this editor refuses every request another site makes"
                ));
            }
        }
        let token = &self.token;
        let in_query = req
            .query
            .unwrap_or("")
            .split('&')
            .filter_map(|kv| kv.strip_prefix("token="))
            .any(|t| token.matches(t));
        let in_cookie = req
            .cookies
            .iter()
            .flat_map(|h| h.split(';'))
            .filter_map(|kv| {
                let (k, v) = kv.trim().split_once('=')?;
                (k == self.cookie).then_some(v)
            })
            .any(|t| token.matches(t));
        let in_header = req.token_header.is_some_and(|t| token.matches(t.trim()));
        if in_cookie {
            return Ok(Admitted::Open);
        }
        if in_query {
            return Ok(self.set_cookie());
        }
        if in_header {
            return Ok(Admitted::Open);
        }
        match what {
            Resource::Page if !self.page_needs_token => Ok(self.set_cookie()),
            Resource::Asset if !self.page_needs_token => Ok(Admitted::Open),
            Resource::Data if !self.page_needs_token => Err(
                "the editor's data and files need its access token: open the editor's page (it sets the token's cookie), or send the token of the URL `snowscape serve` printed (?token=, or the X-Snowscape-Token header)"
                    .into(),
            ),
            _ => Err(
                "this editor is reachable from the network and asks for its access token: open it with the URL `snowscape serve` printed (…/?token=…)"
                    .into(),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_served_address_and_its_pages_are_admitted() {
        let a = AllowedHosts::new("127.0.0.1".parse().unwrap(), 8080);
        for host in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LOCALHOST:8080",
            "[::1]:8080",
        ] {
            assert!(a.admits(Some(host), None).is_ok(), "{host}");
        }
        assert!(
            a.admits(Some("localhost:8080"), Some("http://localhost:8080"))
                .is_ok()
        );
        assert!(
            a.admits(Some("127.0.0.1:8080"), Some("http://127.0.0.1:8080"))
                .is_ok()
        );
        let refused = [
            (Some("evil.example"), None),
            (Some("evil.example:8080"), None),
            (Some("127.0.0.1:9090"), None),
            (None, None),
            (Some("127.0.0.1:8080"), Some("http://evil.example")),
            (Some("127.0.0.1:8080"), Some("http://127.0.0.1:9090")),
            (Some("127.0.0.1:8080"), Some("null")),
            (
                Some("127.0.0.1:8080"),
                Some("http://localhost:8080.evil.example"),
            ),
        ];
        for (host, origin) in refused {
            let e = a.admits(host, origin).unwrap_err();
            let named = origin.or(host).unwrap_or("no Host");
            assert!(e.contains(named), "{e} names {named}");
        }
        // Bound to all interfaces: IP literals with the port, never a DNS name.
        let all = AllowedHosts::new("0.0.0.0".parse().unwrap(), 8080);
        assert!(
            all.admits(Some("192.168.1.7:8080"), Some("http://192.168.1.7:8080"))
                .is_ok()
        );
        assert!(all.admits(Some("rebind.evil.example:8080"), None).is_err());
        assert!(all.admits(Some("192.168.1.7:8081"), None).is_err());
    }

    #[test]
    fn the_bind_address_decides_whether_a_token_is_asked() {
        for loopback in ["127.0.0.1", "127.0.0.2", "::1"] {
            assert!(!token_required(loopback.parse().unwrap()), "{loopback}");
        }
        for beyond in [
            "0.0.0.0",
            "::",
            "192.168.1.7",
            "10.0.0.1",
            "::ffff:127.0.0.1",
        ] {
            assert!(token_required(beyond.parse().unwrap()), "{beyond}");
        }
    }

    #[test]
    fn tokens_are_random_hex_and_compared_whole() {
        let a = AccessToken::generate().unwrap();
        let b = AccessToken::generate().unwrap();
        assert_eq!(a.as_str().len(), 32);
        assert!(a.as_str().bytes().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
        assert!(a.matches(a.as_str()));
        assert!(!a.matches(b.as_str()));
        assert!(!a.matches(&a.as_str()[..31]));
        assert!(!a.matches(""));
        assert!(
            !format!("{a:?}").contains(a.as_str()),
            "Debug hides the token"
        );
    }

    #[test]
    fn the_token_comes_in_the_query_the_cookie_or_the_header() {
        let token = AccessToken::generate().unwrap();
        let t = token.as_str().to_string();
        let gate = Gate::new("0.0.0.0".parse().unwrap(), 8080, token);
        let at = |query: Option<&str>, cookies: &[&str]| {
            gate.admits(
                Resource::Data,
                Credentials {
                    host: Some("192.168.1.7:8080"),
                    query,
                    cookies,
                    ..Credentials::default()
                },
            )
        };
        let e = at(None, &[]).unwrap_err();
        assert!(e.contains("access token") && !e.contains(&t), "{e}");
        assert!(at(Some("token=0123"), &[]).is_err());
        let Admitted::SetCookie(c) = at(Some(&format!("a=1&token={t}")), &[]).unwrap() else {
            panic!("the query token sets the cookie");
        };
        assert!(c.starts_with(&format!("snowscape_token_8080={t};")), "{c}");
        assert!(
            c.contains("HttpOnly") && c.contains("SameSite=Strict"),
            "{c}"
        );
        let cookie = format!("other=1; snowscape_token_8080={t}");
        assert_eq!(at(None, &[&cookie]).unwrap(), Admitted::Open);
        let wrong_port = format!("snowscape_token_8081={t}");
        assert!(at(None, &[&wrong_port]).is_err(), "another editor's cookie");
        assert!(
            at(
                None,
                &["snowscape_token_8080=00000000000000000000000000000000"]
            )
            .is_err()
        );
        let header = |h: &str| {
            gate.admits(
                Resource::Data,
                Credentials {
                    host: Some("192.168.1.7:8080"),
                    token_header: Some(h),
                    ..Credentials::default()
                },
            )
        };
        assert_eq!(header(&t).unwrap(), Admitted::Open);
        assert!(header("0123").is_err());
        // Beyond loopback the page needs the token too.
        for what in [Resource::Page, Resource::Asset] {
            assert!(
                gate.admits(
                    what,
                    Credentials {
                        host: Some("192.168.1.7:8080"),
                        ..Credentials::default()
                    }
                )
                .is_err()
            );
        }
        // Host and Origin are still checked first.
        let e = gate
            .admits(
                Resource::Data,
                Credentials {
                    host: Some("evil.example:8080"),
                    query: Some(&format!("token={t}")),
                    ..Credentials::default()
                },
            )
            .unwrap_err();
        assert!(e.contains("evil.example"), "{e}");
    }

    #[test]
    fn on_loopback_the_page_sets_the_cookie_and_the_data_needs_the_token() {
        let token = AccessToken::generate().unwrap();
        let t = token.as_str().to_string();
        let gate = Gate::new("127.0.0.1".parse().unwrap(), 8080, token);
        let plain = |what: Resource| {
            gate.admits(
                what,
                Credentials {
                    host: Some("127.0.0.1:8080"),
                    ..Credentials::default()
                },
            )
        };
        let Admitted::SetCookie(c) = plain(Resource::Page).unwrap() else {
            panic!("the page sets the cookie");
        };
        assert!(c.contains(&t) && c.contains("SameSite=Strict"), "{c}");
        assert_eq!(plain(Resource::Asset).unwrap(), Admitted::Open);
        let e = plain(Resource::Data).unwrap_err();
        assert!(e.contains("access token") && !e.contains(&t), "{e}");
        let cookie = format!("snowscape_token_8080={t}");
        let with_cookie = gate.admits(
            Resource::Data,
            Credentials {
                host: Some("127.0.0.1:8080"),
                cookies: &[&cookie],
                ..Credentials::default()
            },
        );
        assert_eq!(with_cookie.unwrap(), Admitted::Open);
    }

    #[test]
    fn cross_site_requests_are_refused_and_none_opens_only_the_page() {
        let token = AccessToken::generate().unwrap();
        let t = token.as_str().to_string();
        let cookie = format!("snowscape_token_8080={t}");
        let cookies = [cookie.as_str()];
        let gate = Gate::new("127.0.0.1".parse().unwrap(), 8080, token);
        let site = |what: Resource, site: &str| {
            gate.admits(
                what,
                Credentials {
                    host: Some("127.0.0.1:8080"),
                    fetch_site: Some(site),
                    cookies: &cookies,
                    ..Credentials::default()
                },
            )
        };
        for what in [Resource::Page, Resource::Asset, Resource::Data] {
            assert!(site(what, "same-origin").is_ok(), "{what:?}");
            for other in ["cross-site", "same-site", "bogus"] {
                let e = site(what, other).unwrap_err();
                assert!(e.contains("Sec-Fetch-Site") && e.contains(other), "{e}");
            }
        }
        assert!(site(Resource::Page, "none").is_ok());
        for what in [Resource::Asset, Resource::Data] {
            let e = site(what, "none").unwrap_err();
            assert!(e.contains("\"none\""), "{e}");
        }
    }

    #[test]
    fn requests_are_sorted_into_page_assets_and_data() {
        assert_eq!(Resource::of("GET", "/"), Resource::Page);
        assert_eq!(Resource::of("GET", "/index.html"), Resource::Page);
        assert_eq!(Resource::of("POST", "/"), Resource::Asset);
        assert_eq!(Resource::of("GET", "/main.js"), Resource::Asset);
        for data in [
            "/api/state",
            "/api/export/x",
            "/files/projects/a/x.tif",
            "/ws",
            "/api",
        ] {
            assert_eq!(Resource::of("GET", data), Resource::Data, "{data}");
        }
        assert_eq!(Resource::of("GET", "//api/state"), Resource::Data);
        assert_eq!(Resource::of("GET", "/API/state"), Resource::Data);
        assert_eq!(Resource::of("GET", "/apix.js"), Resource::Asset);
    }
}
