//! A record of the flow: the peak thickness and speed per cell, the kinetic energy and whether
//! anything moves, over the content tiles, in lanes of cells.
//!
//! Per cell with snow (`h > 0`), the speed is that of the velocity reconstructed from its 8
//! pipes ([`AvalancheState::velocity_at`]), its kinetic energy `½·h·|v|²·dx·dy`; the energy is
//! summed cell by cell in the order of the content boxes (tile by tile, row by row), so the lanes
//! give the bits of the one-cell code.

use super::*;

/// The record's peak maps (grid cells, row-major) and what it returns.
pub(crate) struct Peaks<'a> {
    pub thickness: &'a mut [f64],
    pub speed: &'a mut [f64],
}

/// Energy and motion found by a record.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Recorded {
    /// Kinetic energy of the flow, J per kg/m³ of density (`Σ ½·h·|v|²·area`).
    pub energy: f64,
    /// Whether a pipe touching a content cell moves.
    pub moving: bool,
}

impl AvalancheState {
    /// Raises the peaks over the content tiles and returns the flow's energy and motion
    /// (module documentation), with the kernels `scratch` runs.
    pub(crate) fn record_peaks(&self, peaks: Peaks, scratch: &AvalancheScratch) -> Recorded {
        let simd = scratch.simd();
        let w = self.geometry.width();
        let area = self.geometry.cell_area();
        let den = [2.0 * self.pg.e[2][0], 2.0 * self.pg.e[2][1]];
        let Peaks { thickness, speed } = peaks;
        let mut out = Recorded::default();
        for (r0, r1, c0, c1) in self.content_cells() {
            for r in r0..=r1 {
                let row = RecordRow {
                    k0: self.pad(c0, r),
                    i0: r * w + c0,
                    n: c1 - c0 + 1,
                };
                record_row(
                    simd,
                    self,
                    row,
                    (area, den),
                    (&mut thickness[..], &mut speed[..]),
                    &mut out,
                );
            }
        }
        out
    }
}

/// One row of a content box: its first padded index, first grid index and length.
#[derive(Debug, Clone, Copy)]
pub(super) struct RecordRow {
    k0: usize,
    i0: usize,
    n: usize,
}

#[inline(always)]
pub(super) fn record_row_lanes<V: Lanes>(
    s: &AvalancheState,
    row: RecordRow,
    (area, den): (f64, [f64; 2]),
    (thickness, speed): (&mut [f64], &mut [f64]),
    out: &mut Recorded,
) {
    let mut j = 0;
    while j < row.n {
        if j + V::N <= row.n {
            // SAFETY: the cells `j..j + V::N` of the row are grid cells, so every pipe read
            // (one row up, one column either side) lies in the padded arrays.
            unsafe {
                record_lanes::<V>(
                    s,
                    row.k0 + j,
                    row.i0 + j,
                    (area, den),
                    (thickness, speed),
                    out,
                )
            };
            j += V::N;
        } else {
            // SAFETY: as above, for one cell.
            unsafe {
                record_lanes::<f64>(
                    s,
                    row.k0 + j,
                    row.i0 + j,
                    (area, den),
                    (thickness, speed),
                    out,
                )
            };
            j += 1;
        }
    }
}

