//! Pass 2 of a sub-step on one row: the thickness update, the pipes scaled by their upwind
//! cell's outflow factor, the row's content per tile and its CFL maxima, for any lane width.
//! Away from the ghost ring and nodata cells the cells go `V::N` (or half as many, or one) at
//! a time; by them, one at a time with the general code.

use super::*;

/// Lane accumulators of pass 2 (maxima and counts: any order gives the same result).
pub(super) struct Acc<V> {
    umax: V,
    wave: V,
    flowing: usize,
}

impl<V: Lanes> Acc<V> {
    /// Nothing seen yet.
    #[inline(always)]
    fn new() -> Self {
        let zero = V::splat(0.0);
        Acc {
            umax: zero,
            wave: zero,
            flowing: 0,
        }
    }
}

/// A row of pass 2: its index, the segments of cells whose thickness it updates (`seg2`) and
/// those whose pipes it scales (`seg3`).
#[derive(Debug, Clone, Copy)]
pub(super) struct UpdateSegs<'a> {
    pub row: usize,
    pub seg2: &'a [[u32; 2]],
    pub seg3: &'a [[u32; 2]],
}

/// `V::N` cells of pass 2 from padded index `index` (column `col`), with whether their
/// thickness is updated (`thick`: they lie in `seg2`).
#[derive(Debug, Clone, Copy)]
struct LaneCell {
    index: usize,
    col: usize,
    thick: bool,
}

/// A row of pass 2 under way, visiting the cells of seg3 in column order: where it stands in
/// seg2, the accumulators of each lane width (`full` of `V::N` lanes, `half`, `one` for the
/// cells of the general code) and the row's moved volume.
struct RowPass<'s, V: Lanes> {
    seg2: Seg2Cursor<'s>,
    full: Acc<V>,
    half: Acc<V::Half>,
    one: Acc<f64>,
    /// Per cell its four pipes' volumes in direction order, then the cells in column order
    /// (the same bits for any lane width).
    moved: f64,
}

/// The segments of seg2 met by a row's cells in column order.
struct Seg2Cursor<'s> {
    seg2: &'s [[u32; 2]],
    /// The first segment not left of the current cell.
    next: usize,
}

impl Seg2Cursor<'_> {
    /// Whether column `c` (not left of the previous one asked) lies in seg2, with the last
    /// column of its segment if so, else the first column of the next segment (`usize::MAX`
    /// past the last).
    #[inline(always)]
    fn at(&mut self, c: usize) -> (bool, usize) {
        let seg2 = self.seg2;
        while self.next < seg2.len() && (seg2[self.next][1] as usize) < c {
            self.next += 1;
        }
        match seg2.get(self.next) {
            Some(&[a, b]) if a as usize <= c => (true, b as usize),
            Some(&[a, _]) => (false, a as usize),
            None => (false, usize::MAX),
        }
    }
}

/// The content cells of a row (snow or a moving pipe), met in column order, as one column
/// range per tile into the row's entries of `row_tiles`.
struct TileRuns<'t> {
    /// The range of the current tile.
    run: Option<(usize, usize)>,
    trow: &'t mut [[u32; 2]],
}

impl TileRuns<'_> {
    /// Content at column `c`: it joins the current tile's range, or closes it (one more entry
    /// in `st.tiles`) and opens the next.
    #[inline(always)]
    fn add(&mut self, c: usize, st: &mut RowStats) {
        self.run = match self.run {
            Some((a, _)) if a / TILE == c / TILE => Some((a, c)),
            Some((a, b)) => {
                self.trow[st.tiles] = [a as u32, b as u32];
                st.tiles += 1;
                Some((c, c))
            }
            None => Some((c, c)),
        };
    }

    /// The end of the row: closes the last range.
    #[inline(always)]
    fn finish(self, st: &mut RowStats) {
        if let Some((a, b)) = self.run {
            self.trow[st.tiles] = [a as u32, b as u32];
            st.tiles += 1;
        }
    }
}

