//! How a pass walks the cells of a row: lane chunks, single lanes and border cells.

/// How a pass visits a cell.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Visit {
    /// `V::N` cells from this one, all away from the ghost ring and walls: the lane kernel.
    Chunk,
    /// `V::Half::N` such cells (eight-lane kernels only): the half-width lane kernel.
    Half,
    /// One such cell: the lane kernel on one lane.
    One,
    /// A cell near the ghost ring or a wall: the general code.
    Border,
}

/// The cells of `segs` and how to visit them: columns `lo..=hi` not flagged in `wall` run
/// the lane kernels (in chunks of `lanes`; with eight lanes, a segment's end in a chunk of four
/// where it fits), the others the general code. (An iterator, not a
/// callback, so that the kernels are compiled inside the caller, with its target features.)
pub(super) struct Walk<'a> {
    segs: &'a [[u32; 2]],
    /// Next segment, next column, last column of the current segment.
    si: usize,
    c: usize,
    b: usize,
    lo: usize,
    hi: usize,
    wall: Option<&'a [bool]>,
    lanes: usize,
}

#[inline(always)]
pub(super) fn walk<'a>(
    segs: &'a [[u32; 2]],
    lo: usize,
    hi: usize,
    wall: Option<&'a [bool]>,
    lanes: usize,
) -> Walk<'a> {
    Walk {
        segs,
        si: 0,
        c: 1,
        b: 0,
        lo,
        hi,
        wall,
        lanes,
    }
}

impl Walk<'_> {
    #[inline(always)]
    pub(super) fn clear(&self, c: usize) -> bool {
        self.wall.is_none_or(|w| !w[c])
    }
}

impl Iterator for Walk<'_> {
    type Item = (usize, Visit);

    #[inline(always)]
    fn next(&mut self) -> Option<(usize, Visit)> {
        if self.c > self.b {
            let &[a, b] = self.segs.get(self.si)?;
            self.si += 1;
            self.c = a as usize;
            self.b = b as usize;
        }
        let c = self.c;
        if c >= self.lo && c <= self.hi && self.clear(c) {
            let n = self.lanes;
            let end = self.b.min(self.hi);
            if n > 1 && c + n - 1 <= end && (c + 1..c + n).all(|i| self.clear(i)) {
                self.c += n;
                return Some((c, Visit::Chunk));
            }
            if n == 8 && c + 3 <= end && (c + 1..c + 4).all(|i| self.clear(i)) {
                self.c += 4;
                return Some((c, Visit::Half));
            }
            self.c += 1;
            return Some((c, Visit::One));
        }
        self.c += 1;
        Some((c, Visit::Border))
    }
}