/// The record of `V::N` grid cells from padded index `k` (grid index `i`).
///
/// # Safety
/// The cells are grid cells (not the ghost ring), so that the pipes read lie in the arrays.
#[inline(always)]
unsafe fn record_lanes<V: Lanes>(
    s: &AvalancheState,
    k: usize,
    i: usize,
    (area, den): (f64, [f64; 2]),
    (thickness, speed): (&mut [f64], &mut [f64]),
    out: &mut Recorded,
) {
    // SAFETY: the caller's contract.
    unsafe {
        let (pw, p) = (s.pw, &s.pipes);
        let zero = V::splat(0.0);
        if !out.moving {
            // [`AvalancheState::at_rest`]: the 8 pipes touching each cell.
            let moving = [
                ld::<V>(&p[0], k - 1).ne(zero),
                ld::<V>(&p[0], k).ne(zero),
                ld::<V>(&p[1], k).ne(zero),
                ld::<V>(&p[1], k - pw).ne(zero),
                ld::<V>(&p[2], k).ne(zero),
                ld::<V>(&p[2], k - pw - 1).ne(zero),
                ld::<V>(&p[3], k).ne(zero),
                ld::<V>(&p[3], k - pw + 1).ne(zero),
            ]
            .into_iter()
            .reduce(V::or)
            .expect("eight pipes");
            out.moving = V::any(moving);
        }
        let hk = ld::<V>(&s.h, k);
        let wet = hk.gt(zero);
        if !V::any(wet) {
            return;
        }
        // [`AvalancheState::velocity_at`].
        let half = V::splat(0.5);
        let p0 = half * (ld::<V>(&p[0], k) + ld::<V>(&p[0], k - 1));
        let p1 = half * (ld::<V>(&p[1], k) + ld::<V>(&p[1], k - pw));
        let p2 = half * (ld::<V>(&p[2], k) + ld::<V>(&p[2], k - pw - 1));
        let p3 = half * (ld::<V>(&p[3], k) + ld::<V>(&p[3], k - pw + 1));
        let vx_d = (p2 - p3) / V::splat(den[0]);
        let vy_d = (p2 + p3) / V::splat(den[1]);
        let (v0, v1) = (half * (p0 + vx_d), half * (p1 + vy_d));
        let sp2 = v0 * v0 + v1 * v1;
        let peak_h = ld::<V>(thickness, i);
        V::select(V::and(wet, hk.gt(peak_h)), hk, peak_h).store(thickness, i);
        let sp = sp2.sqrt();
        let peak_u = ld::<V>(speed, i);
        V::select(V::and(wet, sp.gt(peak_u)), sp, peak_u).store(speed, i);
        // The energy cell by cell (a dry cell adds nothing: every term is ≥ 0).
        let e = V::select(wet, half * hk * sp2 * V::splat(area), zero);
        let mut cells = [0.0; 8];
        e.store(&mut cells, 0);
        for &v in &cells[..V::N] {
            out.energy += v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The eight- and four-lane records give the one-lane bits (peaks, energy, motion), over
    /// content boxes of every width.
    #[test]
    fn records_in_lanes_match_one_cell_at_a_time() {
        let (w, h) = (53, 37);
        let g = GridGeometry::new(w, h, 4.0, 3.0).unwrap();
        let bed: Vec<f64> = (0..w * h)
            .map(|i| -3.0 * (i / w) as f64 + 0.1 * ((i * 7919) % 13) as f64)
            .collect();
        let mut s = AvalancheState::new(&g, &NodataMask::all_valid(), &bed).unwrap();
        let depth: Vec<f64> = (0..w * h)
            .map(|i| {
                let v = ((i * 2654435761) % 1000) as f64 / 1000.0;
                if v < 0.35 { 0.0 } else { 1.5 * v }
            })
            .collect();
        s.set_thickness(&depth).unwrap();
        let mut scratch = AvalancheScratch::default();
        step(&AvalancheParams::default(), &mut s, &mut scratch, 0.7).unwrap();
        let record = |lanes: usize| {
            let mut scratch = AvalancheScratch::default();
            scratch.set_max_lanes(lanes);
            let (mut th, mut sp) = (vec![0.1; w * h], vec![0.5; w * h]);
            let r = s.record_peaks(
                Peaks {
                    thickness: &mut th,
                    speed: &mut sp,
                },
                &scratch,
            );
            (r.energy.to_bits(), r.moving, th, sp)
        };
        let one = record(1);
        assert!(one.1, "the flow moves");
        assert!(f64::from_bits(one.0) > 0.0);
        for lanes in [4, 8] {
            assert_eq!(record(lanes), one, "{lanes} lanes");
        }
    }
}
