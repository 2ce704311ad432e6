//! One sub-step of the flow over the active set: its two passes (pipes, volumes and outflow
//! factors by blocks of rows; thickness and scaled pipes row by row), then the active set's
//! upkeep.

use super::*;

/// One sub-step over the active set.
///
/// Regions (`C` = the cells with snow or a moving owned pipe, `C+m` grown by `m` cells): new
/// snow and moving pipes lie in `C+1`, and a pipe with a wet end has its owner in `C+1`, so
/// pipes are updated on `C+2` (read: velocities on `C+3`), thickness on `C+1`. The active set
/// visits `seg3 ⊇ C+3` for velocities and pipes (pipes with two dry ends come out 0 without
/// reading velocities) and `seg2 ⊇ C+2` for thickness (reading fluxes on `seg3`).
pub(super) fn substep(
    params: &AvalancheParams,
    pg: &PipeGeometry,
    state: &mut AvalancheState,
    scratch: &mut AvalancheScratch,
    dt: f64,
) -> SubReport {
    let (pw, ph) = (state.pw, state.ph);
    let k = Consts::new(params, pg, pw, ph, dt);
    let simd = scratch.simd();
    scratch.seg3.build(&state.tiles, 3, pw, ph);
    scratch.seg2.build(&state.tiles, 2, pw, ph);
    let AvalancheScratch {
        new_pipes,
        flux,
        factor,
        row_tiles,
        row_stats,
        seg3,
        seg2,
        block_rows,
        max_lanes: _,
        team,
    } = scratch;
    block_rows.reserve_workers();
    let block_rows = &*block_rows;
    let (seg3, seg2) = (&*seg3, &*seg2);
    let split = Split::of(seg3, team);
    let (r0, nr) = (seg3.r0, seg3.rows());
    let empty: &[f64] = &[];
    let none = Inputs {
        h: &state.h,
        bed: &state.bed,
        nodata: &state.nodata,
        near_wall: &state.near_wall,
        pipes: [empty; 4],
        vel: [empty; 9],
        vbase: 0,
        new_pipes: [empty; 4],
        flux: [empty; 4],
        fbase: 0,
        factor: empty,
        mu: &state.mu,
        xi: &state.xi,
    };
    let pass1 = PipePass {
        params,
        pg,
        k: &k,
        simd,
        none,
        pipes: state.pipes.each_ref().map(|p| p.as_slice()),
        seg3,
        block_rows,
        r0,
        end: r0 + nr,
        pw,
        ph,
    };
    pipe_pass(&pass1, new_pipes, flux, factor, split, team);

    let ntx = state.tiles.ntx();
    let pass2 = ThicknessPass {
        k: &k,
        simd,
        inp: Inputs {
            h: empty,
            bed: empty,
            nodata: &state.nodata,
            near_wall: &[],
            pipes: [empty; 4],
            vel: [empty; 9],
            vbase: 0,
            new_pipes: new_pipes.each_ref().map(|v| v.as_slice()),
            flux: flux.each_ref().map(|v| v.as_slice()),
            fbase: 0,
            factor,
            mu: empty,
            xi: empty,
        },
        seg2,
        seg3,
        r0,
        nr,
        pw,
        ntx,
    };
    let (h, pipes) = (&mut state.h, &mut state.pipes);
    thickness_pass(&pass2, h, pipes, row_tiles, row_stats, split, team);

    let rows = RowResults {
        r0,
        stats: row_stats,
        tiles: row_tiles,
        ntx,
    };
    tally(state, rows, seg3.cells)
}

/// How a sub-step's passes are shared among threads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Split {
    /// All on the calling thread.
    None,
    /// Halves on the calling thread and the run's helper.
    Team,
    /// On the dispatch's workers ([`snowscape_terrain::parallel`]).
    Rayon,
}

impl Split {
    /// The split of a sub-step visiting the cells of `seg3`: a small flow runs on the calling
    /// thread, or splits its passes with the run's helper thread (`team`): below
    /// [`PARALLEL_MIN_CELLS`] cells a rayon fork and join cost more than the second core
    /// saves. A large one runs on the dispatch's workers (on two threads, with the helper).
    fn of(seg3: &Segments, team: &TeamHandle) -> Self {
        let big = seg3.cells >= PARALLEL_MIN_CELLS;
        if team.is_on() && !(big && parallel::workers() > 2) {
            Split::Team
        } else if big {
            Split::Rayon
        } else {
            Split::None
        }
    }
}

