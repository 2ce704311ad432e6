//! The high-resolution track texture: track intensity in [0, 1] over the whole terrain.
//!
//! The texture has `texels_per_cell` texels per grid cell along each axis and the grid's
//! extent, so texel `(u, v)` covers local metres `[u·tx, (u+1)·tx) × [v·ty, (v+1)·ty)` with
//! `tx = dx/texels_per_cell`. It is stored sparsely in 64×64 tiles allocated on first touch:
//! tracks cover a small share of a terrain, so memory and fading cost follow the tracks, not
//! the texture (a 1024² grid at 8 texels per cell is 8192², 256 MiB dense).
//!
//! **Lines.** A fine-track segment of width `w` is drawn anti-aliased by box-filter coverage
//! across the line: a texel whose centre lies at distance `d` from the segment gets the
//! overlap of `[d − w/2, d + w/2]` with `[−s/2, s/2]`, divided by `s`, where `s = sqrt(tx·ty)`
//! is the texel size (the exact coverage of a texel by a long straight band, in 1-D). Texels
//! keep the maximum of their value and the new coverage, so consecutive segments, whose round
//! ends overlap, never darken their joints and drawing is independent of the order.
//!
//! **Fading.** New or drifted snow fills tracks: [`TrackTexture::fade`] multiplies each texel
//! by `exp(−Δ/fade_depth)`, `Δ` the added snow depth (m) bilinearly interpolated between cell
//! centres at the texel centre (negative values, snow removed, count as 0).

use crate::SkiError;

/// Tile side, texels.
pub const TILE: usize = 64;

/// A sparse grayscale texture of track intensities in [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub struct TrackTexture {
    width: usize,
    height: usize,
    texels_per_cell: usize,
    grid_width: usize,
    grid_height: usize,
    texel_x: f64,
    texel_y: f64,
    tiles_x: usize,
    tiles_y: usize,
    tiles: Vec<Option<Box<[f32]>>>,
}

/// Length of the overlap of `[a, b]` and `[c, d]`.
#[inline(always)]
fn overlap(a: f64, b: f64, c: f64, d: f64) -> f64 {
    (b.min(d) - a.max(c)).max(0.0)
}

