//! The one dispatch point for data-parallel work over a grid, after pbrt-v4's `ParallelFor`:
//! every per-cell kernel of the season's phenomena and of the avalanche flow runs through
//! [`for_each_row`] (or its variants here), never through the thread pool directly.
//!
//! A kernel is a function of a row index and that row's slices of several per-cell arrays
//! ([`Rows`]: any tuple of `&mut [T]`, `&[T]`, [`PerRow`] records and [`Chunks`] of a few
//! values per row, up to twelve); the dispatch decides how rows are spread over the workers.
//! What it guarantees, once for every kernel:
//!
//! - **Each row is handed to exactly one call**, so a kernel that writes only its own row's
//!   slices (and reads anything else) gives the same bytes whatever the thread count and
//!   schedule: the season's determinism rests on this.
//! - **Results come back in row order** ([`map_rows`]): a reduction over them (a budget, a
//!   hazard sum) is summed in that order by the caller, never in the order workers finish, so
//!   it too is independent of the thread count.
//!
//! This is the seam for other backends (docs/src/architecture.md, "Backends"): on the CPU the
//! rows go to rayon's pool (its width set by `--threads` / `RAYON_NUM_THREADS`); a process
//! backend (MPI, issue 50) runs the same kernels over its block's rows after a halo exchange;
//! a GPU backend (issue 49) replaces a whole phenomenon step, whose kernels are these row
//! functions translated to WGSL and tested against them.

use rayon::prelude::*;

/// Per-row views of one or several per-cell arrays, handed to a kernel together: a slice is
/// cut into rows of the dispatch's length; a tuple of them yields a tuple of rows.
pub trait Rows: Sized + Send {
    /// What one call of the kernel receives.
    type Row: Send;
    /// The rows, `len` values each (the last may be shorter), as a parallel iterator.
    fn par_rows(self, len: usize) -> impl IndexedParallelIterator<Item = Self::Row>;
}

impl<'a, T: Send + Sync + 'a> Rows for &'a mut [T] {
    type Row = &'a mut [T];
    fn par_rows(self, len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
        self.par_chunks_mut(len)
    }
}

impl<'a, T: Sync + 'a> Rows for &'a [T] {
    type Row = &'a [T];
    fn par_rows(self, len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
        self.par_chunks(len)
    }
}

impl<'a, T: Send + Sync + 'a> Rows for &'a mut Vec<T> {
    type Row = &'a mut [T];
    fn par_rows(self, len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
        self.par_chunks_mut(len)
    }
}

impl<'a, T: Sync + 'a> Rows for &'a Vec<T> {
    type Row = &'a [T];
    fn par_rows(self, len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
        self.par_chunks(len)
    }
}

/// One record per row (a row's precomputed inputs, or a row's output slot), handed to the
/// kernel with that row.
#[derive(Debug)]
pub struct PerRow<I>(pub I);

impl<T: Send> Rows for PerRow<Vec<T>> {
    type Row = T;
    fn par_rows(self, _len: usize) -> impl IndexedParallelIterator<Item = T> {
        self.0.into_par_iter()
    }
}

impl<'a, T: Send + Sync + 'a> Rows for PerRow<&'a mut [T]> {
    type Row = &'a mut T;
    fn par_rows(self, _len: usize) -> impl IndexedParallelIterator<Item = &'a mut T> {
        self.0.par_iter_mut()
    }
}

impl<'a, T: Sync + 'a> Rows for PerRow<&'a [T]> {
    type Row = &'a T;
    fn par_rows(self, _len: usize) -> impl IndexedParallelIterator<Item = &'a T> {
        self.0.par_iter()
    }
}

/// `n` consecutive values per row, whatever the dispatch's row length: a slice of per-row
/// outputs (or inputs) of several values each, such as the sums of a block's rows handed to
/// a [`for_each_block`] kernel with that block's cells. `Chunks(v, n)` yields `v`'s chunks of
/// `n` values (the last may be shorter), the `k`-th with the `k`-th row.
#[derive(Debug)]
pub struct Chunks<S>(pub S, pub usize);

impl<'a, T: Send + Sync + 'a> Rows for Chunks<&'a mut [T]> {
    type Row = &'a mut [T];
    fn par_rows(self, _len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
        self.0.par_chunks_mut(self.1.max(1))
    }
}

impl<'a, T: Sync + 'a> Rows for Chunks<&'a [T]> {
    type Row = &'a [T];
    fn par_rows(self, _len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
        self.0.par_chunks(self.1.max(1))
    }
}

macro_rules! tuple_rows {
    ($($name:ident),+) => {
        impl<$($name: Rows),+> Rows for ($($name,)+) {
            type Row = ($($name::Row,)+);
            #[allow(non_snake_case)]
            fn par_rows(self, len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
                let ($($name,)+) = self;
                ($($name.par_rows(len),)+).into_par_iter()
            }
        }
    };
}