/// Pass 2 on one row.
#[inline(always)]
pub(super) fn update_row_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    segs: UpdateSegs,
    hrow: &mut [f64],
    prow: &mut [&mut [f64]; 4],
    trow: &mut [[u32; 2]],
) -> RowStats {
    let UpdateSegs { row: r, seg2, seg3 } = segs;
    let (pw, ph) = (k.pw, k.ph);
    let mut st = RowStats::default();
    let mut pass = RowPass::<V> {
        seg2: Seg2Cursor { seg2, next: 0 },
        full: Acc::new(),
        half: Acc::new(),
        one: Acc::new(),
        moved: 0.0,
    };
    let (lo, hi) = if r >= 1 && r + 2 <= ph {
        (1, pw - 2)
    } else {
        (1, 0)
    };
    let mut runs = TileRuns { run: None, trow };
    // Nodata cells take the general code: with an open border, the snow that flows into them
    // leaves as the ghost ring's does.
    let nodata = &inp.nodata[r * pw..(r + 1) * pw];
    for (c, visit) in walk(seg3, lo, hi, Some(nodata), V::N) {
        let kk = r * pw + c;
        let bits = match visit {
            Visit::Chunk | Visit::Half | Visit::One => {
                // SAFETY: `walk` only gives lane visits in the inner region of this pass, where
                // the stencil lies in the padded arrays (all of length `pw·ph`).
                unsafe { update_visit(k, inp, visit, (kk, c), hrow, prow, &mut pass) }
            }
            Visit::Border => {
                let cell = GeneralCell {
                    index: kk,
                    col: c,
                    row: r,
                    nodata,
                };
                update_general(k, inp, cell, hrow, prow, &mut st, &mut pass)
            }
        };
        let mut b = bits;
        while b != 0 {
            runs.add(c + b.trailing_zeros() as usize, &mut st);
            b &= b - 1;
        }
    }
    runs.finish(&mut st);
    pass.finish(st)
}

impl<V: Lanes> RowPass<'_, V> {
    /// The row's stats `st` with its volume moved, its count of flowing cells and its maxima
    /// (over every lane).
    #[inline(always)]
    fn finish(self, mut st: RowStats) -> RowStats {
        let Self {
            full,
            half,
            one,
            moved,
            ..
        } = self;
        st.moved = moved;
        st.flowing = full.flowing + half.flowing + one.flowing;
        st.umax = one.umax;
        st.wave = one.wave;
        for i in 0..V::N {
            st.umax = st.umax.max(full.umax.lane(i));
            st.wave = st.wave.max(full.wave.lane(i));
        }
        for i in 0..V::Half::N {
            st.umax = st.umax.max(half.umax.lane(i));
            st.wave = st.wave.max(half.wave.lane(i));
        }
        st
    }
}

/// A lane visit of pass 2 (`visit`: `V::N`, `V::Half::N` or one cell from padded index `kk`,
/// column `c`): all lanes at once where they all lie in seg2 or none does, else cell by cell.
/// Returns the lanes with content.
///
/// # Safety
/// `walk` gave the visit: the cells lie in the pass's inner region, where the stencil lies in
/// the padded arrays (all of length `pw·ph`).
#[inline(always)]
unsafe fn update_visit<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    visit: Visit,
    (kk, c): (usize, usize),
    hrow: &mut [f64],
    prow: &mut [&mut [f64]; 4],
    pass: &mut RowPass<V>,
) -> u32 {
    let (inside, edge) = pass.seg2.at(c);
    let n = match visit {
        Visit::Chunk => V::N,
        Visit::Half => V::Half::N,
        _ => 1,
    };
    // SAFETY (the three calls): the caller guarantees the stencil lies in the arrays (see
    // `# Safety`).
    if n == 1 {
        unsafe {
            let cell = LaneCell {
                index: kk,
                col: c,
                thick: inside,
            };
            update_lanes::<f64>(k, inp, cell, hrow, prow, &mut pass.one, &mut pass.moved)
        }
    } else if (inside && c + n - 1 <= edge) || (!inside && c + n - 1 < edge) {
        // All lanes in seg2, or none.
        let cell = LaneCell {
            index: kk,
            col: c,
            thick: inside,
        };
        if n == V::N {
            unsafe { update_lanes::<V>(k, inp, cell, hrow, prow, &mut pass.full, &mut pass.moved) }
        } else {
            unsafe {
                update_lanes::<V::Half>(k, inp, cell, hrow, prow, &mut pass.half, &mut pass.moved)
            }
        }
    } else {
        let mut bits = 0;
        for i in 0..n {
            let inside = pass.seg2.at(c + i).0;
            let b = unsafe {
                let cell = LaneCell {
                    index: kk + i,
                    col: c + i,
                    thick: inside,
                };
                update_lanes::<f64>(k, inp, cell, hrow, prow, &mut pass.one, &mut pass.moved)
            };
            bits |= b << i;
        }
        bits
    }
}

