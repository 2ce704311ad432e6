//! One indirect bounce of sunlight (Cordonnier et al. 2018, Section 4.1, Figure 6):
//!
//! `I_ind(p) = (k_ind/π) Σ_i Σ_j A_ij · I_sun(p_ij) · cos φs_ij · cos φr_ij / d_ij²`
//!
//! Receiver `p` samples senders `p_ij` in polar coordinates: `N` directions
//! `θ_i = 2π(i + ξ_p)/N` (the paper's "random directions", here a stratified set rotated by a
//! counter-based random offset `ξ_p ∈ {(j + 1/2)/64}` per cell, so the result is a pure
//! function of the seed; the 64 rotated patterns are tabulated once)
//! and radii `r_0 < … < r_{M-1}` spaced geometrically from `min_radius_m` to `max_radius_m`.
//! `A_ij = π(r_{j+1/2}² − r_{j−1/2}²)/N` is the horizontal area a sample stands for (the
//! sector of angle 2π/N between the mid-radii), with `r_{j+1/2} = (r_j + r_{j+1})/2`,
//! `r_{−1} = 0` and `r_M = r_{M−1}²/r_{M−2}` (the next geometric radius; `2r_0` when `M = 1`).
//! The paper prints `2π(…)/N`, twice the sector area (its sectors would cover the disc twice). `φr` is the angle between the receiver's normal and
//! `p_ij − p`, `φs` between the sender's normal and `p − p_ij` (both clamped at 90°: a surface
//! facing away neither sends nor receives), `d_ij` the 3-D distance.
//!
//! Departures from the paper, documented: the sum is divided by π, the Lambertian form-factor
//! normalisation that the paper's formula leaves out (without it a receiver surrounded by
//! sunlit slopes would get up to π·k_ind times their exposure, more than they receive), so
//! `k_ind` reads as the senders' albedo; senders are the nearest cell to each sample point;
//! as in the paper, occlusion between sender and receiver is not tested. Cost: O(N·M·cells).
//! Samples outside the grid or on nodata are skipped; nodata receivers get 0.

use crate::field::TerrainField;
use crate::{BounceParams, EnvironmentError};
use rayon::prelude::*;
use snowscape_terrain::random::hash3;
use snowscape_terrain::{GridGeometry, NodataMask};

/// Random stream of the per-cell rotation of the sample directions.
const STREAM_ROTATION: u64 = 0x626f_756e_6365; // "bounce"

/// Radii `r_j` and ring areas `A_ij` (per direction) of the polar sampling, metres and m².
pub fn sample_rings(params: &BounceParams, cell_size_m: f64) -> Vec<(f64, f64)> {
    let m = params.radii as usize;
    let r0 = params.min_radius_m.max(cell_size_m);
    let r1 = params.max_radius_m.max(r0);
    let radii: Vec<f64> = (0..m)
        .map(|j| {
            if m == 1 {
                r0
            } else {
                r0 * (r1 / r0).powf(j as f64 / (m - 1) as f64)
            }
        })
        .collect();
    let next = if m == 1 {
        2.0 * r0
    } else {
        radii[m - 1] * radii[m - 1] / radii[m - 2]
    };
    let n = params.directions as f64;
    (0..m)
        .map(|j| {
            let before = if j == 0 { 0.0 } else { radii[j - 1] };
            let after = if j + 1 < m { radii[j + 1] } else { next };
            let inner = 0.5 * (before + radii[j]);
            let outer = 0.5 * (radii[j] + after);
            (
                radii[j],
                std::f64::consts::PI * (outer * outer - inner * inner) / n,
            )
        })
        .collect()
}

/// Indirect exposure from `sun` (the direct exposure map, any units; the result has the same).
pub fn indirect_bounce(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    sun: &[f32],
    params: &BounceParams,
) -> Result<Vec<f32>, EnvironmentError> {
    params.validate()?;
    let field = TerrainField::new(surface, geometry, mask)?;
    if sun.len() != field.len() {
        return Err(EnvironmentError::LengthMismatch {
            what: "direct sun map",
            width: field.width,
            height: field.height,
            expected: field.len(),
            actual: sun.len(),
        });
    }
    Ok(bounce_field(&field, sun, params))
}