tuple_rows!(A, B);
tuple_rows!(A, B, C);
tuple_rows!(A, B, C, D);
tuple_rows!(A, B, C, D, E);
tuple_rows!(A, B, C, D, E, F);
tuple_rows!(A, B, C, D, E, F, G);
tuple_rows!(A, B, C, D, E, F, G, H);
tuple_rows!(A, B, C, D, E, F, G, H, I);
tuple_rows!(A, B, C, D, E, F, G, H, I, J);
tuple_rows!(A, B, C, D, E, F, G, H, I, J, K);
tuple_rows!(A, B, C, D, E, F, G, H, I, J, K, L);

/// Runs `kernel(row, rows)` once for every row of `width` cells of `rows`.
#[inline]
pub fn for_each_row<R: Rows>(width: usize, rows: R, kernel: impl Fn(usize, R::Row) + Sync + Send) {
    rows.par_rows(width.max(1))
        .enumerate()
        .for_each(|(row, r)| kernel(row, r));
}

/// Runs `kernel(block, rows)` once for every block of `len` consecutive cells (or `len`
/// records) of `rows`: for kernels whose work is independent of the grid's rows (a block of
/// cells, a band of rows, a lane-width strip).
#[inline]
pub fn for_each_block<R: Rows>(len: usize, rows: R, kernel: impl Fn(usize, R::Row) + Sync + Send) {
    for_each_row(len, rows, kernel);
}

/// `f(row, rows)` for every row of `width` cells, collected in row order (a reduction over
/// the result, summed in that order, is the same for any thread count).
#[inline]
pub fn map_rows<R: Rows, T: Send>(
    width: usize,
    rows: R,
    f: impl Fn(usize, R::Row) -> T + Sync + Send,
) -> Vec<T> {
    rows.par_rows(width.max(1))
        .enumerate()
        .map(|(row, r)| f(row, r))
        .collect()
}

/// [`for_each_row`] with a scratch value per worker, made by `init` (a row buffer the kernel
/// reuses from row to row; its contents on entry are whatever the worker's last row left).
#[inline]
pub fn for_each_row_with<R: Rows, S>(
    width: usize,
    rows: R,
    init: impl Fn() -> S + Sync + Send,
    kernel: impl Fn(&mut S, usize, R::Row) + Sync + Send,
) {
    rows.par_rows(width.max(1))
        .enumerate()
        .for_each_init(init, |s, (row, r)| kernel(s, row, r));
}

/// [`map_rows`] with a scratch value per worker, made by `init` (as [`for_each_row_with`]).
#[inline]
pub fn map_rows_with<R: Rows, S, T: Send>(
    width: usize,
    rows: R,
    init: impl Fn() -> S + Sync + Send,
    f: impl Fn(&mut S, usize, R::Row) -> T + Sync + Send,
) -> Vec<T> {
    rows.par_rows(width.max(1))
        .enumerate()
        .map_init(init, |s, (row, r)| f(s, row, r))
        .collect()
}

/// `f(i)` for every `i` in `0..n`, collected in order: independent items (rows of a
/// neighbourhood scan, tiles, bands) that read shared inputs and return their own results.
#[inline]
pub fn map_range<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    (0..n).into_par_iter().map(f).collect()
}

/// `f(value)` written into every cell of `out`, from the same cell of `input`.
#[inline]
pub fn map_cells<T: Send, U: Sync>(out: &mut [T], input: &[U], f: impl Fn(&U) -> T + Sync + Send) {
    out.par_iter_mut()
        .zip(input.par_iter())
        .for_each(|(o, i)| *o = f(i));
}

/// The smallest and largest of `values` (`None` when empty or all NaN): fixed blocks folded
/// in parallel, then the blocks' ranges in order, so the same pair (signed zeros included) for
/// any thread count.
pub fn range(values: &[f32]) -> Option<(f32, f32)> {
    let fold = |(a, b): (f32, f32), (c, d): (f32, f32)| (a.min(c), b.max(d));
    let (lo, hi) = map_rows(1 << 14, values, |_, block| {
        block
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |r, &v| fold(r, (v, v)))
    })
    .into_iter()
    .fold((f32::INFINITY, f32::NEG_INFINITY), fold);
    (lo <= hi).then_some((lo, hi))
}

/// How many workers the dispatch spreads rows over (the pool's width: `--threads` or
/// `RAYON_NUM_THREADS`, else the cores); a kernel sizes per-worker scratch with it.
#[inline]
pub fn workers() -> usize {
    rayon::current_num_threads()
}

/// The index of the worker running the caller, in `0..workers()` (0 outside the pool): the
/// slot of its per-worker scratch.
#[inline]
pub fn worker_index() -> usize {
    rayon::current_thread_index().unwrap_or(0)
}

