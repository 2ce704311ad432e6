//! The flow state's constructors, accessors and active-set upkeep.

use super::*;

impl AvalancheState {
    /// A state with no flowing snow on `bed` (m, row-major, one value per grid cell).
    pub fn new(
        geometry: &GridGeometry,
        mask: &NodataMask,
        bed: &[f64],
    ) -> Result<Self, AvalancheError> {
        let (w, hgt) = (geometry.width(), geometry.height());
        if bed.len() != w * hgt {
            return Err(AvalancheError::LengthMismatch {
                what: "bed",
                got: bed.len(),
                expected: w * hgt,
            });
        }
        let (pw, ph) = (w + 2, hgt + 2);
        let bed_from = nearest_valid(w, hgt, mask);
        let mut nodata = vec![false; pw * ph];
        let mut pbed = vec![0.0; pw * ph];
        for r in 0..ph {
            for c in 0..pw {
                let i = (r.clamp(1, hgt) - 1) * w + c.clamp(1, w) - 1;
                let inside = c >= 1 && c <= w && r >= 1 && r <= hgt;
                nodata[r * pw + c] = inside && !mask.is_valid(i);
                // The ghost ring and nodata cells take the bed of a valid cell (module
                // documentation, *Borders*).
                let src = bed_from.get(i).map_or(i, |&j| j as usize);
                if !mask.is_valid(src) {
                    // No valid cell anywhere.
                    continue;
                }
                let b = bed[src];
                if !b.is_finite() {
                    return Err(AvalancheError::BadValue {
                        what: "bed",
                        index: src,
                        value: b,
                    });
                }
                pbed[r * pw + c] = b;
            }
        }
        let mut near_wall = vec![false; pw * ph];
        for r in 0..ph {
            for c in 0..pw {
                if nodata[r * pw + c] {
                    for rr in r.saturating_sub(1)..=(r + 1).min(ph - 1) {
                        for cc in c.saturating_sub(1)..=(c + 1).min(pw - 1) {
                            near_wall[rr * pw + cc] = true;
                        }
                    }
                }
            }
        }
        Ok(Self {
            geometry: geometry.clone(),
            pw,
            ph,
            nodata,
            bed: pbed,
            h: vec![0.0; pw * ph],
            settled: vec![0.0; pw * ph],
            pipes: std::array::from_fn(|_| vec![0.0; pw * ph]),
            active: None,
            tiles: TileSet::new(pw, ph),
            maxima: (0.0, 0.0),
            near_wall,
            bed_from,
            pg: PipeGeometry::new(geometry, ph),
            footprint: footprint::Footprint::new(pw.div_ceil(TILE) * ph.div_ceil(TILE), false),
            mu: Vec::new(),
            xi: Vec::new(),
        })
    }

