//! The one triangulation of a height field, used by every mesh made of a grid (the terrain and
//! snow GLB of a season, `snowscape-render`; a DEM as a scene object, `snowscape-mesh`).
//!
//! A lattice keeps every `step`-th column and row of a grid plus the last ones, so that it
//! always spans the whole grid (`step = 1`: every cell). Its vertices are numbered row by row,
//! row 0 the northern one. Each square of four neighbouring vertices is split along its
//! south-west to north-east diagonal into two triangles, `[sw, se, ne]` and `[sw, ne, nw]`,
//! counter-clockwise seen from above (east to the right, north up), so that their front faces
//! point up in any right-handed frame whose up axis points to the sky. A triangle is kept when
//! its three corners are usable: a square with one nodata corner keeps the triangle opposite
//! it, so the surface reaches up to the edge of a hole or of a clipped outline.

use crate::TerrainError;

/// Sampled positions `0, step, 2·step, ..., n - 1` of an axis of `n` cells.
pub fn lattice_axis(n: usize, step: usize) -> Vec<usize> {
    let mut axis: Vec<usize> = (0..n).step_by(step.max(1)).collect();
    if n > 0 && axis.last() != Some(&(n - 1)) {
        axis.push(n - 1);
    }
    axis
}

/// Vertices of the lattice of a `width x height` grid at `step` (the lengths of the two
/// [`lattice_axis`]).
pub fn lattice_vertices(width: usize, height: usize, step: usize) -> usize {
    let step = step.max(1);
    let samples = |n: usize| {
        if n == 0 {
            0
        } else {
            (n - 1) / step + 1 + usize::from(!(n - 1).is_multiple_of(step))
        }
    };
    samples(width) * samples(height)
}

/// The triangles of a lattice of `columns x rows` vertices whose three corners are `usable`
/// (one flag per vertex, row by row), as vertex numbers (module docs: diagonal and
/// orientation). An error when the vertices cannot be numbered with 32 bits or `usable` has
/// the wrong length.
pub fn lattice_triangles(
    usable: &[bool],
    columns: usize,
    rows: usize,
) -> Result<Vec<[u32; 3]>, TerrainError> {
    let n = columns.checked_mul(rows).ok_or(TerrainError::InvalidSize {
        width: columns,
        height: rows,
        reason: "more lattice vertices than addressable",
    })?;
    if n > u32::MAX as usize {
        return Err(TerrainError::InvalidSize {
            width: columns,
            height: rows,
            reason: "a mesh numbers its vertices with 32 bits (decimate the lattice)",
        });
    }
    if usable.len() != n {
        return Err(TerrainError::LengthMismatch {
            width: columns,
            height: rows,
            expected: n,
            actual: usable.len(),
        });
    }
    let mut out = Vec::new();
    for b in 0..rows.saturating_sub(1) {
        for a in 0..columns.saturating_sub(1) {
            let nw = b * columns + a;
            let (ne, sw) = (nw + 1, nw + columns);
            let se = sw + 1;
            for tri in [[sw, se, ne], [sw, ne, nw]] {
                if tri.iter().all(|&v| usable[v]) {
                    out.push(tri.map(|v| v as u32));
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_keeps_the_last_row_and_column() {
        assert_eq!(lattice_axis(10, 3), vec![0, 3, 6, 9]);
        assert_eq!(lattice_axis(11, 3), vec![0, 3, 6, 9, 10]);
        assert_eq!(lattice_axis(1, 4), vec![0]);
        assert_eq!(lattice_axis(0, 4), Vec::<usize>::new());
        assert_eq!(lattice_vertices(11, 10, 3), 5 * 4);
        assert_eq!(lattice_vertices(8192, 8192, 1), 8192 * 8192);
        for (n, step) in [(1, 1), (2, 5), (17, 4), (100, 7), (0, 3)] {
            assert_eq!(
                lattice_vertices(n, 3, step),
                lattice_axis(n, step).len() * lattice_axis(3, step).len()
            );
        }
    }

    #[test]
    fn triangles_face_up_and_reach_the_edge_of_a_hole() {
        // 3 x 3 vertices, the centre one unusable: of the 8 triangles, those touching the
        // centre go (6 of them), the two opposite corners' ones stay.
        let mut usable = vec![true; 9];
        let all = lattice_triangles(&usable, 3, 3).unwrap();
        assert_eq!(all.len(), 8);
        usable[4] = false;
        let holed = lattice_triangles(&usable, 3, 3).unwrap();
        assert_eq!(holed.len(), 2);
        assert!(holed.iter().all(|t| !t.contains(&4)));
        // Counter-clockwise seen from above: x east = column, y north = −row.
        let xy = |v: u32| (f64::from(v % 3), -f64::from(v / 3));
        for t in &all {
            let [a, b, c] = t.map(xy);
            let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
            assert!(cross > 0.0, "{t:?} is clockwise");
        }
    }

    #[test]
    fn bad_sizes_are_errors() {
        assert!(matches!(
            lattice_triangles(&[true; 3], 2, 2),
            Err(TerrainError::LengthMismatch { expected: 4, .. })
        ));
        assert!(lattice_triangles(&[], 1 << 17, 1 << 16).is_err());
        assert!(lattice_triangles(&[], usize::MAX, 2).is_err());
    }
}
