//! The 8-neighbourhood of a cell for slope shedding: neighbour offsets and distances, what
//! lies in each direction (a valid cell, or the border and nodata with the bed continued from
//! the opposite cell), and the steepest descent that follows from them.

use crate::phenomenon::Validity;
use snowscape_terrain::GridGeometry;

/// A neighbour: offsets and `1 / distance`.
#[derive(Clone, Copy)]
pub(super) struct Neighbour {
    pub(super) dc: isize,
    pub(super) dr: isize,
    /// `dr · width + dc`: the index offset.
    pub(super) di: isize,
    pub(super) inv_l: f32,
}

/// The 8 neighbours.
pub(super) fn neighbours(geometry: &GridGeometry) -> [Neighbour; 8] {
    let (dx, dy) = (geometry.cell_size_x(), geometry.cell_size_y());
    let w = geometry.width() as isize;
    let n = |dc, dr, l: f64| Neighbour {
        dc,
        dr,
        di: dr * w + dc,
        inv_l: (1.0 / l) as f32,
    };
    let d = dx.hypot(dy);
    [
        n(1, 0, dx),
        n(-1, 0, dx),
        n(0, -1, dy),
        n(0, 1, dy),
        n(1, -1, d),
        n(-1, -1, d),
        n(1, 1, d),
        n(-1, 1, d),
    ]
}

/// `1 / distance` of the neighbours east-west, north-south and diagonal (the groups of
/// `cascade::distance_group`).
pub(super) fn distance_inv_l(geometry: &GridGeometry) -> [f32; 3] {
    let (dx, dy) = (geometry.cell_size_x(), geometry.cell_size_y());
    [dx, dy, dx.hypot(dy)].map(|l| (1.0 / l) as f32)
}

/// What lies in the direction of a neighbour.
#[derive(Clone, Copy)]
pub(super) enum Around {
    /// A valid cell.
    Cell(usize),
    /// Beyond the grid border or in nodata; the valid cell on the opposite side.
    Ghost(usize),
}

/// Calls `f` with each of the 8 neighbours `nb` of cell `i` and what lies there: a valid
/// cell; or the border, past the grid or into nodata (with the valid opposite cell the bed is
/// continued from; east, west, north and south only: a diagonal continuation through a cell at
/// the foot of a slope would extend the slope past its foot). Directions with nothing (a
/// diagonal past the border or into nodata, a border with no valid opposite cell) are skipped.
#[inline(always)]
pub(super) fn for_each_around<V: Validity>(
    geometry: &GridGeometry,
    valid: &V,
    nb: &[Neighbour; 8],
    i: usize,
    f: impl FnMut(&Neighbour, Around),
) {
    let (w, h) = (geometry.width(), geometry.height());
    let (col, row) = (i % w, i / w);
    let interior = col > 0 && row > 0 && col + 1 < w && row + 1 < h;
    for_each_around_of(geometry, valid, nb, i, interior, f);
}

/// [`for_each_around`] for a cell whose position, away from the grid border or not, is known
/// (`interior`: not in the first or last row or column), as the sweep keeps it per cell: an
/// interior cell's neighbours need no division of its index into a column and a row.
#[inline(always)]
pub(super) fn for_each_around_of<V: Validity>(
    geometry: &GridGeometry,
    valid: &V,
    nb: &[Neighbour; 8],
    i: usize,
    interior: bool,
    mut f: impl FnMut(&Neighbour, Around),
) {
    if interior {
        for n in nb {
            let j = i.wrapping_add_signed(n.di);
            if valid.at(j) {
                f(n, Around::Cell(j));
            } else if n.dc == 0 || n.dr == 0 {
                // Into nodata: the opposite cell of an interior cell is inside the grid.
                let o = i.wrapping_sub(j.wrapping_sub(i));
                if valid.at(o) {
                    f(n, Around::Ghost(o));
                }
            }
        }
        return;
    }
    let (w, h) = (geometry.width(), geometry.height());
    let (col, row) = (i % w, i / w);
    let inside = |dc: isize, dr: isize| {
        let (c, r) = (col.wrapping_add_signed(dc), row.wrapping_add_signed(dr));
        (c < w && r < h).then(|| r * w + c)
    };
    for n in nb {
        match inside(n.dc, n.dr) {
            Some(j) if valid.at(j) => f(n, Around::Cell(j)),
            // Past the grid border or into nodata (the outline of a clipped DEM is its border).
            _ if n.dc == 0 || n.dr == 0 => {
                if let Some(o) = inside(-n.dc, -n.dr).filter(|&o| valid.at(o)) {
                    f(n, Around::Ghost(o));
                }
            }
            _ => {}
        }
    }
}

/// Steepest downhill slope (tan) from cell `i`, at height `z_i`, to a valid neighbour `j` at
/// height `z_to(j)`: the slope its snow would slide down (0 in a pit or on level ground). Past
/// the border the bed `bed` is continued linearly, so the drop to a missing neighbour is the
/// bed's rise to the opposite one.
#[inline]
pub(super) fn steepest_descent<V: Validity>(
    z_i: f32,
    z_to: impl Fn(usize) -> f32,
    bed: impl Fn(usize) -> f32,
    geometry: &GridGeometry,
    valid: &V,
    nb: &[Neighbour; 8],
    i: usize,
) -> f32 {
    let mut best = 0.0f32;
    for_each_around(geometry, valid, nb, i, |n, a| {
        let drop = match a {
            Around::Cell(j) => z_i - z_to(j),
            Around::Ghost(o) => bed(o) - bed(i),
        };
        best = best.max(drop * n.inv_l);
    });
    best
}
