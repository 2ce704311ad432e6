//! Scene voxelisation (Jubert 2018, Section 6.3 and Fig. 6.3): the solid cells of the wind
//! grid and the 2D height map of the transport (Section 5.3, Fig. 5.1).
//!
//! A height map (a DEM, or the orthographic top view of a mesh: the highest surface per
//! cell) is rasterised into cubic voxels of side `cell`: a voxel is solid when its centre
//! lies below the highest surface of its column ("nous remplissons toutes les cellules
//! en-dessous d'une cellule occupée", Section 6.3). A voxel column covering several height
//! map cells takes their highest surface, as the orthographic top view does.
//!
//! Axes: `x` east, `y` north, `z` up; voxel `(i, j, k)` is at index `(k ny + j) nx + i`.
//! Height-map row 0 is the northern edge, so column `j` maps to rows counted from the south.
//!
//! Size cap: a grid holds at most [`MAX_VOXELS`] (2^26, 67 M) voxels. [`VoxelGrid::dimensions`]
//! computes `nx`, `ny` from the scene's extent and the voxel side in floating point and
//! refuses a larger grid with [`TransportError::TooManyVoxels`] naming `nx`, `ny`, `nz` and
//! the cap, before anything is allocated; [`VoxelGrid::from_heights`] and the transport run
//! ([`crate::scenario::run`], which checks it first) go through it. The voxel grid itself is
//! 1 byte a voxel (the solid flags), but the wind solver over it keeps several f32 and f64
//! arrays per voxel and face (velocity and its previous step, the RK4 displacement, the mean
//! sums, the pressure and its right-hand side, the multigrid levels), so the cap bounds a
//! run's memory to a few gigabytes; a 1 m voxel over a 16 km scene (16384² x 32 layers, 8.6 G
//! voxels) is refused at once instead of aborting on an allocation.

use crate::error::{TransportError, check_positive};
use crate::terrain_wind::check_len;
use snowscape_terrain::GridGeometry;

/// The most voxels a [`VoxelGrid`] may hold: 2^26 (see the module docs).
pub const MAX_VOXELS: usize = 1 << 26;

/// Solid voxels over a rectangular domain.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelGrid {
    /// Voxels along x (east).
    pub nx: usize,
    /// Voxels along y (north).
    pub ny: usize,
    /// Voxels along z (up).
    pub nz: usize,
    /// Side of a voxel, m.
    pub cell: f64,
    /// Altitude of the bottom of the grid, m.
    pub base: f64,
    /// Whether each voxel is solid.
    pub solid: Vec<bool>,
    /// Highest surface of each column (the transport's height map), m, index `j nx + i`.
    pub column_top: Vec<f32>,
}