/// What every block of pass 1 reads: the sub-step's constants, the state's arrays (`none`:
/// the inputs no row has filled yet, `pipes` the pipes at the start of the sub-step), the
/// visited cells and the workers' own rows, and the visited rows `r0..end` of the padded
/// grid of `pw` x `ph` cells.
#[derive(Clone, Copy)]
struct PipePass<'a> {
    params: &'a AvalancheParams,
    pg: &'a PipeGeometry,
    k: &'a Consts,
    simd: Simd,
    none: Inputs<'a>,
    pipes: [&'a [f64]; 4],
    seg3: &'a Segments,
    block_rows: &'a BlockRowsPool,
    r0: usize,
    end: usize,
    pw: usize,
    ph: usize,
}

/// Pass 1: new pipe velocities, raw volumes and outflow factors, by blocks of rows
/// ([`pipe_block`]), into `new_pipes`, `flux` and `factor`. (The factors of the first row
/// of the active set are never used: no snow lies within 3 rows of it.)
fn pipe_pass(
    pass: &PipePass,
    new_pipes: &mut [Vec<f64>; 4],
    flux: &mut [Vec<f64>; 4],
    factor: &mut [f64],
    split: Split,
    team: &TeamHandle,
) {
    let PipePass {
        seg3,
        r0,
        end,
        pw,
        ph,
        ..
    } = *pass;
    let nr = end - r0;
    let rows = r0 * pw..end * pw;
    let nb = nr.div_ceil(BLOCK);
    // Block `b` holds the factors of its rows shifted down by one (the last block's may run
    // past the grid: they are cut there).
    let frows = (r0 + 1).min(ph) * pw..(end + 1).min(ph) * pw;
    let [n0, n1, n2, n3] = new_pipes.each_mut().map(|v| &mut v[rows.clone()]);
    let [f0, f1, f2, f3] = flux.each_mut().map(|v| &mut v[rows.clone()]);
    let blocks = Rows::new(
        [n0, n1, n2, n3, f0, f1, f2, f3, &mut factor[frows]],
        BLOCK * pw,
        nb,
    );
    match split {
        Split::Rayon => parallel::for_each_block(0, blocks, |bi, item| {
            pipe_block(pass, parallel::worker_index(), bi, item)
        }),
        Split::None => blocks
            .enumerate()
            .for_each(|(bi, item)| pipe_block(pass, 0, bi, item)),
        Split::Team => {
            // The blocks split where half the visited cells lie on either side.
            let mid = half_of_cells(seg3, r0, nb, BLOCK);
            let (first, rest) = blocks.split_at(mid);
            team.join(
                || {
                    first
                        .enumerate()
                        .for_each(|(bi, item)| pipe_block(pass, 0, bi, item))
                },
                || {
                    rest.enumerate()
                        .for_each(|(bi, item)| pipe_block(pass, 1, mid + bi, item))
                },
            );
        }
    }
}

