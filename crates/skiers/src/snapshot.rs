//! A [`SkiArea`] as plain data and back, for a season's checkpoint: a resumed season's
//! skiers carry on exactly as an uninterrupted season's do.
//!
//! The area splits into what a checkpoint stores in its own layout:
//! - [`SkiAreaHeader`]: the scalars (seed, clock, next skier id, termini rule, texture
//!   resolution), small, in the checkpoint's JSON header;
//! - three per-cell maps: the distance to the terminus (the spawn weights are rebuilt from it,
//!   bit-identical: a cell's weight is its distance when finite, the termini adding 0) and the
//!   recent-skier count and time;
//! - [`SkiTracks`]: the skiers on the slopes (every field of their motion) and the finished
//!   tracks, as JSON (floats round-trip exactly);
//! - the track texture's allocated tiles, `(index, TILE² texels)`.
//!
//! [`SkiArea::restore`] validates every decoded value before the area is built (a checksum
//! detects damage, not a file written wrong or forged): the texture resolution the
//! parameters', distances ≥ 0 or +∞, recent counts and times finite and ≥ 0, tile indices
//! within the texture and increasing, texels in [0, 1], skier ids below the next id, skier
//! positions and cells on the grid and every track's cells on it. A refusal is
//! [`SkiError::Implausible`], naming the field and the value.

use crate::area::SkiArea;
use crate::effects::RecentSkiers;
use crate::skier::{Skier, Track};
use crate::terminus::{Terminus, TerminusMap};
use crate::texture::TrackTexture;
use crate::{SkiError, SkiParams};
use serde::{Deserialize, Serialize};
use snowscape_terrain::GridGeometry;

/// Largest counter a restored area may hold (ids, decisions, passes): 10^12.
pub const MAX_COUNT: u64 = 1_000_000_000_000;

/// The scalars of a ski area.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkiAreaHeader {
    /// The random seed of spawns, steering and triggers.
    pub seed: u64,
    /// The area's clock, s.
    pub time_s: f64,
    /// The id the next skier gets.
    pub next_id: u64,
    /// The termini rule of the distance map.
    pub rule: Terminus,
    /// Sweeps the distance map took (reported only).
    pub sweeps: usize,
    /// Texels per cell of the track texture.
    pub texels_per_cell: usize,
}

/// The skiers on the slopes and the finished tracks.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct SkiTracks {
    /// Skiers on the slopes, in id order.
    pub skiers: Vec<Skier>,
    /// Tracks of skiers that stopped, in the order they stopped.
    pub finished: Vec<Track>,
}

/// Borrowed [`SkiTracks`], for writing.
#[derive(Serialize)]
struct SkiTracksRef<'a> {
    skiers: &'a [Skier],
    finished: &'a [Track],
}

/// The per-cell maps of a ski area: distance to the terminus, recent-skier count and time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SkiAreaMaps {
    /// Distance to the terminus, m (+∞: no route).
    pub distance: Vec<f32>,
    /// Recent-skier count at its last pass.
    pub recent_value: Vec<f32>,
    /// Time of the last pass, s.
    pub recent_time: Vec<f32>,
}

/// A refusal of a decoded value.
fn implausible(field: impl Into<String>, value: impl ToString, expected: &str) -> SkiError {
    SkiError::Implausible {
        field: field.into(),
        value: value.to_string(),
        expected: expected.to_string(),
    }
}

/// The index of the first value of `map` that `ok` refuses, named `field`.
fn check_map(
    map: &[f32],
    field: &str,
    ok: impl Fn(f32) -> bool,
    expected: &str,
) -> Result<(), SkiError> {
    match map.iter().position(|&v| !ok(v)) {
        Some(i) => Err(implausible(format!("{field} cell {i}"), map[i], expected)),
        None => Ok(()),
    }
}

impl SkiArea {
    /// The area's scalars.
    pub fn header(&self) -> SkiAreaHeader {
        SkiAreaHeader {
            seed: self.seed,
            time_s: self.time_s,
            next_id: self.next_id,
            rule: self.terminus.rule().clone(),
            sweeps: self.terminus.sweeps(),
            texels_per_cell: self.texture.texels_per_cell(),
        }
    }

    /// The per-cell maps, borrowed: distance, recent count, recent time.
    pub fn maps(&self) -> [&[f32]; 3] {
        let (value, time) = self.recent.arrays();
        [self.terminus.distance(), value, time]
    }

    /// The skiers on the slopes and the finished tracks as JSON ([`SkiTracks`]).
    pub fn tracks_json(&self) -> serde_json::Result<Vec<u8>> {
        serde_json::to_vec(&SkiTracksRef {
            skiers: &self.skiers,
            finished: &self.finished,
        })
    }