/// A cell of pass 2 on the general code (the ghost ring, nodata cells and their neighbours):
/// its padded index, column and row, and the row's nodata flags.
#[derive(Clone, Copy)]
struct GeneralCell<'a> {
    index: usize,
    col: usize,
    row: usize,
    nodata: &'a [bool],
}

/// Pass 2 on one cell with the general code: its thickness where it lies in seg2
/// ([`general_thickness`]), its pipes ([`general_pipes`]). Returns 1 where it has content.
#[inline(always)]
fn update_general<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    cell: GeneralCell,
    hrow: &mut [f64],
    prow: &mut [&mut [f64]; 4],
    st: &mut RowStats,
    pass: &mut RowPass<V>,
) -> u32 {
    let c = cell.col;
    if pass.seg2.at(c).0 {
        general_thickness(k, inp, cell, hrow, st, &mut pass.one);
    }
    let (moving, cell_moved) = general_pipes(k, inp, cell, prow, &mut pass.one);
    pass.moved += cell_moved;
    (moving || hrow[c] > 0.0) as u32
}

/// The new thickness of a cell of seg2 on the general code, from the volumes of its 8 pipes
/// scaled by their upwind cell's factor (and its wave speed); the snow that reaches the ghost
/// ring or a nodata cell leaves the terrain (`st.outflow`).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn general_thickness(
    k: &Consts,
    inp: &Inputs,
    cell: GeneralCell,
    hrow: &mut [f64],
    st: &mut RowStats,
    acc1: &mut Acc<f64>,
) {
    let GeneralCell {
        index: kk,
        col: c,
        row: r,
        nodata,
    } = cell;
    let (pw, ph) = (k.pw, k.ph);
    let ghost_row = r == 0 || r == ph - 1;
    let mut dv = 0.0;
    for d in 0..4 {
        dv -= scaled_flux(k, inp, kk, c, r, d);
        if let Some(kb) = k.back(c, r, d) {
            let (dc, dr) = DIRS[d];
            dv += scaled_flux(k, inp, kb, (c as isize - dc) as usize, r - dr as usize, d);
        }
    }
    let mut hn = hrow[c] + dv * k.inv_area;
    if hn < 0.0 {
        hn = 0.0;
    }
    if ghost_row || c == 0 || c == pw - 1 || nodata[c] {
        // (With a closed border no snow reaches them: `hn` is 0.)
        st.outflow += hn * k.area;
        hn = 0.0;
    } else if hn > 0.0 {
        acc1.flowing += 1;
    }
    let mut umax = 0.0f64;
    for d in 0..4 {
        umax = umax.max(scaled_pipe(k, inp, kk, c, r, d).abs());
        if let Some(kb) = k.back(c, r, d) {
            let (dc, dr) = DIRS[d];
            let u = scaled_pipe(k, inp, kb, (c as isize - dc) as usize, r - dr as usize, d);
            umax = umax.max(u.abs());
        }
    }
    acc1.wave = acc1.wave.max((G * hn).sqrt() + umax);
    hrow[c] = hn;
}

/// The four pipes a cell owns on the general code, scaled by their upwind cell's factor, into
/// `prow`: whether one moves, and the volume they move (summed in direction order).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn general_pipes(
    k: &Consts,
    inp: &Inputs,
    cell: GeneralCell,
    prow: &mut [&mut [f64]; 4],
    acc1: &mut Acc<f64>,
) -> (bool, f64) {
    let GeneralCell {
        index: kk,
        col: c,
        row: r,
        ..
    } = cell;
    let mut moving = false;
    let mut cell_moved = 0.0;
    for d in 0..4 {
        let mut u = inp.new_pipes[d][kk];
        let mut f = inp.flux[d][kk];
        if f != 0.0 {
            let src = if f > 0.0 {
                kk
            } else {
                k.neighbour(c, r, d).unwrap_or(kk)
            };
            let s = inp.factor[src];
            f *= s;
            u *= s;
        }
        prow[d][c] = u;
        cell_moved += f.abs();
        acc1.umax = acc1.umax.max(u.abs());
        moving |= u != 0.0;
    }
    (moving, cell_moved)
}

