//! A genuine checkpoint of a small season and a forger of checkpoints: edits of the header or
//! the maps re-assembled with their lengths and CRC computed anew, so the checksum accepts
//! them and only the checks of the decoded values stand between them and a resumed season.
//! Shared by `hostile_checkpoints.rs` and `reader_mutations.rs`.
#![allow(dead_code)]

use serde_json::Value;
use snowscape_season::checkpoint;
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain};

/// Bytes before the JSON header: magic, version, header length, maps length.
pub const PREAMBLE: usize = 28;
pub const COLS: usize = 24;
pub const ROWS: usize = 20;

/// A 24x20 terrain of 20 m cells: a cone from 900 m to 2100 m.
pub fn terrain() -> LayeredTerrain {
    let g = GridGeometry::square(COLS, ROWS, 20.0).unwrap();
    LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| {
        let (x, y) = (c as f32 / COLS as f32 - 0.5, r as f32 / ROWS as f32 - 0.5);
        900.0 + 1200.0 * (1.0 - 2.0 * (x * x + y * y).sqrt()).max(0.0)
    }))
}

/// The 6-day season of these tests (8 sky directions, a 30-day sun step: quick to build).
pub fn scenario() -> Scenario {
    let mut s = Scenario {
        days: 6.0,
        ..Scenario::default()
    };
    s.parameters.environment.sky.directions = 8;
    s.parameters.environment.sun.day_step = 30;
    s
}

/// A genuine checkpoint of the season stopped at `day`.
pub fn checkpoint_at(day: f64) -> Vec<u8> {
    let mut w = Winter::new(scenario(), terrain()).unwrap();
    w.run_until(day).unwrap();
    let mut bytes = Vec::new();
    w.write_checkpoint(&mut bytes).unwrap();
    bytes
}

/// The JSON header's bytes and the raw maps of a checkpoint.
pub fn split_raw(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let len = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    let (header_len, maps_len) = (len(12), len(20));
    let header = bytes[PREAMBLE..PREAMBLE + header_len].to_vec();
    let maps = bytes[PREAMBLE + header_len..PREAMBLE + header_len + maps_len].to_vec();
    (header, maps)
}

/// The JSON header and the raw maps of a checkpoint.
pub fn split(bytes: &[u8]) -> (Value, Vec<u8>) {
    let (header, maps) = split_raw(bytes);
    (serde_json::from_slice(&header).unwrap(), maps)
}

/// A checkpoint of the header bytes `json` and `maps` with lengths and CRC computed anew:
/// what a forger (or a writer with a bug) produces, and the checksum accepts.
pub fn assemble_raw(json: &[u8], maps: &[u8]) -> Vec<u8> {
    let mut out = b"SNOWCKPT".to_vec();
    out.extend_from_slice(&checkpoint::VERSION.to_le_bytes());
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&(maps.len() as u64).to_le_bytes());
    out.extend_from_slice(json);
    out.extend_from_slice(maps);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// [`assemble_raw`] of a JSON header.
pub fn assemble(header: &Value, maps: &[u8]) -> Vec<u8> {
    assemble_raw(&serde_json::to_vec(header).unwrap(), maps)
}

/// `bytes` with the header edited by `edit`, the CRC re-computed.
pub fn forge(bytes: &[u8], edit: impl FnOnce(&mut Value)) -> Vec<u8> {
    let (mut header, maps) = split(bytes);
    edit(&mut header);
    assemble(&header, &maps)
}

/// `bytes` with map `map` (0..4 the layers, then the extra maps) at `cell` set to `v`.
pub fn forge_map(bytes: &[u8], map: usize, cell: usize, v: f32) -> Vec<u8> {
    let (header, mut maps) = split(bytes);
    let at = 4 * (map * COLS * ROWS + cell);
    maps[at..at + 4].copy_from_slice(&v.to_le_bytes());
    assemble(&header, &maps)
}
