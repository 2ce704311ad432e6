//! Who may talk to the editor: the `Host` and `Origin` checks on every request, and the access
//! token every request must carry when the server is bound beyond loopback.
//!
//! **Host and Origin.** Every request must name the served address in its `Host` header
//! (`127.0.0.1:PORT`, `localhost:PORT`, `[::1]:PORT`, the `--bind` address; any IP literal
//! when bound to all interfaces), and a request that carries an `Origin` (every browser
//! WebSocket upgrade and cross-site fetch does) must come from a page of such an address.
//! This keeps other sites the artist visits, pages served from other local ports and
//! DNS-rebinding names away from the session and the project files.
//!
//! **Access token.** The bind address decides: bound to a loopback address, only this machine
//! can connect and no token is asked; bound to anything else (`0.0.0.0`, a LAN address, `::`)
//! the server draws a 128-bit [`AccessToken`] from the operating system's random source and
//! every request, from any client (loopback ones too, since they cannot be told apart from a
//! forwarded connection), must carry it: as the query parameter `token=` (the URL the server
//! prints) or in the cookie `snowscape_token_PORT`, which the server sets (`HttpOnly`,
//! `SameSite=Strict`) on the response to a request whose query carried the token. The page
//! opened with the printed URL therefore loads its scripts, downloads exports and opens its
//! WebSocket on the cookie. Tokens are compared in constant time. Any refusal is a 403.

use std::net::{IpAddr, SocketAddr};

/// Whether a server bound to `bind` asks for an access token: any address but loopback.
pub fn token_required(bind: IpAddr) -> bool {
    !bind.is_loopback()
}

/// The access token of a server bound beyond loopback: 128 bits from the OS, as 32 lowercase
/// hexadecimal digits.
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
    /// The URL's query (after `?`).
    pub query: Option<&'a str>,
    /// The values of its `Cookie` headers.
    pub cookies: &'a [&'a str],
}

/// The gate's verdict on an admitted request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Admitted {
    /// Served as it is.
    Open,
    /// Served, and the response sets this `Set-Cookie` value (the token came in the query).
    SetCookie(String),
}

/// The Host/Origin checks and, beyond loopback, the access token.
#[derive(Debug, Clone)]
pub struct Gate {
    hosts: AllowedHosts,
    token: Option<AccessToken>,
    cookie: String,
}

impl Gate {
    /// The gate of a server bound to `bind` on `port`; `token` is required when given.
    pub fn new(bind: IpAddr, port: u16, token: Option<AccessToken>) -> Self {
        Self {
            hosts: AllowedHosts::new(bind, port),
            token,
            cookie: format!("snowscape_token_{port}"),
        }
    }

    /// The token requests must carry, if any.
    pub fn token(&self) -> Option<&AccessToken> {
        self.token.as_ref()
    }

    /// The name of the cookie that carries the token.
    pub fn cookie_name(&self) -> &str {
        &self.cookie
    }

    /// Whether a request may be served; a refusal says why (never the token).
    pub fn admits(&self, req: Credentials<'_>) -> Result<Admitted, String> {
        self.hosts.admits(req.host, req.origin)?;
        let Some(token) = &self.token else {
            return Ok(Admitted::Open);
        };
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
        match (in_query, in_cookie) {
            (_, true) => Ok(Admitted::Open),
            (true, false) => Ok(Admitted::SetCookie(format!(
                "{}={}; Path=/; HttpOnly; SameSite=Strict",
                self.cookie,
                token.as_str()
            ))),
            (false, false) => Err(
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
    fn the_token_comes_in_the_query_or_the_cookie() {
        let token = AccessToken::generate().unwrap();
        let t = token.as_str().to_string();
        let gate = Gate::new("0.0.0.0".parse().unwrap(), 8080, Some(token));
        let at = |query: Option<&str>, cookies: &[&str]| {
            gate.admits(Credentials {
                host: Some("192.168.1.7:8080"),
                origin: None,
                query,
                cookies,
            })
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
        // Host and Origin are still checked first.
        let e = gate
            .admits(Credentials {
                host: Some("evil.example:8080"),
                query: Some(&format!("token={t}")),
                ..Credentials::default()
            })
            .unwrap_err();
        assert!(e.contains("evil.example"), "{e}");
        // Loopback: no token.
        let open = Gate::new("127.0.0.1".parse().unwrap(), 8080, None);
        assert_eq!(
            open.admits(Credentials {
                host: Some("127.0.0.1:8080"),
                ..Credentials::default()
            })
            .unwrap(),
            Admitted::Open
        );
    }
}
