//! The page's messages to the server and the server's replies (JSON text frames), their
//! decoder with a byte cap, and the per-connection rate cap.
//!
//! The user "directs the simulation ... by directly painting height changes into the snow
//! layers, by interactively exploring the phenomena parameters, or by triggering avalanches and
//! skiing" (Cordonnier et al. 2018, Section 3): one [`ClientMessage`] variant per action.
//! Messages are `{"type": "...", ...}` objects; unknown types and unknown fields are rejected.
//! Every rejection is answered with [`ServerMessage::Error`] and the connection stays open.
//! Grid data go the other way as binary frames ([`crate::wire`]).

use serde::{Deserialize, Serialize};
use std::time::Instant;
use thiserror::Error;

/// Largest text message accepted from a page, bytes (a scenario with every parameter is
/// about 5 KiB).
pub const MAX_MESSAGE_BYTES: usize = 64 * 1024;
/// Sustained messages per second accepted from one connection.
pub const RATE_PER_S: f64 = 120.0;
/// Burst of messages accepted above the sustained rate.
pub const RATE_BURST: f64 = 240.0;

/// What a brush does (Section 3: "directly painting height changes").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BrushOp {
    /// Adds `strength` metres (or units) at the centre, fading to 0 at the radius.
    Add,
    /// Removes `strength` metres at the centre.
    Remove,
    /// Moves values towards their 3x3 mean, by `strength` (0..1) at the centre.
    Smooth,
    /// Moves values towards `value`, by `strength` (0..1) at the centre.
    Set,
}

/// What a brush paints into.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BrushTarget {
    /// The total snow depth (added to and smoothed in proportion to the layers; removed
    /// from the top down; set in proportion).
    All,
    Compacted,
    Stable,
    Unstable,
    Powder,
    /// The painted avalanche release probability, per day (0..1).
    AvalancheProbability,
    /// The painted skier area (0..1).
    SkiArea,
}

/// A message from the page.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMessage {
    /// One brush dab at grid position (`col`, `row`) (cell units, may be fractional).
    /// Dabs with the same `stroke` number are one undo step.
    Brush {
        stroke: u32,
        op: BrushOp,
        target: BrushTarget,
        col: f64,
        row: f64,
        /// Radius, m.
        radius_m: f64,
        /// Metres per dab for add/remove (probability units for paint targets); 0..1 for
        /// smooth and set.
        strength: f64,
        /// The value `set` moves towards (m, or 0..1 for paint targets).
        #[serde(default)]
        value: f64,
    },
    /// (Struct variants without fields, so that `deny_unknown_fields` applies to them.)
    Undo {},
    Redo {},
    /// Runs the season `days` days on (the server keeps a snapshot after each step).
    Step {
        days: f64,
    },
    /// Goes back (or forward) to snapshot `index` of the timeline.
    Seek {
        index: usize,
    },
    /// Ruptures the snow at a grid position; the flow is streamed as it runs.
    TriggerAvalanche {
        col: f64,
        row: f64,
    },
    /// Launches a skier at a grid position; its position is streamed as it skis.
    LaunchSkier {
        col: f64,
        row: f64,
    },
    /// Replaces the scenario (weather timeline, Table 2 parameters) and restarts the season
    /// from the first snapshot's snow.
    SetScenario {
        scenario: serde_json::Value,
    },
    /// Saves the project under `name` in the project folder.
    Save {
        name: String,
    },
    /// Loads the project `name` from the project folder.
    Load {
        name: String,
    },
    /// Writes the outputs of `snowscape run` for the current state to `exports/<name>`.
    Export {
        name: String,
    },
    /// Asks for the layer values at a cell.
    Probe {
        col: usize,
        row: usize,
    },
    /// Asks for the whole state again (after a lost frame).
    Resync {},
    /// Stops the running job (a season step, a scenario change, a load, an export: its
    /// result is dropped) or the live avalanche or skier ([`crate::job`]).
    Cancel {},
}

/// Error codes of [`ServerMessage::Error`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    TooLarge,
    RateLimited,
    Malformed,
    BinaryNotAccepted,
    InvalidValue,
    Busy,
    NotFound,
    BadPath,
    Failed,
}