    /// Sets the per-cell friction of the flow (`crate::friction_maps`): the maps are padded
    /// like the bed (the ghost ring repeats the border cells); empty maps restore the law's
    /// scalars.
    pub fn set_friction_maps(&mut self, maps: &FrictionMaps) -> Result<(), AvalancheError> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        if maps.size() != (w, hgt) && !maps.is_empty() {
            return Err(AvalancheError::GeometryMismatch {
                width: w,
                height: hgt,
                terrain_width: maps.size().0,
                terrain_height: maps.size().1,
            });
        }
        let (pw, ph) = (self.pw, self.ph);
        let pad = |map: Option<&[f64]>| -> Vec<f64> {
            let Some(map) = map else {
                return Vec::new();
            };
            let mut out = vec![0.0; pw * ph];
            for r in 0..ph {
                for c in 0..pw {
                    let i = (r.clamp(1, hgt) - 1) * w + c.clamp(1, w) - 1;
                    out[r * pw + c] = map[i];
                }
            }
            out
        };
        self.mu = pad(maps.mu());
        self.xi = pad(maps.xi());
        Ok(())
    }

    /// Whether per-cell friction maps are set.
    pub fn has_friction_maps(&self) -> bool {
        !self.mu.is_empty() || !self.xi.is_empty()
    }

    /// A state on the avalanche bed of a layered terrain: bedrock + compacted + stable snow.
    pub fn from_terrain(
        terrain: &snowscape_terrain::LayeredTerrain,
    ) -> Result<Self, AvalancheError> {
        use snowscape_terrain::SnowLayer;
        let bed: Vec<f64> = (0..terrain.bedrock.len())
            .map(|i| {
                terrain.bedrock[i] as f64
                    + terrain.layer(SnowLayer::Compacted)[i] as f64
                    + terrain.layer(SnowLayer::Stable)[i] as f64
            })
            .collect();
        Self::new(terrain.geometry(), terrain.mask(), &bed)
    }

    /// The valid grid cell whose bed the padded cell `k` takes: itself for a valid cell, the
    /// nearest valid cell for a nodata cell ([`nearest_valid`]), that of the nearest grid cell
    /// for the ghost ring; `None` where the grid has no valid cell.
    pub(super) fn bed_source(&self, k: usize) -> Option<usize> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let (r, c) = (k / self.pw, k % self.pw);
        let i = (r.clamp(1, hgt) - 1) * w + c.clamp(1, w) - 1;
        let src = self.bed_from.get(i).map_or(i, |&j| j as usize);
        (!self.nodata[self.pad(src % w, src / w)]).then_some(src)
    }

    /// The grid geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    #[inline]
    pub(crate) fn pad(&self, col: usize, row: usize) -> usize {
        (row + 1) * self.pw + col + 1
    }

    /// Flowing thickness at a grid cell, m.
    pub fn thickness_at(&self, col: usize, row: usize) -> f64 {
        self.h[self.pad(col, row)]
    }

    /// Bed altitude at a grid cell, m.
    pub fn bed_at(&self, col: usize, row: usize) -> f64 {
        self.bed[self.pad(col, row)]
    }

    /// Flowing thickness of every grid cell (row-major), m.
    pub fn thickness(&self) -> Vec<f64> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let mut out = Vec::with_capacity(w * hgt);
        for r in 0..hgt {
            let k = self.pad(0, r);
            out.extend_from_slice(&self.h[k..k + w]);
        }
        out
    }

    /// Sets the flowing thickness of every grid cell (m, row-major) and stops all motion.
    pub fn set_thickness(&mut self, h: &[f64]) -> Result<(), AvalancheError> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        if h.len() != w * hgt {
            return Err(AvalancheError::LengthMismatch {
                what: "thickness",
                got: h.len(),
                expected: w * hgt,
            });
        }
        for (i, &v) in h.iter().enumerate() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(AvalancheError::BadValue {
                    what: "thickness",
                    index: i,
                    value: v,
                });
            }
        }
        self.pipes.iter_mut().for_each(|p| p.fill(0.0));
        self.h.fill(0.0);
        self.settled.fill(0.0);
        for r in 0..hgt {
            for c in 0..w {
                let k = self.pad(c, r);
                if !self.nodata[k] {
                    self.h[k] = h[r * w + c];
                }
            }
        }
        self.refresh_active();
        Ok(())
    }

    /// Adds `dh` metres of flowing snow (at rest) to one grid cell, keeping the motion elsewhere.
    pub fn add_thickness(&mut self, col: usize, row: usize, dh: f64) -> Result<(), AvalancheError> {
        let k = self.pad(col, row);
        if !(dh.is_finite() && dh >= 0.0) {
            return Err(AvalancheError::BadValue {
                what: "added thickness",
                index: row * self.geometry.width() + col,
                value: dh,
            });
        }
        if self.nodata[k] || dh == 0.0 {
            return Ok(());
        }
        self.h[k] += dh;
        self.mark_content(k);
        Ok(())
    }

    /// Adds padded cell `k`, which received snow, to the active set (its tile touched) and
    /// to the CFL maxima.
    pub(crate) fn mark_content(&mut self, k: usize) {
        self.maxima.1 = self.maxima.1.max(self.wave_speed(k));
        let (r, c) = (k / self.pw, k % self.pw);
        self.tiles.add(r, c, c);
        let cell = ActiveBox {
            r0: r,
            r1: r,
            c0: c,
            c1: c,
        }
        .grown(self.pw, self.ph);
        self.active = Some(match self.active {
            None => cell,
            Some(b) => ActiveBox {
                r0: b.r0.min(cell.r0),
                r1: b.r1.max(cell.r1),
                c0: b.c0.min(cell.c0),
                c1: b.c1.max(cell.c1),
            },
        });
        self.touch_tile((r / TILE) * self.tiles.ntx() + c / TILE);
    }

    /// Multiplies the 8 pipes touching padded cell `k` by `factor` (in (0, 1]: snow taken up
    /// in place, whose momentum the flow shares) and raises the CFL maxima to the cell's new
    /// wave speed, `sqrt(g·h) +` the largest of those pipes' speeds, taken as they are scaled:
    /// the pipes [`AvalancheState::wave_speed`] would read again, the same value.
    pub(crate) fn slow_pipes_around(&mut self, k: usize, factor: f64) {
        let pw = self.pw;
        // Owned: east, south, south-east, south-west; reaching the cell: from the west, north,
        // north-west and north-east owners (the order of `DIRS`).
        let incoming = [k - 1, k - pw, k - pw - 1, k - pw + 1];
        let mut umax = 0.0f64;
        for (d, pipes) in self.pipes.iter_mut().enumerate() {
            pipes[k] *= factor;
            pipes[incoming[d]] *= factor;
            umax = umax.max(pipes[k].abs()).max(pipes[incoming[d]].abs());
        }
        self.maxima.1 = self.maxima.1.max((G * self.h[k]).sqrt() + umax);
    }

    /// Flowing volume on the grid, m³ (rows summed in order).
    pub fn flowing_volume(&self) -> f64 {
        let area = self.geometry.cell_area();
        let Some(bx) = self.active else {
            return 0.0;
        };
        // Only the box can hold snow; the cells outside would add zeros to the row-major sum.
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let (r0, r1) = (bx.r0.max(1), bx.r1.min(hgt));
        let (c0, c1) = (bx.c0.max(1), bx.c1.min(w));
        (r0..=r1)
            .flat_map(|r| self.h[r * self.pw + c0..=r * self.pw + c1].iter())
            .sum::<f64>()
            * area
    }

    /// Largest pipe speed, m/s.
    pub fn max_speed(&self) -> f64 {
        self.maxima.0
    }

    /// The "snow moving" layer: a grid cell is active if it or one of its 8 neighbours holds
    /// flowing snow.
    pub fn moving_mask(&self) -> Vec<bool> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let mut out = vec![false; w * hgt];
        for r in 0..hgt {
            for c in 0..w {
                let k = self.pad(c, r);
                out[r * w + c] = (-1isize..=1).any(|dr| {
                    (-1isize..=1).any(|dc| {
                        let kk = (k as isize + dr * self.pw as isize + dc) as usize;
                        self.h[kk] > 0.0
                    })
                });
            }
        }
        out
    }

    /// Velocity of the snow in a grid cell (m/s; x east, y south), reconstructed from its 8
    /// pipes as in the advection step.
    #[inline(always)]
    pub fn velocity_at(&self, col: usize, row: usize) -> [f64; 2] {
        let (k, pw) = (self.pad(col, row), self.pw);
        let p = &self.pipes;
        // (The owners of the pipes reaching the cell: west, north, north-west, north-east.)
        let p0 = 0.5 * (p[0][k] + p[0][k - 1]);
        let p1 = 0.5 * (p[1][k] + p[1][k - pw]);
        let p2 = 0.5 * (p[2][k] + p[2][k - pw - 1]);
        let p3 = 0.5 * (p[3][k] + p[3][k - pw + 1]);
        let vx_d = (p2 - p3) / (2.0 * self.pg.e[2][0]);
        let vy_d = (p2 + p3) / (2.0 * self.pg.e[2][1]);
        [0.5 * (p0 + vx_d), 0.5 * (p1 + vy_d)]
    }

    /// Whether a grid cell and all 8 pipes touching it are at rest.
    #[inline(always)]
    pub fn at_rest(&self, col: usize, row: usize) -> bool {
        let (k, pw) = (self.pad(col, row), self.pw);
        let p = &self.pipes;
        // (Row above, from the north-west to the north-east neighbour; the cell's row, from the
        // west neighbour to the cell.)
        let (up, here) = (k - pw - 1..k - pw + 2, k - 1..k + 1);
        let (n0, n1, n2, n3) = (
            &p[0][here.clone()],
            &p[1][up.clone()],
            &p[2][up.clone()],
            &p[3][up],
        );
        let (h1, h2, h3) = (&p[1][here.clone()], &p[2][here.clone()], &p[3][here]);
        n0[0] == 0.0
            && n0[1] == 0.0
            && h1[1] == 0.0
            && n1[1] == 0.0
            && h2[1] == 0.0
            && n2[0] == 0.0
            && h3[1] == 0.0
            && n3[2] == 0.0
    }

    /// `sqrt(g·h) + |u|` at padded cell `k`, `|u|` the largest speed of the 8 pipes touching it.
    pub(super) fn wave_speed(&self, k: usize) -> f64 {
        let (c, r) = (k % self.pw, k / self.pw);
        let mut umax = 0.0f64;
        for (d, &(dc, dr)) in DIRS.iter().enumerate() {
            umax = umax.max(self.pipes[d][k].abs());
            let (cc, rr) = (c as isize - dc, r as isize - dr);
            if cc >= 0 && rr >= 0 && (cc as usize) < self.pw {
                umax = umax.max(self.pipes[d][rr as usize * self.pw + cc as usize].abs());
            }
        }
        (G * self.h[k]).sqrt() + umax
    }

    /// Recomputes the active set, the active box and the CFL maxima by scanning the whole grid
    /// (after external edits).
    ///
    /// The largest wave speed over all cells is the larger of the wet cells' and the largest
    /// pipe speed (a dry cell's `|u|` is the speed of a pipe, and the cell at either end of the
    /// fastest pipe reaches it), so dry cells cost one look at their pipes.
    pub(crate) fn refresh_active(&mut self) {
        self.refresh_active_over(&[(0, self.ph - 1, 0, self.pw - 1)]);
    }

    /// [`AvalancheState::refresh_active`] over the padded boxes `(r0, r1, c0, c1)` only (all
    /// snow and motion must lie in them), each scanned row by row.
    pub(crate) fn refresh_active_over(&mut self, boxes: &[(usize, usize, usize, usize)]) {
        self.tiles.clear();
        let (mut umax, mut wave) = (0.0f64, 0.0f64);
        for &(r0, r1, c0, c1) in boxes {
            for r in r0..=r1 {
                let mut run: Option<(usize, usize)> = None;
                for c in c0..=c1 {
                    let k = r * self.pw + c;
                    let mut moving = false;
                    for p in &self.pipes {
                        umax = umax.max(p[k].abs());
                        moving |= p[k] != 0.0;
                    }
                    let wet = self.h[k] > 0.0;
                    if wet {
                        wave = wave.max(self.wave_speed(k));
                    }
                    if wet || moving {
                        run = match run {
                            Some((a, _)) if a / TILE == c / TILE => Some((a, c)),
                            Some((a, b)) => {
                                self.tiles.add(r, a, b);
                                Some((c, c))
                            }
                            None => Some((c, c)),
                        };
                    }
                }
                if let Some((a, b)) = run {
                    self.tiles.add(r, a, b);
                }
            }
        }
        self.maxima = (umax, wave.max(umax));
        self.active = self.tiles.bbox().map(|b| b.grown(self.pw, self.ph));
        for o in 0..self.tiles.occupied().len() {
            self.touch_tile(self.tiles.occupied()[o] as usize);
        }
    }
}