impl VoxelGrid {
    /// Index of voxel `(i, j, k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.ny + j) * self.nx + i
    }

    /// Whether voxel `(i, j, k)` is solid.
    #[inline]
    pub fn is_solid(&self, i: usize, j: usize, k: usize) -> bool {
        self.solid[self.index(i, j, k)]
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// Whether the grid has no voxel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The voxels along x and y of a grid of side `cell` m over `geometry`, and `nz`, after
    /// checking the total against [`MAX_VOXELS`] (in floating point, so no count can
    /// overflow): the check every voxel grid passes before it is allocated.
    pub fn dimensions(
        geometry: &GridGeometry,
        cell: f64,
        nz: usize,
    ) -> Result<(usize, usize, usize), TransportError> {
        check_positive("voxel_size_m", cell)?;
        check_positive("voxel_layers", nz as f64)?;
        let (ex, ey) = geometry.extent_m();
        let nx = (ex / cell).round().max(1.0);
        let ny = (ey / cell).round().max(1.0);
        let total = nx * ny * nz as f64;
        if !total.is_finite() || total > MAX_VOXELS as f64 {
            return Err(TransportError::TooManyVoxels {
                nx: nx as u64,
                ny: ny as u64,
                nz: nz as u64,
                voxel_size_m: cell,
                extent_x_m: ex,
                extent_y_m: ey,
                max: MAX_VOXELS as u64,
            });
        }
        Ok((nx as usize, ny as usize, nz))
    }

    /// Voxelises a height map over `geometry` into voxels of side `cell` m, `nz` voxels
    /// high from altitude `base` (Section 6.3). Fails on a bad size, a grid of more than
    /// [`MAX_VOXELS`] (before allocating) or a non-finite height.
    pub fn from_heights(
        geometry: &GridGeometry,
        heights: &[f32],
        cell: f64,
        nz: usize,
        base: f64,
    ) -> Result<Self, TransportError> {
        check_len("height", heights, geometry)?;
        let (nx, ny, nz) = Self::dimensions(geometry, cell, nz)?;
        let (_, ey) = geometry.extent_m();
        let (w, h) = (geometry.width(), geometry.height());
        let mut column_top = vec![f32::NEG_INFINITY; nx * ny];
        for row in 0..h {
            for col in 0..w {
                let z = heights[row * w + col];
                if !z.is_finite() {
                    return Err(TransportError::NonFinite {
                        phenomenon: "voxelisation",
                        what: "height",
                        col,
                        row,
                        value: f64::from(z),
                    });
                }
                // Cell centre in metres from the south-west corner.
                let x = (col as f64 + 0.5) * geometry.cell_size_x();
                let y = ey - (row as f64 + 0.5) * geometry.cell_size_y();
                let i = ((x / cell) as usize).min(nx - 1);
                let j = ((y / cell) as usize).min(ny - 1);
                let top = &mut column_top[j * nx + i];
                *top = top.max(z);
            }
        }
        // Voxel columns finer than the height map take the nearest height-map cell.
        for j in 0..ny {
            for i in 0..nx {
                if column_top[j * nx + i] == f32::NEG_INFINITY {
                    let x = (i as f64 + 0.5) * cell;
                    let y = (j as f64 + 0.5) * cell;
                    let col = ((x / geometry.cell_size_x()) as usize).min(w - 1);
                    let row = (((ey - y) / geometry.cell_size_y()) as usize).min(h - 1);
                    column_top[j * nx + i] = heights[row * w + col];
                }
            }
        }
        let mut solid = vec![false; nx * ny * nz];
        for k in 0..nz {
            let zc = base + (k as f64 + 0.5) * cell;
            for j in 0..ny {
                for i in 0..nx {
                    solid[(k * ny + j) * nx + i] = zc < f64::from(column_top[j * nx + i]);
                }
            }
        }
        Ok(Self {
            nx,
            ny,
            nz,
            cell,
            base,
            solid,
            column_top,
        })
    }

    /// Number of solid voxels at the bottom of column `(i, j)` (the ground's top layer).
    pub fn ground_layers(&self, i: usize, j: usize) -> usize {
        (0..self.nz).take_while(|&k| self.is_solid(i, j, k)).count()
    }
}