/// A message to the page.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    /// The session state; sent on connect and after every change of it.
    State(Box<crate::session::StateSummary>),
    /// A request was refused; the session goes on.
    Error { code: ErrorCode, message: String },
    /// Layer values at a cell (reply to `probe`).
    Cell(crate::session::CellValues),
    /// A live avalanche: started, progressing, or ended.
    Avalanche(crate::live::AvalancheProgress),
    /// Live skiers: positions in grid cells.
    Skiers(crate::live::SkierProgress),
    /// A job (a season step, a scenario change, a load, an export): started, progressing,
    /// cancelling, ended, cancelled or failed.
    Job(crate::job::JobProgress),
    /// Something every tab should know that is not an error (old snapshots dropped for the
    /// memory budget, ...).
    Notice { message: String },
    /// A project was saved or loaded, or outputs were exported; `files` relative to the
    /// project folder.
    Done {
        what: String,
        name: String,
        files: Vec<String>,
    },
}

impl ServerMessage {
    /// An error reply.
    pub fn error(code: ErrorCode, message: impl Into<String>) -> Self {
        ServerMessage::Error {
            code,
            message: message.into(),
        }
    }
    /// The JSON text of the message.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| {
            format!("{{\"type\":\"error\",\"code\":\"failed\",\"message\":\"cannot encode a reply: {e}\"}}")
        })
    }
}

/// Why a message was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DecodeError {
    #[error("message of {len} bytes is larger than the limit of {max} bytes")]
    TooLarge { len: usize, max: usize },
    #[error("message is not UTF-8 text (byte {valid_up_to})")]
    NotUtf8 { valid_up_to: usize },
    #[error("malformed message: {0}")]
    Malformed(String),
    #[error("invalid {field} {value}: {reason}")]
    Invalid {
        field: &'static str,
        value: String,
        reason: &'static str,
    },
}

impl DecodeError {
    /// The error code the reply carries.
    pub fn code(&self) -> ErrorCode {
        match self {
            DecodeError::TooLarge { .. } => ErrorCode::TooLarge,
            DecodeError::NotUtf8 { .. } | DecodeError::Malformed(_) => ErrorCode::Malformed,
            DecodeError::Invalid { .. } => ErrorCode::InvalidValue,
        }
    }
}

fn check(field: &'static str, v: f64, ok: bool, reason: &'static str) -> Result<(), DecodeError> {
    if v.is_finite() && ok {
        Ok(())
    } else {
        Err(DecodeError::Invalid {
            field,
            value: v.to_string(),
            reason,
        })
    }
}

/// Longest project or export name.
pub const MAX_NAME: usize = 64;

/// Checks a project or export name: 1..=64 of `A-Z a-z 0-9 _ -` (no dots, no separators, so
/// it can never leave the project folder).
pub fn check_name(name: &str) -> Result<(), DecodeError> {
    let ok = !name.is_empty()
        && name.len() <= MAX_NAME
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-');
    if ok {
        Ok(())
    } else {
        Err(DecodeError::Invalid {
            field: "name",
            value: format!("{:?}", name.chars().take(80).collect::<String>()),
            reason: "must be 1 to 64 letters, digits, '_' or '-'",
        })
    }
}