/// For every grid cell of a `w x hgt` grid, the valid cell whose bed it takes: itself where it
/// is valid, else the nearest valid cell by 8-neighbour steps (a breadth-first fill from all
/// valid cells at once, one ring of steps at a time: at each ring first across edges, then
/// across corners, each cell taking the source of the first cell to reach it; the sources in
/// row-major order, the neighbours west, east, north, south, then north-west, north-east,
/// south-west, south-east). A nodata cell next to valid cells thus takes the bed of one of its
/// edge neighbours where it has one. Empty where the grid has no nodata cell (every cell is
/// its own source) or no valid cell (none has one). O(cells), depends on the mask only.
pub(super) fn nearest_valid(w: usize, hgt: usize, mask: &NodataMask) -> Vec<u32> {
    let n = w * hgt;
    if !mask.has_nodata() || (0..n).all(|i| !mask.is_valid(i)) {
        return Vec::new();
    }
    // (Grids hold at most 2³² cells, so an index fits in u32.)
    let mut src = vec![0u32; n];
    let mut reached = vec![false; n];
    let mut ring: Vec<usize> = Vec::new();
    for (i, s) in src.iter_mut().enumerate() {
        if mask.is_valid(i) {
            *s = i as u32;
            reached[i] = true;
            ring.push(i);
        }
    }
    let edges: [(isize, isize); 4] = [(-1, 0), (1, 0), (0, -1), (0, 1)];
    let corners: [(isize, isize); 4] = [(-1, -1), (1, -1), (-1, 1), (1, 1)];
    let mut next = Vec::new();
    while !ring.is_empty() {
        for steps in [&edges, &corners] {
            for &i in &ring {
                let (c, r) = ((i % w) as isize, (i / w) as isize);
                for &(dc, dr) in steps {
                    let (cc, rr) = (c + dc, r + dr);
                    if cc < 0 || rr < 0 || cc >= w as isize || rr >= hgt as isize {
                        continue;
                    }
                    let j = rr as usize * w + cc as usize;
                    if !reached[j] {
                        reached[j] = true;
                        src[j] = src[i];
                        next.push(j);
                    }
                }
            }
        }
        std::mem::swap(&mut ring, &mut next);
        next.clear();
    }
    src
}