/// Runs two independent jobs, possibly at the same time (a fork with two branches).
#[inline]
pub fn join<A: Send, B: Send>(
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    rayon::join(a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    #[test]
    fn every_row_is_visited_once_with_its_slices() {
        let (w, h) = (7, 13);
        let a: Vec<f32> = (0..w * h).map(|i| i as f32).collect();
        let mut b = vec![0.0f32; w * h];
        let mut visits = vec![0u32; h];
        let offsets: Vec<f32> = (0..h).map(|r| 1000.0 * r as f32).collect();
        for_each_row(
            w,
            (&mut b, &a, PerRow(&mut visits[..]), PerRow(offsets)),
            |row, (b, a, n, off)| {
                assert_eq!(a[0], (row * w) as f32);
                *n += 1;
                for (b, a) in b.iter_mut().zip(a) {
                    *b = a + off;
                }
            },
        );
        assert!(visits.iter().all(|&n| n == 1));
        for (i, &v) in b.iter().enumerate() {
            assert_eq!(v, i as f32 + 1000.0 * (i / w) as f32);
        }
    }

    #[test]
    fn reductions_in_row_order_do_not_depend_on_the_thread_count() {
        // Values whose float sum depends on the order they are added in.
        let v: Vec<f32> = (0..4096)
            .map(|i| ((i * 2654435761u64 as usize) % 1000) as f32 * 1e-3 + 1e4 * (i % 3) as f32)
            .collect();
        let sum = |threads: usize| {
            pool(threads).install(|| {
                map_rows(64, &v, |_, r| r.iter().map(|&x| f64::from(x)).sum::<f64>())
                    .into_iter()
                    .sum::<f64>()
            })
        };
        let one = sum(1);
        for t in [2, 3, 8] {
            assert_eq!(one.to_bits(), sum(t).to_bits(), "{t} threads");
        }
    }

    #[test]
    fn a_short_last_row_and_an_empty_grid_are_handled() {
        let mut v = vec![1u8; 10];
        for_each_block(4, &mut v, |block, r| {
            assert_eq!(r.len(), if block == 2 { 2 } else { 4 });
            r.fill(block as u8);
        });
        assert_eq!(v, [0, 0, 0, 0, 1, 1, 1, 1, 2, 2]);
        let mut empty: Vec<f32> = Vec::new();
        for_each_row(0, &mut empty, |_, _| panic!("no rows"));
        assert!(map_range(0, |i| i).is_empty());
        let mut out = vec![0.0; 3];
        map_cells(&mut out, &[1.0f32, 2.0, 3.0], |x| x * 2.0);
        assert_eq!(out, [2.0, 4.0, 6.0]);
        assert_eq!(join(|| 1, || 2), (1, 2));
        let many: Vec<f32> = (0..40_000)
            .map(|i| ((i * 7919) % 40_001) as f32 - 20_000.0)
            .collect();
        assert_eq!(range(&many), Some((-20_000.0, 20_000.0)));
        assert_eq!(range(&[]), None);
        assert_eq!(range(&[f32::NAN]), None);
        assert_eq!(range(&[2.0, f32::NAN, -1.0]), Some((-1.0, 2.0)));
        assert_eq!(pool(3).install(workers), 3);
        assert!(pool(3).install(worker_index) < 3);
        let sums = map_rows_with(
            2,
            &[1.0f32, 2.0, 3.0, 4.0, 5.0][..],
            || vec![0.0f32; 2],
            |scratch, _, r| {
                scratch[..r.len()].copy_from_slice(r);
                scratch[..r.len()].iter().sum::<f32>()
            },
        );
        assert_eq!(sums, [3.0, 7.0, 5.0]);
        let mut v = vec![0u32; 6];
        for_each_row_with(3, &mut v, || 10u32, |s, row, r| r.fill(*s + row as u32));
        assert_eq!(v, [10, 10, 10, 11, 11, 11]);
    }

    #[test]
    fn chunks_hand_n_values_with_each_row() {
        // Blocks of two rows of three cells, each with its two row sums (the last block
        // holds one row, and one sum).
        let cells: Vec<u32> = (0..15).collect();
        let mut sums = vec![0u32; 5];
        for_each_block(6, (&cells, Chunks(&mut sums[..], 2)), |block, (c, s)| {
            assert_eq!(s.len(), if block == 2 { 1 } else { 2 });
            for (s, row) in s.iter_mut().zip(c.chunks(3)) {
                *s = row.iter().sum();
            }
        });
        assert_eq!(sums, [3, 12, 21, 30, 39]);
        let firsts = map_rows(6, (&cells, Chunks(&sums[..], 2)), |_, (c, s)| (c[0], s[0]));
        assert_eq!(firsts, [(0, 3), (6, 21), (12, 39)]);
    }
}