/// The contribution of one sender: `cos φs · cos φr / d²` for offset `d` (receiver to
/// sender, metres) and the two unit normals; 0 when either surface faces away.
#[inline(always)]
fn form_term(d: [f32; 3], n_receiver: [f32; 3], n_sender: [f32; 3]) -> f32 {
    let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let cos_r = n_receiver[0] * d[0] + n_receiver[1] * d[1] + n_receiver[2] * d[2];
    let cos_s = -(n_sender[0] * d[0] + n_sender[1] * d[1] + n_sender[2] * d[2]);
    if cos_r <= 0.0 || cos_s <= 0.0 {
        0.0
    } else {
        // cos φr cos φs / d² with both cosines un-normalised by |d|.
        cos_r * cos_s / (d2 * d2)
    }
}

/// Number of precomputed rotations of the sample pattern; each cell picks one by a keyed
/// random number (a stratified rotation quantised to 1/ROTATIONS of the sector).
const ROTATIONS: usize = 64;

/// One polar sample: grid offset, metric offset and area.
#[derive(Debug, Clone, Copy)]
struct Offset {
    dc: i32,
    dr: i32,
    east: f32,
    north: f32,
    area: f32,
}

/// The sample offsets of every rotation: `ROTATIONS` blocks of `directions × radii`.
fn offsets(params: &BounceParams, csx: f64, csy: f64) -> Vec<Offset> {
    let rings = sample_rings(params, csx.max(csy));
    let n = params.directions as usize;
    let mut out = Vec::with_capacity(ROTATIONS * n * rings.len());
    for rot in 0..ROTATIONS {
        for i in 0..n {
            let theta = std::f64::consts::TAU * (i as f64 + (rot as f64 + 0.5) / ROTATIONS as f64)
                / n as f64;
            let (se, cn) = theta.sin_cos();
            for &(r, area) in &rings {
                let dc = (r * se / csx).round() as i32;
                let dr = -(r * cn / csy).round() as i32;
                out.push(Offset {
                    dc,
                    dr,
                    east: (dc as f64 * csx) as f32,
                    north: (-dr as f64 * csy) as f32,
                    area: area as f32,
                });
            }
        }
    }
    out
}

/// The bounce on a prepared field.
pub(crate) fn bounce_field(field: &TerrainField, sun: &[f32], params: &BounceParams) -> Vec<f32> {
    bounce_fields(field, &[sun], params)
        .pop()
        .unwrap_or_default()
}

/// Most sun maps one pass of [`bounce_fields`] carries (the months of a year).
const MAX_SUNS: usize = 12;