/// A castle-like scene built by the project for the thesis's "Château" scenario (Table 7.I:
/// 850 m × 850 m): gently rolling ground, a square curtain wall 12 m high and 4 m thick
/// with a gate in its west side, four round corner towers 20 m high, and a 30 m keep. The
/// walls enclose the central 30 % of the domain. Heights are in metres on a `n × n` grid
/// of `cell_m` cells.
pub fn castle_heights(n: usize, cell_m: f64) -> Vec<f32> {
    let size = n as f64 * cell_m;
    let (lo, hi) = (0.35 * size, 0.65 * size);
    let mid = 0.5 * size;
    let thick = 4.0;
    let tower_r = 8.0;
    let keep_half = 0.04 * size;
    let mut z = vec![0.0f32; n * n];
    for row in 0..n {
        for col in 0..n {
            let x = (col as f64 + 0.5) * cell_m;
            let y = size - (row as f64 + 0.5) * cell_m;
            let ground = 3.0 * ((x / size * 6.0).sin() * (y / size * 5.0).cos());
            let inside = |a: f64| a >= lo - thick && a <= hi + thick;
            let near = |a: f64, b: f64| (a - b).abs() <= thick;
            let on_wall = (inside(x) && (near(y, lo) || near(y, hi)))
                || (inside(y) && (near(x, lo) || near(x, hi)));
            let gate = near(x, lo) && (y - mid).abs() < 6.0;
            let corner = [(lo, lo), (lo, hi), (hi, lo), (hi, hi)]
                .iter()
                .any(|&(cx, cy)| (x - cx).hypot(y - cy) <= tower_r);
            let keep = (x - mid).abs() <= keep_half && (y - mid).abs() <= keep_half;
            let building = if corner {
                20.0
            } else if keep {
                30.0
            } else if on_wall && !gate {
                12.0
            } else {
                0.0
            };
            z[row * n + col] = (ground + building) as f32;
        }
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_below_the_surface_are_solid() {
        // A 4 × 2 map of 2 m cells: heights 0.9, 3.1, 5.0, 0 m over 1 m voxels → 1, 3, 5, 0
        // solid layers (a voxel is solid when its centre, at k + 0.5 m, is below the top).
        let g = GridGeometry::square(4, 2, 2.0).unwrap();
        let z = [0.9, 3.1, 5.0, 0.0, 0.9, 3.1, 5.0, 0.0];
        let v = VoxelGrid::from_heights(&g, &z, 1.0, 8, 0.0).unwrap();
        assert_eq!((v.nx, v.ny, v.nz), (8, 4, 8));
        for j in 0..4 {
            let layers: Vec<usize> = (0..8).map(|i| v.ground_layers(i, j)).collect();
            assert_eq!(layers, [1, 1, 3, 3, 5, 5, 0, 0]);
        }
        // Nothing floats: above the first empty voxel, every voxel is empty.
        for i in 0..8 {
            let n = v.ground_layers(i, 0);
            assert!((n..8).all(|k| !v.is_solid(i, 0, k)));
        }
    }

    #[test]
    fn coarse_voxels_take_the_highest_surface_of_their_cells() {
        // A thin 10 m wall one cell wide in a 1 m map survives in 4 m voxels.
        let g = GridGeometry::square(8, 8, 1.0).unwrap();
        let mut z = vec![0.0f32; 64];
        for row in 0..8 {
            z[row * 8 + 5] = 10.0;
        }
        let v = VoxelGrid::from_heights(&g, &z, 4.0, 4, 0.0).unwrap();
        assert_eq!((v.nx, v.ny), (2, 2));
        assert_eq!(v.column_top, vec![0.0, 10.0, 0.0, 10.0]);
        assert_eq!(v.ground_layers(1, 0), 2); // centres at 2 and 6 m are below 10 m
        assert_eq!(v.ground_layers(0, 0), 0);
    }

    #[test]
    fn a_grid_beyond_the_voxel_cap_is_refused_before_allocating() {
        // 16384² cells of 1 m in 1 m voxels x 32 layers: 8.6 G voxels (the old code asked for
        // 8.6 GB of solid flags alone, then the solver's arrays).
        let g = GridGeometry::square(16384, 16384, 1.0).unwrap();
        let e = VoxelGrid::dimensions(&g, 1.0, 32).unwrap_err();
        assert_eq!(
            e,
            TransportError::TooManyVoxels {
                nx: 16384,
                ny: 16384,
                nz: 32,
                voxel_size_m: 1.0,
                extent_x_m: 16384.0,
                extent_y_m: 16384.0,
                max: 1 << 26,
            }
        );
        let msg = e.to_string();
        assert!(
            msg.contains("16384 x 16384 x 32 voxels") && msg.contains("67108864"),
            "{msg}"
        );
        // from_heights refuses it the same way, before its first allocation (the heights
        // are checked for length only, so a short slice shows nothing was voxelised).
        let small = GridGeometry::square(2, 2, 8192.0).unwrap();
        let e = VoxelGrid::from_heights(&small, &[0.0; 4], 1.0, 32, 0.0).unwrap_err();
        assert!(
            matches!(e, TransportError::TooManyVoxels { nz: 32, .. }),
            "{e:?}"
        );
        // A tiny voxel side cannot overflow the count.
        let e = VoxelGrid::dimensions(&g, 1e-300, 4096).unwrap_err();
        assert!(matches!(e, TransportError::TooManyVoxels { .. }), "{e:?}");
        // At the cap: accepted (2^13 x 2^13 x 1 = 2^26).
        assert_eq!(
            VoxelGrid::dimensions(&GridGeometry::square(8192, 8192, 1.0).unwrap(), 1.0, 1).unwrap(),
            (8192, 8192, 1)
        );
    }

    #[test]
    fn castle_has_walls_towers_a_keep_and_a_gate() {
        let n = 170;
        let z = castle_heights(n, 5.0); // 850 m
        let at = |x: f64, y: f64| {
            let col = (x / 5.0) as usize;
            let row = n - 1 - (y / 5.0) as usize;
            z[row * n + col]
        };
        assert!(at(425.0, 425.0) > 25.0); // keep
        assert!(at(297.5, 297.5) > 15.0); // south-west tower
        assert!(at(425.0, 297.5) > 8.0); // south wall
        assert!(at(297.5, 425.0) < 5.0); // west gate
        assert!(at(100.0, 100.0).abs() <= 3.0); // open ground
    }
}
