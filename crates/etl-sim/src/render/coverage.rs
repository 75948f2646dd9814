//! Stages 1-2 of [`super::render`]: the sharp image, each pixel the exact mean grey level of
//! the board over its footprint.
//!
//! Most pixels of a checkerboard image see a single square: their footprint lies wholly
//! inside one region of the board, their mean is that region's grey level, and mapping
//! their corners or clipping polygons would be wasted. So the padded image is cut into
//! tiles of `TILE_PX` x `TILE_PX` pixels and only the tiles' corners (the nodes,
//! `Nodes`) are first mapped to the board, exactly. A tile whose nodes' bounding box on
//! the board, widened by the size of one pixel there, lies inside one square, or in the
//! background, or in the white margin (`BoardLayout::level_over`) is filled with that
//! grey level. The widening covers the bending of the tile's edges on the
//! board: the pixel -> board map is a homography (straight lines stay straight) composed
//! with the undistortion, whose curvature moves the middle of an 8 px edge by about
//! 1e-4 px from the chord on the paper's lens, four orders of magnitude inside the margin.
//! The classification is therefore conservative, and the image is the same as when every
//! pixel corner is mapped (a test compares the two).
//!
//! The other tiles (near an edge of a square, or where the board plane is not seen) are
//! done pixel by pixel as before the tiling: every pixel corner is mapped, a pixel whose
//! four corners lie in one region gets its level, the others the exact polygon mean of
//! `BoardLayout::mean_over`.

use rayon::prelude::*;

use super::board::BoardLayout;
use super::mapping::{BoardPoint, PixelToBoard};

/// Side of a tile, px. Eight pixels keep the tiles along the edges of the squares few
/// (a square is tens of pixels wide) while the nodes stay cheap (1/64 of the pixels); the
/// blur's masks ([`super::defocus`]) hold one tile's columns in a byte.
pub(crate) const TILE_PX: usize = 8;

/// The tile lattice of a padded image and the exact board points of its nodes.
#[derive(Debug, Clone)]
pub(crate) struct Nodes {
    /// Padded pixel-corner columns of the nodes: 0, 8, 16, ..., the image width (the last
    /// tile may be narrower).
    pub xs: Vec<usize>,
    /// Padded pixel-corner rows of the nodes, likewise.
    pub ys: Vec<usize>,
    /// Board point of node (i, j) at `j * xs.len() + i`; `None` where the pixel's ray
    /// misses the board plane (or the distortion folds there).
    pub points: Vec<Option<BoardPoint>>,
}

/// 0, [`TILE_PX`], 2 [`TILE_PX`], ..., `n`.
fn lattice(n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).step_by(TILE_PX).collect();
    v.push(n);
    v
}

impl Nodes {
    /// Maps the nodes of a `pw` x `ph` image padded by `pad` px on every side (padded
    /// pixel-corner column c lies at pixel coordinate c - pad - 0.5).
    pub fn new(map: &PixelToBoard, (pw, ph): (usize, usize), pad: usize) -> Self {
        let (xs, ys) = (lattice(pw), lattice(ph));
        let mut points = vec![None; xs.len() * ys.len()];
        let off = pad as f64 + 0.5;
        points.par_chunks_mut(xs.len()).zip(ys.par_iter()).for_each(|(row, &y)| {
            map.map_positions(y as f64 - off, xs.iter().map(|&x| x as f64 - off), row);
        });
        Nodes { xs, ys, points }
    }

    /// Tiles along x and y.
    pub fn tiles(&self) -> (usize, usize) {
        (self.xs.len() - 1, self.ys.len() - 1)
    }

    /// The four nodes of tile (tx, ty): top left, top right, bottom right, bottom left.
    #[inline]
    pub fn tile_corners(&self, tx: usize, ty: usize) -> [Option<BoardPoint>; 4] {
        let n = self.xs.len();
        let (a, b) = (ty * n + tx, (ty + 1) * n + tx);
        [self.points[a], self.points[a + 1], self.points[b + 1], self.points[b]]
    }
}

/// The level of tile (tx, ty) when its footprint lies inside one region of the board.
fn uniform_level(layout: &BoardLayout, nodes: &Nodes, tx: usize, ty: usize) -> Option<f32> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in nodes.tile_corners(tx, ty) {
        let p = p?;
        lo = [lo[0].min(p.x_mm), lo[1].min(p.y_mm)];
        hi = [hi[0].max(p.x_mm), hi[1].max(p.y_mm)];
    }
    let side_px = (nodes.xs[tx + 1] - nodes.xs[tx]).min(nodes.ys[ty + 1] - nodes.ys[ty]) as f64;
    // An upper bound of one pixel's size on the board.
    let pixel_mm = (hi[0] - lo[0]).max(hi[1] - lo[1]) / side_px;
    if !pixel_mm.is_finite() {
        return None;
    }
    layout.level_over([lo[0] - pixel_mm, lo[1] - pixel_mm], [hi[0] + pixel_mm, hi[1] + pixel_mm]).map(|l| l as f32)
}

