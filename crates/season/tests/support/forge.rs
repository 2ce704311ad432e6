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

/// Bytes before the JSON header: magic, version, the lengths of the header, the maps, the ski
/// tracks and the track tiles.
pub const PREAMBLE: usize = checkpoint::PREAMBLE;
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

/// The JSON header's bytes and the raw maps of a checkpoint (the maps followed by the ski
/// sections, with their two lengths ahead of them: see [`assemble_raw`]).
pub fn split_raw(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let len = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    let (header_len, maps_len, tracks_len, tiles_len) = (len(12), len(20), len(28), len(36));
    let header = bytes[PREAMBLE..PREAMBLE + header_len].to_vec();
    let body = PREAMBLE + header_len;
    let mut maps = bytes[body..body + maps_len + tracks_len + tiles_len].to_vec();
    maps.extend_from_slice(&(tracks_len as u64).to_le_bytes());
    maps.extend_from_slice(&(tiles_len as u64).to_le_bytes());
    (header, maps)
}

/// The sections after the header as [`split_raw`] gives them: the maps, the ski tracks and
/// the track tiles.
pub fn sections(rest: &[u8]) -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let n = rest.len();
    let len = |at: usize| u64::from_le_bytes(rest[at..at + 8].try_into().unwrap()) as usize;
    let (tracks_len, tiles_len) = (len(n - 16), len(n - 8));
    let maps_len = n - 16 - tracks_len - tiles_len;
    (
        rest[..maps_len].to_vec(),
        rest[maps_len..maps_len + tracks_len].to_vec(),
        rest[maps_len + tracks_len..n - 16].to_vec(),
    )
}

/// A checkpoint of `json`, the maps, the ski tracks and the track tiles, with lengths and CRC
/// computed anew.
pub fn assemble_sections(json: &[u8], maps: &[u8], tracks: &[u8], tiles: &[u8]) -> Vec<u8> {
    let mut out = b"SNOWCKPT".to_vec();
    out.extend_from_slice(&checkpoint::VERSION.to_le_bytes());
    for len in [json.len(), maps.len(), tracks.len(), tiles.len()] {
        out.extend_from_slice(&(len as u64).to_le_bytes());
    }
    for part in [json, maps, tracks, tiles] {
        out.extend_from_slice(part);
    }
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// The JSON header and the raw maps of a checkpoint.
pub fn split(bytes: &[u8]) -> (Value, Vec<u8>) {
    let (header, maps) = split_raw(bytes);
    (serde_json::from_slice(&header).unwrap(), maps)
}

/// A checkpoint of the header bytes `json` and `maps` (as [`split_raw`] gives them) with
/// lengths and CRC computed anew: what a forger (or a writer with a bug) produces, and the
/// checksum accepts. Maps too short to hold the two section lengths are assembled as they
/// are, without ski sections.
pub fn assemble_raw(json: &[u8], maps: &[u8]) -> Vec<u8> {
    if maps.len() < 16 {
        return assemble_sections(json, maps, &[], &[]);
    }
    let n = maps.len();
    let len = |at: usize| u64::from_le_bytes(maps[at..at + 8].try_into().unwrap()) as usize;
    let (tracks_len, tiles_len) = (len(n - 16), len(n - 8));
    match (n - 16).checked_sub(tracks_len.saturating_add(tiles_len)) {
        Some(_) => {
            let (m, t, l) = sections(maps);
            assemble_sections(json, &m, &t, &l)
        }
        // Lengths a mutation made nonsense of: the bytes as one maps section.
        None => assemble_sections(json, maps, &[], &[]),
    }
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