    /// A ski area from its parts (see the module docs), each value validated first.
    pub fn restore(
        params: &SkiParams,
        geometry: GridGeometry,
        header: SkiAreaHeader,
        maps: SkiAreaMaps,
        tracks: SkiTracks,
        tiles: Vec<(usize, Vec<f32>)>,
    ) -> Result<Self, SkiError> {
        params.validate()?;
        let n = geometry.len();
        if header.texels_per_cell != params.texels_per_cell {
            return Err(implausible(
                "ski_area.texels_per_cell",
                header.texels_per_cell,
                "the parameters' texels_per_cell",
            ));
        }
        if !(header.time_s.is_finite() && header.time_s >= 0.0) {
            return Err(implausible(
                "ski_area.time_s",
                header.time_s,
                "a time >= 0 s",
            ));
        }
        if header.next_id > MAX_COUNT {
            return Err(implausible(
                "ski_area.next_id",
                header.next_id,
                "at most 10^12",
            ));
        }
        for (name, map) in [
            ("ski distance", &maps.distance),
            ("recent skiers", &maps.recent_value),
            ("recent skier time", &maps.recent_time),
        ] {
            if map.len() != n {
                return Err(implausible(
                    name,
                    format!("{} cells", map.len()),
                    "one per grid cell",
                ));
            }
        }
        let finite = |v: f32| v.is_finite() && v >= 0.0;
        check_map(
            &maps.distance,
            "ski distance",
            |v| v >= 0.0,
            "a distance >= 0 m or +inf",
        )?;
        check_map(
            &maps.recent_value,
            "recent skiers",
            finite,
            "a finite count >= 0",
        )?;
        check_map(
            &maps.recent_time,
            "recent skier time",
            finite,
            "a finite time >= 0 s",
        )?;
        validate_tracks(&tracks, &geometry, header.next_id)?;
        let mut texture = TrackTexture::new(
            geometry.width(),
            geometry.height(),
            geometry.cell_size_x(),
            geometry.cell_size_y(),
            params.texels_per_cell,
        )?;
        texture.restore_tiles(tiles)?;
        let terminus = TerminusMap::from_distance(
            geometry.width(),
            geometry.height(),
            maps.distance,
            header.sweeps,
            header.rule,
        );
        Ok(Self {
            recent: RecentSkiers::from_arrays(maps.recent_value, maps.recent_time),
            geometry,
            seed: header.seed,
            time_s: header.time_s,
            next_id: header.next_id,
            terminus,
            skiers: tracks.skiers,
            finished: tracks.finished,
            texture,
        })
    }
}

/// Every skier on the grid with an id below `next_id` (in id order), every track's numbers
/// finite and its cells on the grid.
fn validate_tracks(tracks: &SkiTracks, g: &GridGeometry, next_id: u64) -> Result<(), SkiError> {
    let (w, h) = (g.width(), g.height());
    let (width_m, height_m) = (w as f64 * g.cell_size_x(), h as f64 * g.cell_size_y());
    let on_grid = |p: (f64, f64)| {
        p.0.is_finite()
            && p.1.is_finite()
            && (0.0..=width_m).contains(&p.0)
            && (0.0..=height_m).contains(&p.1)
    };
    let mut last_id = None;
    for (k, s) in tracks.skiers.iter().enumerate() {
        let field = |f: &str| format!("ski skiers[{k}].{f}");
        if s.id() >= next_id || last_id.is_some_and(|l| s.id() <= l) {
            return Err(implausible(
                field("id"),
                s.id(),
                "an id below the next id, in increasing order",
            ));
        }
        last_id = Some(s.id());
        for (name, p) in [
            ("pos", s.pos),
            ("fine", s.fine),
            ("last_vertex", s.last_vertex),
        ] {
            if !on_grid(p) {
                return Err(implausible(
                    field(name),
                    format!("{p:?}"),
                    "a position on the grid",
                ));
            }
        }
        for (name, c) in [("cell", s.cell), ("target", s.target)] {
            if c.0 >= w || c.1 >= h {
                return Err(implausible(
                    field(name),
                    format!("{c:?}"),
                    "a cell of the grid",
                ));
            }
        }
        let numbers = [
            s.heading.0,
            s.heading.1,
            s.sine.amplitude_m,
            s.sine.frequency,
            s.sine.phase,
            s.in_cell_length,
            s.in_cell_travel,
        ];
        if let Some(v) = numbers.iter().find(|v| !v.is_finite()) {
            return Err(implausible(field("motion"), v, "finite numbers"));
        }
        if s.decisions.max(s.passes) > MAX_COUNT {
            return Err(implausible(
                field("decisions"),
                s.decisions.max(s.passes),
                "at most 10^12",
            ));
        }
        validate_track(&s.track, &field("track"), g, next_id)?;
    }
    for (k, t) in tracks.finished.iter().enumerate() {
        validate_track(t, &format!("ski finished[{k}]"), g, next_id)?;
    }
    Ok(())
}

/// A track's id below `next_id`, its numbers finite and its cells on the grid `g`.
fn validate_track(t: &Track, field: &str, g: &GridGeometry, next_id: u64) -> Result<(), SkiError> {
    let n = g.len();
    if t.id >= next_id {
        return Err(implausible(
            format!("{field}.id"),
            t.id,
            "an id below the next id",
        ));
    }
    let times = [
        t.start_time_s,
        t.end_time_s.unwrap_or(0.0),
        t.length_m,
        t.coarse_length_m,
    ];
    if let Some(v) = times.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
        return Err(implausible(
            format!("{field}.times"),
            v,
            "finite numbers >= 0",
        ));
    }
    if let Some(v) = t.vertices.iter().flatten().find(|v| !v.is_finite()) {
        return Err(implausible(
            format!("{field}.vertices"),
            v,
            "finite coordinates",
        ));
    }
    let cells = t.cells.iter().copied();
    let choices = t.choices.iter().flat_map(|c| [c.cell, c.target]);
    if let Some(c) = cells.chain(choices).find(|&c| c >= n) {
        return Err(implausible(
            format!("{field}.cells"),
            c,
            "a cell of the grid",
        ));
    }
    if t.cells.is_empty() {
        return Err(implausible(
            format!("{field}.cells"),
            "[]",
            "the start cell at least",
        ));
    }
    Ok(())
}
