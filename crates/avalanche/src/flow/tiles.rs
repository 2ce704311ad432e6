//! The active set of the flow: the padded grid cut into square tiles, each holding the box of
//! its cells with flowing snow or a moving pipe, and the row segments a pass visits (the union
//! of those boxes grown by a margin).

use super::ActiveBox;

/// Side of a tile, padded cells.
pub(crate) const TILE: usize = 16;

/// Inclusive box of padded cells; empty when `r0 > r1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct TileBox {
    r0: u32,
    r1: u32,
    c0: u32,
    c1: u32,
}

const EMPTY: TileBox = TileBox {
    r0: u32::MAX,
    r1: 0,
    c0: u32::MAX,
    c1: 0,
};

impl TileBox {
    fn is_empty(self) -> bool {
        self.r0 > self.r1
    }
}

/// Per tile, the box of its *content* cells (flowing snow or a moving owned pipe).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TileSet {
    ntx: usize,
    nty: usize,
    boxes: Vec<TileBox>,
    /// Tiles with content, sorted (row-major tile order).
    occupied: Vec<u32>,
}

impl TileSet {
    pub(crate) fn new(pw: usize, ph: usize) -> Self {
        let (ntx, nty) = (pw.div_ceil(TILE), ph.div_ceil(TILE));
        Self {
            ntx,
            nty,
            boxes: vec![EMPTY; ntx * nty],
            occupied: Vec::new(),
        }
    }

    /// The occupied tiles, sorted (row-major tile order).
    pub(crate) fn occupied(&self) -> &[u32] {
        &self.occupied
    }

    /// Tiles across one row of the grid.
    pub(crate) fn ntx(&self) -> usize {
        self.ntx
    }

    pub(crate) fn clear(&mut self) {
        for &t in &self.occupied {
            self.boxes[t as usize] = EMPTY;
        }
        self.occupied.clear();
    }

    /// Adds the content cells `c0..=c1` of row `r` (all in one tile).
    pub(crate) fn add(&mut self, r: usize, c0: usize, c1: usize) {
        debug_assert_eq!(c0 / TILE, c1 / TILE);
        let t = (r / TILE) * self.ntx + c0 / TILE;
        let b = &mut self.boxes[t];
        if b.is_empty() {
            let t = t as u32;
            // Rows arrive in order, so a new tile is nearly always the last one.
            match self.occupied.last() {
                Some(&l) if l > t => {
                    let i = self.occupied.partition_point(|&o| o < t);
                    self.occupied.insert(i, t);
                }
                _ => self.occupied.push(t),
            }
        }
        b.r0 = b.r0.min(r as u32);
        b.r1 = b.r1.max(r as u32);
        b.c0 = b.c0.min(c0 as u32);
        b.c1 = b.c1.max(c1 as u32);
    }

    /// The content box of the `t`-th occupied tile (row-major tile order), inclusive padded
    /// `(r0, r1, c0, c1)`.
    pub(crate) fn content_box(&self, t: usize) -> Option<(usize, usize, usize, usize)> {
        let b = self.boxes[*self.occupied.get(t)? as usize];
        Some((b.r0 as usize, b.r1 as usize, b.c0 as usize, b.c1 as usize))
    }

    /// The box of all content, `None` when there is none.
    pub(crate) fn bbox(&self) -> Option<ActiveBox> {
        let mut out: Option<ActiveBox> = None;
        for &t in &self.occupied {
            let b = self.boxes[t as usize];
            let (r0, r1, c0, c1) = (b.r0 as usize, b.r1 as usize, b.c0 as usize, b.c1 as usize);
            out = Some(match out {
                None => ActiveBox { r0, r1, c0, c1 },
                Some(o) => ActiveBox {
                    r0: o.r0.min(r0),
                    r1: o.r1.max(r1),
                    c0: o.c0.min(c0),
                    c1: o.c1.max(c1),
                },
            });
        }
        out
    }
}

/// Per padded row, the sorted disjoint column ranges (inclusive) of the union of the content
/// boxes grown by a margin: the cells a pass visits.
#[derive(Debug, Clone, Default)]
pub(crate) struct Segments {
    /// First row with segments (rows `r0..r0 + start.len() - 1`).
    pub(crate) r0: usize,
    /// Per row, the index of its first segment in `segs` (one extra entry at the end).
    start: Vec<u32>,
    segs: Vec<[u32; 2]>,
    /// Cells covered.
    pub(crate) cells: usize,
    tmp: Vec<[u32; 2]>,
    band: Vec<(usize, usize)>,
}

impl Segments {
    /// Number of rows covered (from `r0`).
    pub(crate) fn rows(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// The segments of row `r` (empty outside the rows covered).
    #[inline]
    pub(crate) fn row(&self, r: usize) -> &[[u32; 2]] {
        if r < self.r0 || r - self.r0 >= self.rows() {
            return &[];
        }
        let i = r - self.r0;
        &self.segs[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// Rebuilds the segments of `tiles` grown by `m` cells (`m <= TILE`), clipped to the
    /// padded grid `pw x ph`.
    pub(crate) fn build(&mut self, tiles: &TileSet, m: usize, pw: usize, ph: usize) {
        debug_assert!(m <= TILE);
        self.start.clear();
        self.segs.clear();
        self.cells = 0;
        self.r0 = 0;
        let Some(bb) = tiles.bbox() else {
            return;
        };
        let (rlo, rhi) = (bb.r0.saturating_sub(m), (bb.r1 + m).min(ph - 1));
        self.r0 = rlo;
        // Range of `occupied` per tile row.
        self.band.clear();
        self.band.resize(tiles.nty, (0, 0));
        {
            let mut i = 0;
            for (b, slot) in self.band.iter_mut().enumerate() {
                let s = i;
                while i < tiles.occupied.len() && tiles.occupied[i] as usize / tiles.ntx == b {
                    i += 1;
                }
                *slot = (s, i);
            }
        }
        for r in rlo..=rhi {
            self.start.push(self.segs.len() as u32);
            let b_lo = r.saturating_sub(m) / TILE;
            let b_hi = ((r + m) / TILE).min(tiles.nty - 1);
            self.tmp.clear();
            for &(s, e) in &self.band[b_lo..=b_hi] {
                for &t in &tiles.occupied[s..e] {
                    let b = tiles.boxes[t as usize];
                    let (br0, br1) = (b.r0 as usize, b.r1 as usize);
                    if r + m >= br0 && r <= br1 + m {
                        let c0 = (b.c0 as usize).saturating_sub(m);
                        let c1 = (b.c1 as usize + m).min(pw - 1);
                        self.tmp.push([c0 as u32, c1 as u32]);
                    }
                }
            }
            if b_hi > b_lo {
                self.tmp.sort_unstable_by_key(|s| s[0]);
            }
            let mut cur: Option<[u32; 2]> = None;
            for &s in &self.tmp {
                cur = match cur {
                    Some(c) if s[0] <= c[1] + 1 => Some([c[0], c[1].max(s[1])]),
                    Some(c) => {
                        self.cells += (c[1] - c[0] + 1) as usize;
                        self.segs.push(c);
                        Some(s)
                    }
                    None => Some(s),
                };
            }
            if let Some(c) = cur {
                self.cells += (c[1] - c[0] + 1) as usize;
                self.segs.push(c);
            }
        }
        self.start.push(self.segs.len() as u32);
    }
}