/// Block `bi` of pass 1, on worker `worker`: row by row, the cell velocities, discharges and
/// surface gradients its pipes read (its rows, one row above and two below) into rows of its
/// own, its pipes, and the outflow factors of the row above (those of its first row need the
/// block above). Then it computes the pipes of the next block's first row (into rows of its
/// own) for the factors of its last row.
fn pipe_block(
    pass: &PipePass,
    worker: usize,
    bi: usize,
    [n0, n1, n2, n3, f0, f1, f2, f3, fac]: BlockItem,
) {
    let PipePass {
        params,
        pg,
        k,
        simd,
        none,
        pipes,
        seg3,
        block_rows,
        r0,
        end,
        pw,
        ph,
    } = *pass;
    let inp1 = Inputs { pipes, ..none };
    let (mut np, mut fl) = ([n0, n1, n2, n3], [f0, f1, f2, f3]);
    let b0 = r0 + bi * BLOCK;
    let b1 = b0 + np[0].len() / pw;
    // Pipes of row `b1` too, but in the last block.
    let halo = b1 < end;
    let v0 = b0.saturating_sub(1);
    let v1 = (b1 + 1 + halo as usize).min(ph - 1);
    let len = (v1 - v0 + 1) * pw;
    let mut rows_of_worker = block_rows.of_worker(worker);
    rows_of_worker.fit(len, pw);
    let BlockRows {
        vel,
        np: np_h,
        fl: fl_h,
    } = &mut *rows_of_worker;
    let vel_of = |x: usize, vel: &mut [Vec<f64>; 9]| {
        let lr = (x - v0) * pw;
        let mut row = vel.each_mut().map(|a| &mut a[lr..lr + pw]);
        vel_row(simd, k, pg, &inp1, seg3.row(x), x, &mut row);
    };
    for x in v0..=(b0 + 1).min(v1) {
        vel_of(x, vel);
    }
    for r in b0..b1 + halo as usize {
        if r + 2 <= v1 {
            vel_of(r + 2, vel);
        }
        let inp = Inputs {
            pipes,
            vel: vel.each_ref().map(|a| &a[..len]),
            vbase: v0 * pw,
            ..none
        };
        let segs = seg3.row(r);
        if r < b1 {
            let lr = (r - b0) * pw..(r - b0 + 1) * pw;
            let mut np_r = np.each_mut().map(|a| &mut a[lr.clone()]);
            let mut fl_r = fl.each_mut().map(|a| &mut a[lr.clone()]);
            let out = PipeRows {
                pipes: &mut np_r,
                fluxes: &mut fl_r,
            };
            pipes_row(simd, params, k, pg, &inp, PassRow { row: r, segs }, out);
        } else {
            // The next block's first row, after a copy of this block's last row of volumes
            // (the factors read both).
            let last = (b1 - 1 - b0) * pw..(b1 - b0) * pw;
            for (h, f) in fl_h.iter_mut().zip(fl.iter()) {
                h[..pw].copy_from_slice(&f[last.clone()]);
            }
            let mut np_r = np_h.each_mut().map(|a| &mut a[..pw]);
            let mut fl_r = fl_h.each_mut().map(|a| &mut a[pw..2 * pw]);
            let out = PipeRows {
                pipes: &mut np_r,
                fluxes: &mut fl_r,
            };
            pipes_row(simd, params, k, pg, &inp, PassRow { row: r, segs }, out);
        }
        // The factors of the row (the block's first row: the block above).
        if r > b0 {
            let inp = if r < b1 {
                Inputs {
                    flux: fl.each_ref().map(|a| &**a),
                    fbase: b0 * pw,
                    ..none
                }
            } else {
                Inputs {
                    flux: fl_h.each_ref().map(|a| &a[..2 * pw]),
                    fbase: (r - 1) * pw,
                    ..none
                }
            };
            let lr = (r - b0 - 1) * pw..(r - b0) * pw;
            factor_row(simd, k, &inp, segs, r, &mut fac[lr]);
        }
    }
}

impl BlockRows {
    /// Makes the rows long enough for a block whose velocities span `len` cells, on rows of
    /// `pw` cells (they only grow: their values are overwritten before they are read).
    fn fit(&mut self, len: usize, pw: usize) {
        for a in self.vel.iter_mut() {
            if a.len() < len {
                a.resize(len, 0.0);
            }
        }
        for a in self.np.iter_mut().chain(self.fl.iter_mut()) {
            if a.len() < 2 * pw {
                a.resize(2 * pw, 0.0);
            }
        }
    }
}

/// What every row of pass 2 reads: the sub-step's constants, the arrays of pass 1 (new
/// pipes, raw volumes, outflow factors) and the nodata flags, the visited cells, and the
/// `nr` visited rows from `r0` of a padded grid `pw` cells wide, `ntx` tiles wide.
struct ThicknessPass<'a> {
    k: &'a Consts,
    simd: Simd,
    inp: Inputs<'a>,
    seg2: &'a Segments,
    seg3: &'a Segments,
    r0: usize,
    nr: usize,
    pw: usize,
    ntx: usize,
}