/// The bounce of several sun maps on a prepared field (the months of a season), in one pass
/// over the samples: the sample geometry and its form term are shared by every map, so the
/// pass costs about what one map's does. Each map's bounce is the same sum, in the same order,
/// as [`bounce_field`]'s alone. More than [`MAX_SUNS`] maps are done in several passes.
pub(crate) fn bounce_fields(
    field: &TerrainField,
    suns: &[&[f32]],
    params: &BounceParams,
) -> Vec<Vec<f32>> {
    if suns.len() > MAX_SUNS {
        let (first, rest) = suns.split_at(MAX_SUNS);
        let mut out = bounce_fields(field, first, params);
        out.extend(bounce_fields(field, rest, params));
        return out;
    }
    let m = suns.len();
    let (w, h) = (field.width as i64, field.height as i64);
    let table = offsets(params, field.csx, field.csy);
    let per_cell = table.len() / ROTATIONS;
    let k = (params.k_ind / std::f64::consts::PI) as f32;
    let layout = &field.rows;
    // Sender records packed for one memory access per sample: height, normal, then the sun of
    // each map.
    let stride = 4 + m;
    let mut senders = vec![0.0f32; field.len() * stride];
    senders
        .par_chunks_mut(stride)
        .enumerate()
        .for_each(|(i, rec)| {
            let n = layout.normal[i];
            rec[..4].copy_from_slice(&[layout.z[i], n[0], n[1], n[2]]);
            for (r, sun) in rec[4..].iter_mut().zip(suns) {
                *r = sun[i];
            }
        });
    let mut out: Vec<Vec<f32>> = (0..m).map(|_| vec![0.0f32; field.len()]).collect();
    let mut rows: Vec<Vec<&mut [f32]>> = (0..field.height).map(|_| Vec::with_capacity(m)).collect();
    for map in &mut out {
        for (row, line) in map.chunks_mut(field.width).enumerate() {
            rows[row].push(line);
        }
    }
    rows.par_iter_mut().enumerate().for_each(|(row, lines)| {
        for col in 0..field.width {
            let p = row * field.width + col;
            let rec = &senders[p * stride..(p + 1) * stride];
            let [zp, nx, ny, nz] = [rec[0], rec[1], rec[2], rec[3]];
            if zp == f32::NEG_INFINITY {
                continue;
            }
            let rot = (hash3(params.seed, STREAM_ROTATION, p as u64) % ROTATIONS as u64) as usize;
            let mut sums = [0.0f32; MAX_SUNS];
            for s in &table[rot * per_cell..(rot + 1) * per_cell] {
                let (c, r) = (col as i64 + s.dc as i64, row as i64 + s.dr as i64);
                if (s.dc == 0 && s.dr == 0) || c < 0 || r < 0 || c >= w || r >= h {
                    continue;
                }
                let q = (r * w + c) as usize;
                let rec = &senders[q * stride..(q + 1) * stride];
                let [zq, mx, my, mz] = [rec[0], rec[1], rec[2], rec[3]];
                if zq == f32::NEG_INFINITY || rec[4..].iter().all(|&sq| sq == 0.0) {
                    continue;
                }
                let d = [s.east, s.north, zq - zp];
                let f = form_term(d, [nx, ny, nz], [mx, my, mz]);
                for (sum, &sq) in sums.iter_mut().zip(&rec[4..]) {
                    if sq != 0.0 {
                        *sum += s.area * sq * f;
                    }
                }
            }
            for (line, sum) in lines.iter_mut().zip(sums) {
                line[col] = k * sum;
            }
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rings_tile_the_disc() {
        let p = BounceParams {
            directions: 8,
            radii: 4,
            min_radius_m: 10.0,
            max_radius_m: 80.0,
            ..BounceParams::default()
        };
        let rings = sample_rings(&p, 2.0);
        let radii: Vec<f64> = rings.iter().map(|r| r.0).collect();
        assert!((radii[0] - 10.0).abs() < 1e-9 && (radii[3] - 80.0).abs() < 1e-9);
        assert!((radii[1] - 20.0).abs() < 1e-9);
        // Areas over all directions sum to the annulus from r_0/2 = 5 m to (r_3 + r_4)/2 = 120 m.
        let total: f64 = rings.iter().map(|r| r.1).sum::<f64>() * 8.0;
        assert!((total - std::f64::consts::PI * (120.0f64.powi(2) - 25.0)).abs() < 1e-6);
    }

    #[test]
    fn facing_surfaces_exchange_and_coplanar_do_not() {
        let up = [0.0, 0.0, 1.0];
        assert_eq!(form_term([10.0, 0.0, 0.0], up, up), 0.0);
        // A wall facing west, 10 m east of the receiver and 10 m up.
        let west = [-1.0, 0.0, 0.0];
        let t = form_term([10.0, 0.0, 10.0], up, west);
        let d = 200f32.sqrt();
        assert!((t - (10.0 / d) * (10.0 / d) / 200.0).abs() < 1e-9);
        assert_eq!(form_term([10.0, 0.0, 10.0], up, [1.0, 0.0, 0.0]), 0.0);
    }

    #[test]
    fn maps_bounced_together_equal_each_bounced_alone_bit_for_bit() {
        let g = GridGeometry::square(40, 30, 10.0).unwrap();
        let z: Vec<f32> = (0..g.len())
            .map(|i| {
                // A valley: its two flanks face each other.
                let (c, r) = ((i % 40) as f32, (i / 40) as f32);
                1000.0 + 8.0 * (c - 20.0).abs() + 3.0 * (r * 0.2).cos()
            })
            .collect();
        let mut invalid = vec![false; g.len()];
        invalid[5 * 40 + 7] = true;
        let mask = NodataMask::from_invalid(invalid);
        let field = TerrainField::new(&z, &g, &mask).unwrap();
        let params = BounceParams {
            min_radius_m: 10.0,
            max_radius_m: 150.0,
            ..BounceParams::default()
        };
        // 14 maps: more than one pass carries; some zero here and there.
        let suns: Vec<Vec<f32>> = (0..14)
            .map(|m| {
                (0..g.len())
                    .map(|i| {
                        if (i + m) % 7 == 0 {
                            0.0
                        } else {
                            ((i * (m + 3)) % 11 + 1) as f32
                        }
                    })
                    .collect()
            })
            .collect();
        let refs: Vec<&[f32]> = suns.iter().map(|v| &v[..]).collect();
        let together = bounce_fields(&field, &refs, &params);
        assert_eq!(together.len(), 14);
        for (sun, t) in suns.iter().zip(&together) {
            let alone = bounce_field(&field, sun, &params);
            assert!(alone.iter().any(|&v| v > 0.0));
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&alone), bits(t));
        }
    }
}
