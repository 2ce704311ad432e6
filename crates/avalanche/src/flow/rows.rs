//! Rows (or blocks of rows) of several arrays at once, each item an array of slices, without
//! allocating a list of them: one after the other, on the dispatch's workers (as
//! [`snowscape_terrain::parallel::Rows`], through [`Rows::par`]), or cut
//! in two for the run's helper thread ([`Rows::split_at`]). A sub-step's passes hand their
//! rows out this way, so a sub-step allocates nothing.

use rayon::iter::plumbing::{Consumer, Producer, ProducerCallback, UnindexedConsumer, bridge};
use rayon::iter::{IndexedParallelIterator, ParallelIterator};

/// `n` chunks of `len` elements of each of `N` arrays: chunk `k` of an array is its elements
/// `k·len..(k+1)·len`, cut at its end (an array shorter than the others gives short or empty
/// chunks at the end).
#[derive(Debug)]
pub(crate) struct Rows<'a, T, const N: usize> {
    arrays: [&'a mut [T]; N],
    /// Elements per chunk.
    chunk: usize,
    /// Chunks.
    count: usize,
}

impl<'a, T, const N: usize> Rows<'a, T, N> {
    /// The `n` chunks of `len` elements of `arrays`.
    pub(crate) fn new(arrays: [&'a mut [T]; N], len: usize, n: usize) -> Self {
        Self {
            arrays,
            chunk: len,
            count: n,
        }
    }

    /// The first `k` chunks (at most all) and the rest.
    pub(crate) fn split_at(self, k: usize) -> (Self, Self) {
        let k = k.min(self.count);
        let mut first = self.arrays;
        let mut rest: [&'a mut [T]; N] = std::array::from_fn(|_| Default::default());
        for (a, r) in first.iter_mut().zip(rest.iter_mut()) {
            let whole = std::mem::take(a);
            let at = (k * self.chunk).min(whole.len());
            (*a, *r) = whole.split_at_mut(at);
        }
        (
            Self {
                arrays: first,
                chunk: self.chunk,
                count: k,
            },
            Self {
                arrays: rest,
                chunk: self.chunk,
                count: self.count - k,
            },
        )
    }

    /// The chunks, leaving none.
    fn take(&mut self) -> Self {
        let none = Self::new(std::array::from_fn(|_| Default::default()), self.chunk, 0);
        std::mem::replace(self, none)
    }

    /// The chunks on rayon's workers.
    pub(crate) fn par(self) -> ParRows<'a, T, N> {
        ParRows(self)
    }
}

impl<'a, T, const N: usize> Iterator for Rows<'a, T, N> {
    type Item = [&'a mut [T]; N];

    fn next(&mut self) -> Option<Self::Item> {
        if self.count == 0 {
            return None;
        }
        let whole = self.take();
        let (first, rest) = whole.split_at(1);
        *self = rest;
        Some(first.arrays)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.count, Some(self.count))
    }
}

impl<T, const N: usize> DoubleEndedIterator for Rows<'_, T, N> {
    fn next_back(&mut self) -> Option<Self::Item> {
        if self.count == 0 {
            return None;
        }
        let n = self.count;
        let whole = self.take();
        let (rest, last) = whole.split_at(n - 1);
        *self = rest;
        Some(last.arrays)
    }
}

impl<T, const N: usize> ExactSizeIterator for Rows<'_, T, N> {}

/// [`Rows`] handed to the project's dispatch ([`snowscape_terrain::parallel`]) with their own
/// chunk length (the dispatch's length applies to the slices beside them).
impl<'a, T: Send, const N: usize> snowscape_terrain::parallel::Rows for Rows<'a, T, N> {
    type Row = [&'a mut [T]; N];
    fn par_rows(self, _len: usize) -> impl IndexedParallelIterator<Item = Self::Row> {
        self.par()
    }
}

/// [`Rows`] as a rayon parallel iterator.
#[derive(Debug)]
pub(crate) struct ParRows<'a, T, const N: usize>(Rows<'a, T, N>);

impl<'a, T: Send, const N: usize> ParallelIterator for ParRows<'a, T, N> {
    type Item = [&'a mut [T]; N];

    fn drive_unindexed<C: UnindexedConsumer<Self::Item>>(self, consumer: C) -> C::Result {
        bridge(self, consumer)
    }

    fn opt_len(&self) -> Option<usize> {
        Some(self.0.count)
    }
}

impl<T: Send, const N: usize> IndexedParallelIterator for ParRows<'_, T, N> {
    fn drive<C: Consumer<Self::Item>>(self, consumer: C) -> C::Result {
        bridge(self, consumer)
    }

    fn len(&self) -> usize {
        self.0.count
    }

    fn with_producer<CB: ProducerCallback<Self::Item>>(self, callback: CB) -> CB::Output {
        callback.callback(self.0)
    }
}

impl<'a, T: Send, const N: usize> Producer for Rows<'a, T, N> {
    type Item = [&'a mut [T]; N];
    type IntoIter = Self;

    fn into_iter(self) -> Self {
        self
    }

    fn split_at(self, index: usize) -> (Self, Self) {
        Rows::split_at(self, index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every way of handing the chunks out gives the chunks of `chunks_mut`, empty ones past
    /// a short array's end.
    #[test]
    fn chunks_match_chunks_mut_every_way() {
        let (len, n) = (3, 5);
        let mut a: Vec<u32> = (0..15).collect();
        let mut b: Vec<u32> = (100..111).collect();
        let want: Vec<(Vec<u32>, Vec<u32>)> = (0..n)
            .map(|k| {
                let c =
                    |v: &[u32]| v[(k * len).min(v.len())..((k + 1) * len).min(v.len())].to_vec();
                (c(&a), c(&b))
            })
            .collect();
        let got: Vec<_> = Rows::new([&mut a[..], &mut b[..]], len, n)
            .map(|[x, y]| (x.to_vec(), y.to_vec()))
            .collect();
        assert_eq!(got, want);
        let back: Vec<_> = Rows::new([&mut a[..], &mut b[..]], len, n)
            .rev()
            .map(|[x, y]| (x.to_vec(), y.to_vec()))
            .collect();
        assert_eq!(back.into_iter().rev().collect::<Vec<_>>(), want);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let par: Vec<_> = pool.install(|| {
            Rows::new([&mut a[..], &mut b[..]], len, n)
                .par()
                .map(|[x, y]| (x.to_vec(), y.to_vec()))
                .collect()
        });
        assert_eq!(par, want);
        for k in 0..=n + 1 {
            let (first, rest) = Rows::new([&mut a[..], &mut b[..]], len, n).split_at(k);
            let got: Vec<_> = first
                .chain(rest)
                .map(|[x, y]| (x.to_vec(), y.to_vec()))
                .collect();
            assert_eq!(got, want, "split at {k}");
        }
        // Writes land in the arrays.
        for (k, [x, _]) in Rows::new([&mut a[..], &mut b[..]], len, n).enumerate() {
            x.fill(k as u32);
        }
        assert_eq!(a, [0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4]);
    }
}
