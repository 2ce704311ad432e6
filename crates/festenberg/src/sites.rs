//! The snow sites the kernel works on: the sites of a height-span map (von Festenberg &
//! Gumhold 2011, Section 5: "every point p_ijk is a future snow site. It stores its snow
//! capacity c_ijk ..., its height z_ijk and its indices {ijk}") plus the bridge sites of
//! Section 5.1, in one column-major structure of arrays.
//!
//! Each site carries its initial snow height `h0(p) = min(c(p), h0)` (Section 5.2; reduced on
//! bridge sites) and its base surface `s(p) = z(p) + h0(p)`, from which the kernel's height
//! differences `Δz = s(p') - s(p)` are taken.
//!
//! Kernel member selection (Section 5.2): in a neighbouring column the member is the site
//! whose base surface is nearest to `s(p)` ("the p' ... with the minimum Δz"; ties go to the
//! lower site). "If the snow capacities are both larger than 2 h0 this choice is kept. If not,
//! ... the next upper neighbour in the height span ... with sufficient snow capacity is
//! chosen": when `p` has room (c(p) >= 2 h0) but the chosen `p'` does not, the member moves up
//! its column to the next site with c >= 2 h0, if there is one. A site is visible from the sky
//! when nothing is above it (infinite capacity).

use crate::bridges::BridgeSite;
use snowscape_mesh::HeightSpanMap;

/// Sites of every column, lowest first, with their initial heights.
#[derive(Debug, Clone, PartialEq)]
pub struct SiteField {
    /// Columns along x and along y (row 0 north, as in [`HeightSpanMap`]).
    pub width: usize,
    pub height: usize,
    /// Column spacing, metres.
    pub cell_size: f64,
    /// Scene (x, y) of the south-west corner of the grid.
    pub origin: [f64; 2],
    /// `offsets[c]..offsets[c + 1]` are column `c`'s sites.
    offsets: Vec<u32>,
    /// Surface height, metres (a bridge site: the bridge's base).
    pub z: Vec<f32>,
    /// Free space above, metres (infinite under the open sky).
    pub capacity: Vec<f32>,
    /// Initial snow height `h0(p)`, metres.
    pub h0: Vec<f32>,
    /// Base surface `s(p) = z(p) + h0(p)`, metres.
    base: Vec<f32>,
    /// Column index of each site.
    pub column: Vec<u32>,
    /// For bridge sites, the distance coefficient to the supports in [0, 1] (0 at a support,
    /// 1 in the middle of the gap); negative on ordinary sites.
    pub bridge: Vec<f32>,
    /// The global initial height `h0`, metres.
    pub depth: f32,
}

/// Share of `h0` a bridge site loses in the middle of its gap (Section 5.1: the distance
/// coefficient "is used to lower the initial snow height"; the amount is ours).
pub const BRIDGE_HEIGHT_LOSS: f32 = 0.5;

impl SiteField {
    /// The sites of `map` with the initial height `depth` (h0, metres), and `bridges` placed
    /// on top of their columns (the column's old top site gets the space up to the bridge's
    /// base as its capacity).
    pub fn new(map: &HeightSpanMap, depth: f32, bridges: &[BridgeSite]) -> Self {
        let columns = map.width * map.height;
        let mut bridge_at: Vec<Option<&BridgeSite>> = vec![None; columns];
        for b in bridges {
            bridge_at[b.column as usize] = Some(b);
        }
        let n = map.site_count() + bridges.len();
        let mut f = SiteField {
            width: map.width,
            height: map.height,
            cell_size: map.cell_size,
            origin: map.origin,
            offsets: Vec::with_capacity(columns + 1),
            z: Vec::with_capacity(n),
            capacity: Vec::with_capacity(n),
            h0: Vec::with_capacity(n),
            base: Vec::with_capacity(n),
            column: Vec::with_capacity(n),
            bridge: Vec::with_capacity(n),
            depth,
        };
        f.offsets.push(0);
        for row in 0..map.height {
            for col in 0..map.width {
                let c = row * map.width + col;
                let sites = map.column(col, row);
                for (k, s) in sites.iter().enumerate() {
                    let mut cap = s.capacity;
                    if k + 1 == sites.len()
                        && let Some(b) = bridge_at[c]
                    {
                        cap = cap.min(b.z - s.z);
                    }
                    f.push(c, s.z, cap, -1.0);
                }
                if let Some(b) = bridge_at[c] {
                    f.push(c, b.z, f32::INFINITY, b.support);
                }
                f.offsets.push(f.z.len() as u32);
            }
        }
        f
    }

    fn push(&mut self, column: usize, z: f32, capacity: f32, bridge: f32) {
        let loss = if bridge >= 0.0 {
            1.0 - BRIDGE_HEIGHT_LOSS * bridge
        } else {
            1.0
        };
        self.z.push(z);
        self.capacity.push(capacity);
        let h0 = (self.depth * loss).min(capacity);
        self.h0.push(h0);
        self.base.push(z + h0);
        self.column.push(column as u32);
        self.bridge.push(bridge);
    }

    /// Number of sites.
    pub fn len(&self) -> usize {
        self.z.len()
    }

    /// Whether there is no site.
    pub fn is_empty(&self) -> bool {
        self.z.is_empty()
    }

    /// Number of bridge sites.
    pub fn bridge_count(&self) -> usize {
        self.bridge.iter().filter(|&&b| b >= 0.0).count()
    }

    /// Site indices of column `c`.
    #[inline]
    pub fn column_sites(&self, c: usize) -> std::ops::Range<usize> {
        self.offsets[c] as usize..self.offsets[c + 1] as usize
    }

    /// Base surface `s(p) = z(p) + h0(p)`.
    #[inline]
    pub fn base(&self, i: usize) -> f32 {
        self.base[i]
    }

    /// Whether nothing is above site `i`.
    #[inline]
    pub fn visible(&self, i: usize) -> bool {
        self.capacity[i] == f32::INFINITY
    }

    /// Scene (x, y) of the centre of column `c`.
    pub fn column_xy(&self, c: usize) -> [f64; 2] {
        let (col, row) = (c % self.width, c / self.width);
        [
            self.origin[0] + (col as f64 + 0.5) * self.cell_size,
            self.origin[1] + (self.height as f64 - row as f64 - 0.5) * self.cell_size,
        ]
    }

    /// The kernel member of column `c` for a site of base surface `s` (`roomy`: whether that
    /// site has capacity >= 2 h0), and its `Δz = s(p') - s`; `None` for an empty column.
    #[inline]
    pub fn member(&self, c: usize, s: f32, roomy: bool) -> Option<(usize, f32)> {
        let range = self.column_sites(c);
        let (lo, hi) = (range.start, range.end);
        if lo == hi {
            return None;
        }
        let mut best = lo;
        let mut best_d = self.base[lo] - s;
        for k in lo + 1..hi {
            let d = self.base[k] - s;
            if d.abs() < best_d.abs() {
                best = k;
                best_d = d;
            }
        }
        let two_h0 = 2.0 * self.depth;
        if roomy
            && self.capacity[best] < two_h0
            && let Some(k) = (best + 1..hi).find(|&k| self.capacity[k] >= two_h0)
        {
            return Some((k, self.base(k) - s));
        }
        Some((best, best_d))
    }

    /// Whether site `i` has room for twice the initial height.
    #[inline]
    pub fn roomy(&self, i: usize) -> bool {
        self.capacity[i] >= 2.0 * self.depth
    }
}