/// The factor of pipe `d`'s upwind cell (the cell itself when its volume flows out, the
/// neighbour when it flows in), or `None` for a pipe that carries nothing (general code).
fn upwind_factor(k: &Consts, inp: &Inputs, kk: usize, c: usize, r: usize, d: usize) -> Option<f64> {
    let f = inp.flux[d][kk];
    (f != 0.0).then(|| {
        let src = if f > 0.0 {
            kk
        } else {
            k.neighbour(c, r, d).unwrap_or(kk)
        };
        inp.factor[src]
    })
}

/// A pipe's new velocity scaled by its upwind cell's factor (general code).
pub(super) fn scaled_pipe(
    k: &Consts,
    inp: &Inputs,
    kk: usize,
    c: usize,
    r: usize,
    d: usize,
) -> f64 {
    let u = inp.new_pipes[d][kk];
    upwind_factor(k, inp, kk, c, r, d).map_or(u, |factor| u * factor)
}

/// A pipe's volume scaled by its upwind cell's factor (general code).
pub(super) fn scaled_flux(
    k: &Consts,
    inp: &Inputs,
    kk: usize,
    c: usize,
    r: usize,
    d: usize,
) -> f64 {
    let f = inp.flux[d][kk];
    upwind_factor(k, inp, kk, c, r, d).map_or(f, |factor| f * factor)
}

/// Pass 2 on `V::N` cells away from the ghost ring: the pipes they own scaled by their upwind
/// cell's factor (volume moved, largest speed) and, with `thick`, their new thickness (and
/// wave speed). A volume `f` scaled by the factor `s` is `f·s` even for a zero `f` (`s` is
/// finite and ≥ 0), so the product needs no branch. Returns the lanes with content (snow or a
/// moving pipe).
///
/// # Safety
/// Every array of `inp` the kernel reads has the padded length `pw·ph`, and the `V::N` cells
/// from padded index `kk` lie in the pass's inner region (see the `walk` call), so that every
/// cell of the stencil is in the arrays.
#[inline(always)]
unsafe fn update_lanes<V: Lanes>(
    k: &Consts,
    inp: &Inputs,
    cell: LaneCell,
    hrow: &mut [f64],
    prow: &mut [&mut [f64]; 4],
    acc: &mut Acc<V>,
    moved: &mut f64,
) -> u32 {
    let LaneCell {
        index: kk,
        col: c,
        thick,
    } = cell;
    // SAFETY: the caller guarantees the stencil lies in the arrays (see `# Safety`).
    unsafe {
        let zero = V::splat(0.0);
        let fac = |i: usize| ld::<V>(inp.factor, i);
        let mut dv = zero;
        // Largest speed of the 8 pipes touching the cells.
        let mut ucell = zero;
        let mut moving = zero.ne(zero);
        let mut absf = [zero; 4];
        for d in 0..4 {
            let off = k.off[d];
            let f = ld::<V>(inp.flux[d], kk);
            let s = V::select(f.gt(zero), fac(kk), fac(kk + off));
            let u = ld::<V>(inp.new_pipes[d], kk);
            let u = V::select(f.ne(zero), u * s, u);
            let fs = f * s;
            absf[d] = fs.abs();
            u.store(prow[d], c);
            acc.umax = acc.umax.max(u.abs());
            moving = V::or(moving, u.ne(zero));
            if thick {
                dv = dv - fs;
                ucell = ucell.max(u.abs());
                let kb = kk - off;
                let f = ld::<V>(inp.flux[d], kb);
                let s = V::select(f.gt(zero), fac(kb), fac(kk));
                dv = dv + f * s;
                let u = ld::<V>(inp.new_pipes[d], kb);
                ucell = ucell.max(V::select(f.ne(zero), u * s, u).abs());
            }
        }
        // The row's volume in the order of the general code: per cell its four pipes (lane by
        // lane: `0 + a0` is `a0`, the general code's first sum), then cell by cell.
        let mut cells = [0.0; 8];
        ((absf[0] + absf[1]) + absf[2] + absf[3]).store(&mut cells, 0);
        for &v in &cells[..V::N] {
            *moved += v;
        }
        if thick {
            let hn = ld::<V>(hrow, c) + dv * V::splat(k.inv_area);
            let hn = V::select(hn.lt(zero), zero, hn);
            hn.store(hrow, c);
            acc.flowing += V::bits(hn.gt(zero)).count_ones() as usize;
            acc.wave = acc.wave.max((V::splat(G) * hn).sqrt() + ucell);
        }
        V::bits(V::or(moving, ld::<V>(hrow, c).gt(zero)))
    }
}