/// Squared distance from `(px, py)` to the segment `(ax, ay)–(bx, by)`.
#[inline(always)]
fn segment_distance2(px: f64, py: f64, ax: f64, ay: f64, bx: f64, by: f64) -> f64 {
    let (vx, vy) = (bx - ax, by - ay);
    let (wx, wy) = (px - ax, py - ay);
    let len2 = vx * vx + vy * vy;
    let t = if len2 > 0.0 {
        ((wx * vx + wy * vy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (dx, dy) = (wx - t * vx, wy - t * vy);
    dx * dx + dy * dy
}

impl TrackTexture {
    /// An empty texture over a `grid_width`×`grid_height` grid of `dx`×`dy` m cells.
    pub fn new(
        grid_width: usize,
        grid_height: usize,
        dx: f64,
        dy: f64,
        texels_per_cell: usize,
    ) -> Result<Self, SkiError> {
        if !(1..=crate::params::MAX_TEXELS_PER_CELL).contains(&texels_per_cell) {
            return Err(SkiError::InvalidParameter {
                name: "texels_per_cell",
                value: texels_per_cell as f64,
                expected: "in 1..=64",
            });
        }
        let (width, height) = (grid_width * texels_per_cell, grid_height * texels_per_cell);
        if width.checked_mul(height).is_none_or(|n| n > 1 << 36) {
            return Err(SkiError::TextureTooLarge {
                width,
                height,
                reason: "more than 2^36 texels",
            });
        }
        let (tiles_x, tiles_y) = (width.div_ceil(TILE), height.div_ceil(TILE));
        Ok(Self {
            width,
            height,
            texels_per_cell,
            grid_width,
            grid_height,
            texel_x: dx / texels_per_cell as f64,
            texel_y: dy / texels_per_cell as f64,
            tiles_x,
            tiles_y,
            tiles: vec![None; tiles_x * tiles_y],
        })
    }

    /// Texels along x and y.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
    /// Texels per grid cell along each axis.
    pub fn texels_per_cell(&self) -> usize {
        self.texels_per_cell
    }
    /// Texel size `(tx, ty)`, m.
    pub fn texel_size(&self) -> (f64, f64) {
        (self.texel_x, self.texel_y)
    }
    /// Number of allocated tiles.
    pub fn allocated_tiles(&self) -> usize {
        self.tiles.iter().filter(|t| t.is_some()).count()
    }

    /// Intensity of texel `(u, v)` (0 outside the texture or in an untouched tile).
    pub fn get(&self, u: usize, v: usize) -> f32 {
        if u >= self.width || v >= self.height {
            return 0.0;
        }
        match &self.tiles[(v / TILE) * self.tiles_x + u / TILE] {
            Some(t) => t[(v % TILE) * TILE + u % TILE],
            None => 0.0,
        }
    }

    /// One row of the texture, `out.len() == width`.
    pub fn row(&self, v: usize, out: &mut [f32]) {
        debug_assert_eq!(out.len(), self.width);
        let ty = v / TILE;
        for tx in 0..self.tiles_x {
            let span = &mut out[tx * TILE..((tx + 1) * TILE).min(self.width)];
            match &self.tiles[ty * self.tiles_x + tx] {
                Some(t) => {
                    let start = (v % TILE) * TILE;
                    span.copy_from_slice(&t[start..start + span.len()]);
                }
                None => span.fill(0.0),
            }
        }
    }

    /// Sum of all intensities (texel count of full-intensity equivalents).
    pub fn total(&self) -> f64 {
        self.tiles
            .iter()
            .flatten()
            .map(|t| t.iter().map(|&v| f64::from(v)).sum::<f64>())
            .sum()
    }

    #[inline(always)]
    fn texel_mut(&mut self, u: usize, v: usize) -> &mut f32 {
        let tile = self.tiles[(v / TILE) * self.tiles_x + u / TILE]
            .get_or_insert_with(|| vec![0.0; TILE * TILE].into_boxed_slice());
        &mut tile[(v % TILE) * TILE + u % TILE]
    }

    /// Draws the segment `a`–`b` (local metres) of width `width_m`, anti-aliased.
    pub fn draw_segment(&mut self, a: (f64, f64), b: (f64, f64), width_m: f64) {
        let s = (self.texel_x * self.texel_y).sqrt();
        let half = 0.5 * width_m;
        let reach = half + s;
        let reach2 = (half + 0.5 * s) * (half + 0.5 * s);
        let range = |lo: f64, hi: f64, size: f64, n: usize| -> Option<(usize, usize)> {
            let (lo, hi) = ((lo / size).floor(), (hi / size).floor());
            if hi < 0.0 || lo >= n as f64 || !(lo.is_finite() && hi.is_finite()) {
                return None;
            }
            Some((lo.max(0.0) as usize, (hi as usize).min(n - 1)))
        };
        let Some((u0, u1)) = range(
            a.0.min(b.0) - reach,
            a.0.max(b.0) + reach,
            self.texel_x,
            self.width,
        ) else {
            return;
        };
        let Some((v0, v1)) = range(
            a.1.min(b.1) - reach,
            a.1.max(b.1) + reach,
            self.texel_y,
            self.height,
        ) else {
            return;
        };
        for v in v0..=v1 {
            let py = (v as f64 + 0.5) * self.texel_y;
            for u in u0..=u1 {
                let px = (u as f64 + 0.5) * self.texel_x;
                let d2 = segment_distance2(px, py, a.0, a.1, b.0, b.1);
                if d2 >= reach2 {
                    continue;
                }
                let d = d2.sqrt();
                let cov = (overlap(d - half, d + half, -0.5 * s, 0.5 * s) / s) as f32;
                let t = self.texel_mut(u, v);
                if cov > *t {
                    *t = cov.min(1.0);
                }
            }
        }
    }

    /// Fades the tracks under new snow: each texel is multiplied by `exp(−Δ/fade_depth_m)`,
    /// `Δ` the added depth (m, one value per grid cell, row-major) interpolated bilinearly at
    /// the texel centre; negative depths count as 0. Errors on a wrong length or a NaN.
    pub fn fade(&mut self, added_depth: &[f32], fade_depth_m: f64) -> Result<(), SkiError> {
        let n = self.grid_width * self.grid_height;
        if added_depth.len() != n {
            return Err(SkiError::LengthMismatch {
                what: "added snow depth",
                got: added_depth.len(),
                expected: n,
            });
        }
        if let Some((i, &v)) = added_depth.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SkiError::BadValue {
                what: "added snow depth",
                index: i,
                value: f64::from(v),
            });
        }
        if !(fade_depth_m.is_finite() && fade_depth_m > 0.0) {
            return Err(SkiError::InvalidParameter {
                name: "fade_depth_m",
                value: fade_depth_m,
                expected: "finite and > 0",
            });
        }
        let (gw, gh, k) = (self.grid_width, self.grid_height, self.texels_per_cell);
        let inv_k = 1.0 / k as f64;
        let at = |c: usize, r: usize| f64::from(added_depth[r * gw + c].max(0.0));
        let sample = |u: usize, v: usize| -> f64 {
            // Texel centre in cell units, cell centres at whole numbers.
            let cx = ((u as f64 + 0.5) * inv_k - 0.5).clamp(0.0, (gw - 1) as f64);
            let cy = ((v as f64 + 0.5) * inv_k - 0.5).clamp(0.0, (gh - 1) as f64);
            let (c0, r0) = (cx.floor() as usize, cy.floor() as usize);
            let (c1, r1) = ((c0 + 1).min(gw - 1), (r0 + 1).min(gh - 1));
            let (fx, fy) = (cx - c0 as f64, cy - r0 as f64);
            (1.0 - fy) * ((1.0 - fx) * at(c0, r0) + fx * at(c1, r0))
                + fy * ((1.0 - fx) * at(c0, r1) + fx * at(c1, r1))
        };
        let scale = -1.0 / fade_depth_m;
        let tiles_x = self.tiles_x;
        let (width, height) = (self.width, self.height);
        for (t, tile) in self.tiles.iter_mut().enumerate() {
            let Some(tile) = tile else { continue };
            let (tu, tv) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
            for (k, texel) in tile.iter_mut().enumerate() {
                let (u, v) = (tu + k % TILE, tv + k / TILE);
                if *texel == 0.0 || u >= width || v >= height {
                    continue;
                }
                let added = sample(u, v);
                if added > 0.0 {
                    *texel = (f64::from(*texel) * (scale * added).exp()) as f32;
                }
            }
        }
        Ok(())
    }

    /// The allocated tiles, in index order: `(index, TILE² texels row by row)`.
    pub fn allocated(&self) -> impl Iterator<Item = (usize, &[f32])> {
        self.tiles
            .iter()
            .enumerate()
            .filter_map(|(k, t)| t.as_deref().map(|t| (k, t)))
    }

    /// Tiles of a texture over a `grid_width`×`grid_height` grid at `texels_per_cell`.
    pub fn tile_count(grid_width: usize, grid_height: usize, texels_per_cell: usize) -> usize {
        (grid_width * texels_per_cell).div_ceil(TILE)
            * (grid_height * texels_per_cell).div_ceil(TILE)
    }

    /// Sets the allocated tiles of an empty texture (a checkpoint's), each index within the
    /// texture and above the one before, each tile of TILE² texels in [0, 1].
    pub fn restore_tiles(&mut self, tiles: Vec<(usize, Vec<f32>)>) -> Result<(), SkiError> {
        let bad = |field: String, value: String, expected: &str| SkiError::Implausible {
            field,
            value,
            expected: expected.to_string(),
        };
        let mut last = None;
        for (index, texels) in tiles {
            if index >= self.tiles.len() || last.is_some_and(|l| index <= l) {
                return Err(bad(
                    "ski texture tile".into(),
                    index.to_string(),
                    "a tile of the texture, in increasing order",
                ));
            }
            last = Some(index);
            if texels.len() != TILE * TILE {
                return Err(bad(
                    format!("ski texture tile {index}"),
                    format!("{} texels", texels.len()),
                    "TILE² texels",
                ));
            }
            if let Some(k) = texels.iter().position(|v| !(0.0..=1.0).contains(v)) {
                return Err(bad(
                    format!("ski texture tile {index} texel {k}"),
                    texels[k].to_string(),
                    "an intensity in [0, 1]",
                ));
            }
            self.tiles[index] = Some(texels.into_boxed_slice());
        }
        Ok(())
    }

    /// Tiles along x and y (for row iteration by callers that stream the texture).
    pub fn tiles(&self) -> (usize, usize) {
        (self.tiles_x, self.tiles_y)
    }
}
