//! The machine's copy bandwidth: the reference that kernel memory traffic is compared with.
//!
//! A large buffer (far larger than the caches) is copied into another, in chunks spread over
//! the rayon threads, so the figure reflects the whole machine's memory system. Each copy moves
//! `2 × bytes` (a read and a write); the result is the best of the repeats after a warm-up that
//! also touches every page.

use rayon::prelude::*;
use std::hint::black_box;
use std::time::Instant;

/// Chunk of the copy handed to one rayon task, bytes.
const CHUNK_BYTES: usize = 1 << 20;

/// One parallel copy of `src` into `dst`.
fn parallel_copy(src: &[u8], dst: &mut [u8]) {
    dst.par_chunks_mut(CHUNK_BYTES)
        .zip(src.par_chunks(CHUNK_BYTES))
        .for_each(|(d, s)| d.copy_from_slice(s));
}

/// Copy bandwidth in GB/s (10⁹ bytes per second, read plus write traffic): the best of
/// `repeats` parallel copies of a `bytes`-long buffer, after one warm-up copy. `bytes` is at
/// least one chunk (1 MiB) and `repeats` at least 1.
pub fn measure_copy_bandwidth(bytes: usize, repeats: usize) -> f64 {
    let bytes = bytes.max(CHUNK_BYTES);
    let src: Vec<u8> = (0..bytes).map(|i| (i * 31 % 251) as u8).collect();
    let mut dst = vec![0u8; bytes];
    parallel_copy(&src, &mut dst);
    let mut best = f64::INFINITY;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        parallel_copy(black_box(&src), black_box(&mut dst));
        best = best.min(start.elapsed().as_secs_f64());
    }
    black_box(&dst);
    2.0 * bytes as f64 / best.max(1e-9) / 1e9
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copy_is_exact_and_bandwidth_is_finite_positive() {
        let src: Vec<u8> = (0..3 * CHUNK_BYTES + 17).map(|i| (i % 253) as u8).collect();
        let mut dst = vec![0u8; src.len()];
        parallel_copy(&src, &mut dst);
        assert_eq!(src, dst);
        let gb_s = measure_copy_bandwidth(4 << 20, 2);
        assert!(gb_s.is_finite() && gb_s > 0.0, "{gb_s}");
    }
}