impl ClientMessage {
    /// Checks the values that serde cannot: finite numbers within range, safe names.
    pub fn validate(&self) -> Result<(), DecodeError> {
        match self {
            ClientMessage::Brush {
                op,
                col,
                row,
                radius_m,
                strength,
                value,
                ..
            } => {
                check(
                    "col",
                    *col,
                    col.abs() < 1e7,
                    "must be a finite grid position",
                )?;
                check(
                    "row",
                    *row,
                    row.abs() < 1e7,
                    "must be a finite grid position",
                )?;
                check(
                    "radius_m",
                    *radius_m,
                    *radius_m > 0.0 && *radius_m <= 1e5,
                    "must be within (0, 100000] m",
                )?;
                let unit = matches!(op, BrushOp::Smooth | BrushOp::Set);
                check(
                    "strength",
                    *strength,
                    *strength >= 0.0 && (!unit || *strength <= 1.0) && *strength <= 100.0,
                    "must be within [0, 100] (within [0, 1] for smooth and set)",
                )?;
                check(
                    "value",
                    *value,
                    (0.0..=1000.0).contains(value),
                    "must be within [0, 1000]",
                )
            }
            ClientMessage::Step { days } => check(
                "days",
                *days,
                *days > 0.0 && *days <= 365.0,
                "must be within (0, 365]",
            ),
            ClientMessage::TriggerAvalanche { col, row }
            | ClientMessage::LaunchSkier { col, row } => {
                check(
                    "col",
                    *col,
                    *col >= 0.0 && *col < 1e7,
                    "must be a grid position",
                )?;
                check(
                    "row",
                    *row,
                    *row >= 0.0 && *row < 1e7,
                    "must be a grid position",
                )
            }
            ClientMessage::Save { name }
            | ClientMessage::Load { name }
            | ClientMessage::Export { name } => check_name(name),
            _ => Ok(()),
        }
    }
}

/// Decodes and validates one text message of at most `max_bytes`.
pub fn decode(bytes: &[u8], max_bytes: usize) -> Result<ClientMessage, DecodeError> {
    if bytes.len() > max_bytes {
        return Err(DecodeError::TooLarge {
            len: bytes.len(),
            max: max_bytes,
        });
    }
    let text = std::str::from_utf8(bytes).map_err(|e| DecodeError::NotUtf8 {
        valid_up_to: e.valid_up_to(),
    })?;
    let msg: ClientMessage = serde_json::from_str(text).map_err(|e| {
        let mut s = e.to_string();
        s.truncate(200);
        DecodeError::Malformed(s)
    })?;
    msg.validate()?;
    Ok(msg)
}

/// A token bucket: `rate` messages per second sustained, `burst` at once.
#[derive(Debug, Clone)]
pub struct RateLimiter {
    rate: f64,
    burst: f64,
    tokens: f64,
    last: Instant,
}

impl RateLimiter {
    pub fn new(rate: f64, burst: f64) -> Self {
        Self {
            rate,
            burst,
            tokens: burst,
            last: Instant::now(),
        }
    }
    /// Whether one more message is allowed at time `now`.
    pub fn allow(&mut self, now: Instant) -> bool {
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.last = now;
        self.tokens = (self.tokens + dt * self.rate).min(self.burst);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn decodes_a_brush_dab() {
        let m = decode(
            br#"{"type":"brush","stroke":3,"op":"add","target":"powder","col":10.5,"row":4,"radius_m":50,"strength":0.2}"#,
            MAX_MESSAGE_BYTES,
        )
        .unwrap();
        assert!(matches!(
            m,
            ClientMessage::Brush {
                stroke: 3,
                op: BrushOp::Add,
                target: BrushTarget::Powder,
                ..
            }
        ));
    }

    #[test]
    fn rejects_unknown_fields_types_sizes_and_values() {
        let e = decode(br#"{"type":"undo","x":1}"#, 1000).unwrap_err();
        assert_eq!(e.code(), ErrorCode::Malformed);
        let e = decode(br#"{"type":"explode"}"#, 1000).unwrap_err();
        assert_eq!(e.code(), ErrorCode::Malformed);
        let e = decode(&[b' '; 2000], 1000).unwrap_err();
        assert_eq!(
            e,
            DecodeError::TooLarge {
                len: 2000,
                max: 1000
            }
        );
        let e = decode(br#"{"type":"step","days":-1}"#, 1000).unwrap_err();
        assert!(e.to_string().contains("days -1"), "{e}");
        let e = decode(br#"{"type":"save","name":"../etc"}"#, 1000).unwrap_err();
        assert_eq!(e.code(), ErrorCode::InvalidValue);
        assert!(decode(&[0xff, 0xfe], 1000).is_err());
    }

    #[test]
    fn rate_limiter_refuses_above_the_burst_and_refills() {
        let t0 = Instant::now();
        let mut r = RateLimiter::new(10.0, 3.0);
        assert!((0..3).all(|_| r.allow(t0)));
        assert!(!r.allow(t0));
        assert!(r.allow(t0 + Duration::from_millis(150)));
    }
}