/// The sharp image of the padded `pw` x `ph` image (border `pad`): the mean grey level of
/// the board over every pixel's footprint, row-major.
pub(crate) fn render_sharp(
    map: &PixelToBoard,
    layout: &BoardLayout,
    nodes: &Nodes,
    (pw, ph): (usize, usize),
    pad: usize,
) -> Vec<f32> {
    let mut sharp = vec![0.0f32; pw * ph];
    // The node rows are multiples of TILE_PX, so bands of TILE_PX rows are the tile rows.
    sharp.par_chunks_mut(TILE_PX * pw).enumerate().for_each_init(Vec::new, |scratch, (ty, band)| {
        let (ntx, _) = nodes.tiles();
        let nrows = band.len() / pw;
        let mut tx = 0;
        while tx < ntx {
            let x0 = nodes.xs[tx];
            if let Some(level) = uniform_level(layout, nodes, tx, ty) {
                let x1 = nodes.xs[tx + 1];
                for row in band.chunks_mut(pw) {
                    row[x0..x1].fill(level);
                }
                tx += 1;
                continue;
            }
            // A run of tiles done pixel by pixel: one mapping of each pixel-corner row.
            let start = tx;
            while tx < ntx && (tx == start || uniform_level(layout, nodes, tx, ty).is_none()) {
                tx += 1;
            }
            let cols = x0..nodes.xs[tx];
            exact_pixels(map, layout, (cols, nodes.ys[ty], nrows), (pw, pad), band, scratch);
        }
    });
    sharp
}

/// Pixel-corner board point and its region.
type Corner = Option<(BoardPoint, (i32, i32))>;

/// Renders padded columns `cols` of the `nrows` rows from padded row `y0` into `band` (those
/// rows, `pw` wide) pixel by pixel; `scratch` holds the pixel-corner grid.
fn exact_pixels(
    map: &PixelToBoard,
    layout: &BoardLayout,
    (cols, y0, nrows): (std::ops::Range<usize>, usize, usize),
    (pw, pad): (usize, usize),
    band: &mut [f32],
    scratch: &mut Vec<Corner>,
) {
    let n = cols.len() + 1;
    let mut points = vec![None; n];
    scratch.clear();
    let x0 = cols.start as f64 - pad as f64 - 0.5;
    for r in 0..=nrows {
        map.map_row(x0, (y0 + r) as f64 - pad as f64 - 0.5, &mut points);
        scratch.extend(points.iter().map(|p| p.map(|p| (p, layout.region(p.x_mm, p.y_mm)))));
    }
    let background = layout.level_at(f64::INFINITY, f64::INFINITY) as f32;
    for (r, row) in band.chunks_mut(pw).take(nrows).enumerate() {
        let (top, bottom) = (&scratch[r * n..(r + 1) * n], &scratch[(r + 1) * n..(r + 2) * n]);
        for (k, out) in row[cols.clone()].iter_mut().enumerate() {
            let (Some(a), Some(b), Some(c), Some(d)) = (top[k], top[k + 1], bottom[k + 1], bottom[k]) else {
                *out = background;
                continue;
            };
            *out = if a.1 == b.1 && a.1 == c.1 && a.1 == d.1 {
                layout.level(a.1) as f32
            } else {
                let q = [a.0, b.0, c.0, d.0].map(|p| [p.x_mm, p.y_mm]);
                layout.mean_over(&q) as f32
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::board::Levels;
    use super::*;
    use etl_core::model::CameraModel;

    /// The tiled image equals the one with every pixel corner mapped (the pre-tiling
    /// renderer), on the paper's view and on a steep, rotated view of a small board, and
    /// on ChArUco boards (tiles inside a marker's cell are uniform too).
    #[test]
    fn tiles_change_nothing() {
        let levels = Levels { dark: 40.0, light: 210.0, background: 120.0 };
        let paper = CameraModel::paper_rig();
        let om = [0.5f64, -0.4, 0.3];
        let steep = CameraModel { rotation_rodrigues: om, translation_mm: [-8.0, -4.0, 60.0], ..paper };
        let checker = |size, square| BoardLayout::new(size, square, square, levels);
        let charuco = etl_formats::Board::charuco([15, 13], 1.5, 1.1, "DICT_5X5_100").unwrap();
        for (model, e, z, layout) in [
            (paper, 150.0, 22.0, checker([14, 12], 1.5)),
            (steep, 0.0, 0.0, checker([9, 6], 2.0)),
            (paper, 260.0, 40.0, checker([14, 12], 1.5)),
            (paper, 150.0, 22.0, BoardLayout::of(&charuco, 1.5, levels)),
            (paper, 225.0, 2.0, BoardLayout::of(&charuco, 1.5, levels)),
        ] {
            let map = PixelToBoard::new(&model, e, z).unwrap();
            let (pw, ph, pad) = (1936 / 2 + 13, 1458 / 2 + 5, 6);
            let nodes = Nodes::new(&map, (pw, ph), pad);
            let tiled = render_sharp(&map, &layout, &nodes, (pw, ph), pad);
            let mut all = vec![0.0f32; pw * ph];
            let mut scratch = Vec::new();
            for (ty, band) in all.chunks_mut(TILE_PX * pw).enumerate() {
                let nrows = band.len() / pw;
                exact_pixels(&map, &layout, (0..pw, ty * TILE_PX, nrows), (pw, pad), band, &mut scratch);
            }
            let (mut uniform, mut worst) = (0usize, 0.0f32);
            for (t, a) in tiled.iter().zip(&all) {
                worst = worst.max((t - a).abs());
                uniform += usize::from(*a == 40.0 || *a == 210.0 || *a == 120.0);
            }
            // Continued Newton from other starting points: the same corners to 1e-10 px.
            assert!(worst < 1e-4, "{worst}");
            // The image has both kinds of pixels.
            assert!(uniform > pw * ph / 2 && uniform < pw * ph, "{uniform} of {}", pw * ph);
        }
    }
}
