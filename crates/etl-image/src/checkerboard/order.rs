//! The stable order of the corners.
//!
//! Corner (i, j) of the pattern (`cols` x `rows` inner corners) is returned at index
//! `j * cols + i`; the board square between corners (0,0), (1,0), (0,1) and (1,1) is dark,
//! and `(p(1,0) - p(0,0)) x (p(0,1) - p(0,0)) > 0` in image coordinates (u right, v down):
//! the board's x axis along i, y along j, seen from its printed side. Of the rotations of
//! the found grid that give `cols` x `rows`, those making square (0,0) dark are kept; when
//! two remain (the colouring is symmetric under the rotation: `cols + rows` even, or a square
//! board) the one whose corner 0 is nearest the image's top-left pixel is chosen. If none
//! makes square (0,0) dark (a board printed with the other colouring) the choice is by
//! position among all.

use super::grid::Grid;

/// A rotation of the grid's index space: new index (i, j) -> old index.
#[derive(Debug, Clone, Copy)]
enum Rotation {
    R0,
    R90,
    R180,
    R270,
}

impl Rotation {
    /// Old (i, j) of new (i, j) for an old grid of `nc` x `nr`.
    fn old(self, i: usize, j: usize, nc: usize, nr: usize) -> (usize, usize) {
        match self {
            Rotation::R0 => (i, j),
            Rotation::R180 => (nc - 1 - i, nr - 1 - j),
            Rotation::R90 => (nc - 1 - j, i),
            Rotation::R270 => (j, nr - 1 - i),
        }
    }
    /// New dimensions.
    fn dims(self, nc: usize, nr: usize) -> (usize, usize) {
        match self {
            Rotation::R0 | Rotation::R180 => (nc, nr),
            Rotation::R90 | Rotation::R270 => (nr, nc),
        }
    }
}

/// Reorders a grid to `cols` x `rows` in the documented order; `None` if its size differs.
pub(crate) fn order(g: &Grid, cols: usize, rows: usize) -> Option<Vec<[f32; 2]>> {
    let rots = [Rotation::R0, Rotation::R90, Rotation::R180, Rotation::R270];
    let fits: Vec<Rotation> = rots.into_iter().filter(|r| r.dims(g.nc, g.nr) == (cols, rows)).collect();
    if fits.is_empty() {
        return None;
    }
    // Old cell containing new cell (0,0): the one at the smallest old indices of its corners.
    let dark = |r: Rotation| {
        let corners = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(i, j)| r.old(i, j, g.nc, g.nr));
        let ci = corners.iter().map(|c| c.0).min().unwrap_or(0);
        let cj = corners.iter().map(|c| c.1).min().unwrap_or(0);
        ((ci + cj) % 2 == 0) == g.cell00_dark
    };
    let dark_fits: Vec<Rotation> = fits.iter().copied().filter(|&r| dark(r)).collect();
    let pool = if dark_fits.is_empty() { fits } else { dark_fits };
    let first = |r: Rotation| {
        let (oi, oj) = r.old(0, 0, g.nc, g.nr);
        let p = g.pts[oj * g.nc + oi];
        p[0] * p[0] + p[1] * p[1]
    };
    let best = pool.into_iter().min_by(|&a, &b| first(a).total_cmp(&first(b)))?;
    let mut out = Vec::with_capacity(cols * rows);
    for j in 0..rows {
        for i in 0..cols {
            let (oi, oj) = best.old(i, j, g.nc, g.nr);
            out.push(g.pts[oj * g.nc + oi]);
        }
    }
    Some(out)
}