/// Pass 2: thickness update (seg2), pipes scaled by the upwind cell's factor (seg3), the
/// content of each row per tile (`row_tiles`), the CFL maxima (`row_stats`), row by row.
fn thickness_pass(
    pass: &ThicknessPass,
    h: &mut [f64],
    pipes: &mut [Vec<f64>; 4],
    row_tiles: &mut [[u32; 2]],
    row_stats: &mut Vec<RowStats>,
    split: Split,
    team: &TeamHandle,
) {
    let ThicknessPass {
        k,
        simd,
        ref inp,
        seg2,
        seg3,
        r0,
        nr,
        pw,
        ntx,
    } = *pass;
    row_stats.clear();
    row_stats.resize(nr, RowStats::default());
    let rows = r0 * pw..(r0 + nr) * pw;
    let [p0, p1, p2, p3] = pipes.each_mut().map(|v| &mut v[rows.clone()]);
    let rows = Rows::new([&mut h[rows.clone()], p0, p1, p2, p3], pw, nr);
    let row = |ri: usize, [hrow, p0, p1, p2, p3]: RowItem, trow: &mut [[u32; 2]]| {
        let r = r0 + ri;
        let segs = UpdateSegs {
            row: r,
            seg2: seg2.row(r),
            seg3: seg3.row(r),
        };
        update_row(simd, k, inp, segs, hrow, &mut [p0, p1, p2, p3], trow)
    };
    let (tiles, stats) = (
        &mut row_tiles[r0 * ntx..(r0 + nr) * ntx],
        &mut row_stats[..],
    );
    match split {
        Split::Rayon => {
            parallel::for_each_row(ntx, (rows, tiles, PerRow(stats)), |ri, (item, trow, st)| {
                *st = row(ri, item, trow)
            })
        }
        Split::None => rows
            .zip(tiles.chunks_mut(ntx))
            .zip(stats.iter_mut())
            .enumerate()
            .for_each(|(ri, ((item, trow), st))| *st = row(ri, item, trow)),
        Split::Team => {
            let mid = half_of_cells(seg3, r0, nr, 1);
            let (rows, rest) = rows.split_at(mid);
            let (tiles, tiles_rest) = tiles.split_at_mut(mid * ntx);
            let (stats, stats_rest) = stats.split_at_mut(mid);
            team.join(
                || {
                    rows.zip(tiles.chunks_mut(ntx))
                        .zip(stats.iter_mut())
                        .enumerate()
                        .for_each(|(ri, ((item, trow), st))| *st = row(ri, item, trow))
                },
                || {
                    rest.zip(tiles_rest.chunks_mut(ntx))
                        .zip(stats_rest.iter_mut())
                        .enumerate()
                        .for_each(|(ri, ((item, trow), st))| *st = row(mid + ri, item, trow))
                },
            );
        }
    }
}

/// The results of pass 2 row by row: the stats of the visited rows from padded row `r0`, and
/// per padded row the content column ranges of its tiles (`ntx` entries a row).
struct RowResults<'a> {
    r0: usize,
    stats: &'a [RowStats],
    tiles: &'a [[u32; 2]],
    ntx: usize,
}

/// The sub-step's report (sums in row order) from the rows of pass 2, of a sub-step that
/// visited `visited` cells; the active set of the next sub-step (the tiles' content, the box
/// around it) and its CFL maxima into `state`.
fn tally(state: &mut AvalancheState, rows: RowResults, visited: usize) -> SubReport {
    let RowResults {
        r0,
        stats,
        tiles,
        ntx,
    } = rows;
    let mut out = SubReport {
        moved: 0.0,
        outflow: 0.0,
        max_speed: 0.0,
        flowing: 0,
        visited,
    };
    let mut wave = 0.0f64;
    state.tiles.clear();
    for (ri, st) in stats.iter().enumerate() {
        let r = r0 + ri;
        out.moved += st.moved;
        out.max_speed = out.max_speed.max(st.umax);
        out.outflow += st.outflow;
        out.flowing += st.flowing;
        wave = wave.max(st.wave);
        for &[a, b] in &tiles[r * ntx..r * ntx + st.tiles] {
            state.tiles.add(r, a as usize, b as usize);
        }
    }
    state.maxima = (out.max_speed, wave);
    state.active = state.tiles.bbox().map(|b| b.grown(state.pw, state.ph));
    out
}

/// The first of `n` groups of `rows` rows (from padded row `r0`) after which at least half of
/// the cells `seg` visits lie.
fn half_of_cells(seg: &Segments, r0: usize, n: usize, rows: usize) -> usize {
    let mut seen = 0;
    for g in 0..n {
        for r in r0 + g * rows..r0 + (g + 1) * rows {
            seen += seg
                .row(r)
                .iter()
                .map(|&[a, b]| (b - a + 1) as usize)
                .sum::<usize>();
        }
        if 2 * seen >= seg.cells {
            return g + 1;
        }
    }
    n
}
