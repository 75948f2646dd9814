//! Defocus: thin-lens blur and the spatially varying Gaussian that applies it.
//!
//! A thin lens with aperture diameter A focused on the plane at depth Z_f images a point at
//! depth Z into a disc (the circle of confusion) of diameter, on the sensor,
//! c = A v |1/Z - 1/Z_f|, where v is the image distance. In pixels v is the focal length
//! f_px of the pinhole model (fx(E) of Eq. 16), so the blur grows with the dioptric
//! distance between the point and the plane in focus:
//!
//! ```text
//! c_px = A_mm * f_px * |1/Z_mm - 1/Z_f_mm|,   sigma_px = c_px / 4
//! ```
//!
//! The disc is replaced by the Gaussian of the same second moment (a uniform disc of
//! radius R has a standard deviation R / 2 along each axis, so sigma = c / 4).
//!
//! Known approximation: the Gaussian is sampled and applied to the area-coverage pixels,
//! whereas a camera integrates the blurred scene over each pixel. The two differ by the
//! aliasing of the sharp edges' high frequencies; on blurred boards (sigma 2 px) the image's
//! centre of point symmetry at a corner lies 0.005-0.009 px RMS (0.015 px at most) from the
//! true corner (tests/render.rs). Blurring a 2 x 2 supersampled coverage image would cut
//! that at four times the cost.
//!
//! The blur is applied only where it changes the image (`Blur`), with the sigma of each
//! pixel from the depths at the tile corners (`BlurField`).

use rayon::prelude::*;

use super::coverage::{Nodes, TILE_PX};
use super::Optics;

/// Largest blur the renderer applies, px; larger blurs are clamped (the image is a uniform
/// grey there anyway).
pub const MAX_SIGMA_PX: f64 = 64.0;
/// Blur below which a pixel is left as rendered, px (a sampled Gaussian narrower than this
/// is a delta).
pub const MIN_SIGMA_PX: f64 = 0.25;
/// Resolution of the blur field: sigma is quantised to multiples of this, px.
pub const SIGMA_STEP_PX: f64 = 0.01;
/// Kernel half-width in sigmas.
const KERNEL_SIGMAS: f64 = 4.0;

/// The defocus blur (Gaussian sigma, px) of a point at camera depth `z_mm` when the plane
/// in focus is at depth `focus_depth_mm`, for a lens of focal length `f_px` (the model's
/// fx(E), px) and aperture diameter `aperture_mm`: `aperture_mm * f_px * |1/z_mm -
/// 1/focus_depth_mm| / 4` (thin lens, module docs).
///
/// Returns infinity for a point at or behind the lens (z_mm <= 0) and NaN for NaN input.
///
/// ```
/// use etl_sim::render::defocus_sigma_px;
/// // 1 mm behind the plane in focus at 95 mm, f = 4850 px, A = 2.5 mm: about 0.33 px.
/// let s = defocus_sigma_px(4850.0, 2.5, 96.0, 95.0);
/// assert!((s - 2.5 * 4850.0 * (1.0 / 95.0 - 1.0 / 96.0) / 4.0).abs() < 1e-12);
/// assert_eq!(defocus_sigma_px(4850.0, 2.5, 95.0, 95.0), 0.0);
/// ```
pub fn defocus_sigma_px(f_px: f64, aperture_mm: f64, z_mm: f64, focus_depth_mm: f64) -> f64 {
    if z_mm <= 0.0 {
        return f64::INFINITY;
    }
    0.25 * aperture_mm * f_px * (1.0 / z_mm - 1.0 / focus_depth_mm).abs()
}

/// Total blur of a point: the defocus and a fixed optical blur `base_sigma_px` in quadrature,
/// clamped to [`MAX_SIGMA_PX`].
pub(crate) fn total_sigma_px(defocus_px: f64, base_sigma_px: f64) -> f64 {
    let s = (defocus_px * defocus_px + base_sigma_px * base_sigma_px).sqrt();
    if s.is_nan() {
        base_sigma_px
    } else {
        s.min(MAX_SIGMA_PX)
    }
}

/// Quantised blur level of sigma (0 = no blur).
#[inline]
pub(crate) fn sigma_level(sigma_px: f64) -> u16 {
    if !(sigma_px >= MIN_SIGMA_PX) {
        return 0;
    }
    // Round half up (the cast truncates; sigma is positive here).
    (sigma_px.min(MAX_SIGMA_PX) * (1.0 / SIGMA_STEP_PX) + 0.5) as u16
}

/// Kernel half-width of a blur, px.
pub(crate) fn kernel_radius(sigma_px: f64) -> usize {
    (KERNEL_SIGMAS * sigma_px).ceil() as usize
}

/// Normalised sampled Gaussians for the levels `lo..=hi` (index level - lo); level 0 is
/// the delta.
struct Kernels {
    lo: u16,
    taps: Vec<Vec<f32>>,
}

impl Kernels {
    fn new(lo: u16, hi: u16) -> Self {
        let taps = (lo..=hi)
            .map(|l| {
                if l == 0 {
                    return vec![1.0];
                }
                let s = l as f64 * SIGMA_STEP_PX;
                let r = kernel_radius(s) as i64;
                let w: Vec<f64> = (-r..=r).map(|k| (-0.5 * (k * k) as f64 / (s * s)).exp()).collect();
                let sum: f64 = w.iter().sum();
                w.iter().map(|x| (x / sum) as f32).collect()
            })
            .collect();
        Kernels { lo, taps }
    }

    /// The kernel of `level`, clamped to the table's range.
    #[inline]
    fn get(&self, level: u16) -> &[f32] {
        let i = usize::from(level.saturating_sub(self.lo)).min(self.taps.len() - 1);
        &self.taps[i]
    }
}

/// The blur level of every pixel of the padded image, from the camera depths of the tile
/// nodes ([`Nodes`]).
///
/// The reciprocal depth of the board point a pixel sees is affine in the undistorted image
/// plane, so over a tile of 8 px it is bilinear in the pixel position to far below the
/// blur's quantisation ([`SIGMA_STEP_PX`]); each pixel's sigma comes from the reciprocal
/// depth interpolated at its centre. Sigma is a convex function of the reciprocal depth
/// and the interpolation a convex combination of the nodes', so no pixel of a tile blurs
/// more than the largest of its four nodes: that bounds the kernel radius per tile, which
/// the blur uses to find the pixels whose neighbourhood is flat. A tile with a node off
/// the board plane gets the optics' fixed blur.
pub(crate) struct BlurField {
    xs: Vec<usize>,
    ys: Vec<usize>,
    /// Reciprocal camera depth of each node, 1/mm (NaN off the board plane).
    inv_depth: Vec<f64>,
    /// Largest level of each tile (row-major tiles).
    tile_level: Vec<u16>,
    /// Kernel radius of `tile_level`, px.
    tile_radius: Vec<u16>,
    /// The level everywhere when it does not depend on depth.
    uniform: Option<u16>,
    /// Fixed blur (base sigma) squared, px^2.
    base2: f64,
    /// Defocus sigma per unit of reciprocal depth off the plane in focus, px mm.
    defocus_per_inv_mm: f64,
    /// 1 / the depth in focus, 1/mm.
    inv_focus_depth: f64,
    /// 1 / the width of each tile column, 1 / the height of each tile row.
    inv_width: Vec<f64>,
    inv_height: Vec<f64>,
    /// The level of the fixed blur alone, the least of any pixel.
    min_level: u16,
}

/// 1 / the gaps of `lattice`.
fn inverse_gaps(lattice: &[usize]) -> Vec<f64> {
    lattice.windows(2).map(|g| 1.0 / (g[1] - g[0]) as f64).collect()
}

impl BlurField {
    /// The field of `optics` for a lens of focal length `f_px` over the tiles of `nodes`.
    pub fn new(nodes: &Nodes, optics: &Optics, f_px: f64) -> Self {
        let fixed = sigma_level(optics.sigma_px(f_px, f64::NAN));
        let has_defocus = optics.focus_depth_mm.is_some() && optics.aperture_mm > 0.0;
        let (ntx, nty) = nodes.tiles();
        let inv_depth: Vec<f64> = nodes.points.iter().map(|p| p.map_or(f64::NAN, |p| p.inv_depth)).collect();
        let node_sigma: Vec<f64> =
            inv_depth.iter().map(|&w| if w > 0.0 { optics.sigma_px(f_px, 1.0 / w) } else { f64::NAN }).collect();
        let tile_level: Vec<u16> = (0..nty)
            .flat_map(|ty| (0..ntx).map(move |tx| (tx, ty)))
            .map(|(tx, ty)| {
                if !has_defocus {
                    return fixed;
                }
                let n = nodes.xs.len();
                let (a, b) = (ty * n + tx, (ty + 1) * n + tx);
                let s = [a, a + 1, b, b + 1].map(|i| node_sigma[i]);
                if s.iter().any(|v| v.is_nan()) {
                    return fixed;
                }
                // One quantisation step up for rounding.
                let max = s.iter().fold(0.0f64, |m, &v| m.max(v)).min(MAX_SIGMA_PX);
                sigma_level(max).saturating_add(1).max(fixed)
            })
            .collect();
        let tile_radius = radii(&tile_level);
        BlurField {
            tile_radius,
            xs: nodes.xs.clone(),
            ys: nodes.ys.clone(),
            inv_depth,
            tile_level,
            uniform: (!has_defocus).then_some(fixed),
            base2: optics.base_sigma_px * optics.base_sigma_px,
            defocus_per_inv_mm: 0.25 * optics.aperture_mm * f_px,
            inv_focus_depth: optics.focus_depth_mm.map_or(0.0, |z| 1.0 / z),
            inv_width: inverse_gaps(&nodes.xs),
            inv_height: inverse_gaps(&nodes.ys),
            min_level: sigma_level(optics.base_sigma_px),
        }
    }

    /// The same level everywhere on a `pw` x `ph` image (for tests of the blur itself).
    #[cfg(test)]
    fn constant(level: u16, (pw, ph): (usize, usize)) -> Self {
        let lattice = |n: usize| {
            let mut v: Vec<usize> = (0..n).step_by(TILE_PX).collect();
            v.push(n);
            v
        };
        let (xs, ys) = (lattice(pw), lattice(ph));
        let tiles = (xs.len() - 1) * (ys.len() - 1);
        BlurField {
            inv_width: inverse_gaps(&xs),
            inv_height: inverse_gaps(&ys),
            tile_radius: vec![kernel_radius(level as f64 * SIGMA_STEP_PX) as u16; tiles],
            inv_depth: vec![f64::NAN; xs.len() * ys.len()],
            xs,
            ys,
            tile_level: vec![level; tiles],
            uniform: Some(level),
            base2: 0.0,
            defocus_per_inv_mm: 0.0,
            inv_focus_depth: 0.0,
            min_level: level,
        }
    }

    #[inline]
    fn tile(&self, px: usize, py: usize) -> (usize, usize) {
        let (nx, ny) = (self.xs.len() - 1, self.ys.len() - 1);
        ((px / TILE_PX).min(nx - 1), (py / TILE_PX).min(ny - 1))
    }

    /// An upper bound of the kernel radius of every pixel in the tile of padded pixel
    /// (px, py), px.
    #[inline]
    pub fn radius_bound(&self, px: usize, py: usize) -> usize {
        let (tx, ty) = self.tile(px, py);
        usize::from(self.tile_radius[ty * (self.xs.len() - 1) + tx])
    }

    /// The largest level anywhere.
    pub fn max_level(&self) -> u16 {
        self.tile_level.iter().copied().max().unwrap_or(0)
    }

    /// The smallest level any pixel can have (that of the fixed blur alone).
    pub fn min_level(&self) -> u16 {
        self.min_level
    }

    /// Blur level of padded pixel (px, py).
    #[cfg(test)]
    pub fn level(&self, px: usize, py: usize) -> u16 {
        let c0 = px / TILE_PX * TILE_PX;
        let mut levels = [0; TILE_PX];
        self.tile_row_levels(c0, py, &mut levels);
        levels[px - c0]
    }

    /// Blur levels of the padded pixels (c0 + i, py), i < [`TILE_PX`], one row of a tile
    /// (`c0` a multiple of [`TILE_PX`]). A row at a time so that the pixels' levels are
    /// independent computations (pipelined) rather than a latency chain between
    /// convolutions.
    #[inline]
    pub fn tile_row_levels(&self, c0: usize, py: usize, out: &mut [u16; TILE_PX]) {
        if let Some(l) = self.uniform {
            *out = [l; TILE_PX];
            return;
        }
        let (tx, ty) = self.tile(c0, py);
        let tile_level = self.tile_level[ty * (self.xs.len() - 1) + tx];
        let n = self.xs.len();
        let (a, b) = (ty * n + tx, (ty + 1) * n + tx);
        let (w00, w10, w01, w11) = (self.inv_depth[a], self.inv_depth[a + 1], self.inv_depth[b], self.inv_depth[b + 1]);
        // Bilinear: along y on the tile's left and right sides, then along x.
        let fy = (py as f64 + 0.5 - self.ys[ty] as f64) * self.inv_height[ty];
        let (left, right) = (w00 + fy * (w01 - w00), w10 + fy * (w11 - w10));
        if !(left > 0.0 && right > 0.0) {
            // A node off the board plane: the fixed blur.
            *out = [tile_level; TILE_PX];
            return;
        }
        // Optics::sigma_px in the reciprocal depth, without its divisions.
        let x0 = self.xs[tx] as f64;
        let mut sigma = [0.0f64; TILE_PX];
        for (i, s) in sigma.iter_mut().enumerate() {
            let fx = ((c0 + i) as f64 + 0.5 - x0) * self.inv_width[tx];
            let w = left + fx * (right - left);
            *s = self.defocus_per_inv_mm * (w - self.inv_focus_depth).abs();
        }
        if self.base2 > 0.0 {
            for s in sigma.iter_mut() {
                *s = (*s * *s + self.base2).sqrt();
            }
        }
        for (o, s) in out.iter_mut().zip(sigma) {
            *o = sigma_level(s).min(tile_level);
        }
    }
}

/// The kernel `k` applied to `data[0], data[stride], data[2 stride], ...`. Four partial
/// sums: a single one would wait on the adder's latency at every tap.
#[inline]
fn dot(k: &[f32], data: &[f32], stride: usize) -> f32 {
    let mut acc = [0.0f32; 4];
    let quads = k.chunks_exact(4);
    let rest = quads.remainder();
    let mut i = 0;
    for q in quads {
        acc[0] += q[0] * data[i];
        acc[1] += q[1] * data[i + stride];
        acc[2] += q[2] * data[i + 2 * stride];
        acc[3] += q[3] * data[i + 3 * stride];
        i += 4 * stride;
    }
    for &kv in rest {
        acc[0] += kv * data[i];
        i += stride;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// Kernel radius of each level.
fn radii(levels: &[u16]) -> Vec<u16> {
    levels.iter().map(|&l| kernel_radius(l as f64 * SIGMA_STEP_PX) as u16).collect()
}

/// The spatially varying separable Gaussian of a padded image, done where it changes
/// anything.
///
/// A normalised kernel leaves a flat neighbourhood flat, and most of a checkerboard image
/// is flat (inside the squares): a pixel whose window of the tile's largest kernel radius
/// ([`BlurField::radius_bound`]) holds a single value keeps it, and only the others pay for
/// a convolution with their own kernel. The horizontal pass runs on construction, in place,
/// over all padded rows (central columns only) and finds the flat windows by prefix counts
/// of the value changes along the row; the vertical pass, [`Blur::row`], one output row at
/// a time, by or-ing the rows' change masks (a bit per column, a byte per tile) over the
/// window. Skipping is exact up to the f32 rounding of the kernel's sum (1e-7 relative).
pub(crate) struct Blur<'a> {
    field: &'a BlurField,
    kernels: Kernels,
    /// Padded width, border, output width.
    pw: usize,
    pad: usize,
    w: usize,
    /// The padded image (`pw` x padded height), its central columns blurred horizontally.
    image: Vec<f32>,
    /// Tiles per padded row (bytes per row of `vdiff`).
    mask_bytes: usize,
    /// Bit `c % 8` of byte `py * mask_bytes + c / 8`: padded column c of `image` row py
    /// differs from row py - 1.
    vdiff: Vec<u8>,
    /// No pixel is blurred.
    identity: bool,
}

impl<'a> Blur<'a> {
    /// The horizontal pass over `image` (`pw` x `ph` padded by `pad`, row-major) with the
    /// blur of `field`, for an output of `w` columns. Precondition: `pad` is at least every
    /// tile's radius bound (the renderer pads by it).
    pub fn new(mut image: Vec<f32>, field: &'a BlurField, (pw, ph): (usize, usize), pad: usize, w: usize) -> Self {
        let (lo, hi) = (field.min_level(), field.max_level());
        let mask_bytes = pw.div_ceil(TILE_PX);
        if hi == 0 {
            let kernels = Kernels::new(0, 0);
            return Blur { field, kernels, pw, pad, w, image, mask_bytes, vdiff: Vec::new(), identity: true };
        }
        let kernels = Kernels::new(lo.min(hi), hi);
        image.par_chunks_mut(pw).enumerate().for_each_init(
            || (Vec::new(), Vec::new()),
            |(changes, sharp): &mut (Vec<u32>, Vec<f32>), (py, row)| {
                // The sharp row, read while `row` is overwritten.
                sharp.clear();
                sharp.extend_from_slice(row);
                // changes[i]: value changes between neighbours in sharp[..=i].
                changes.clear();
                let mut n = 0u32;
                changes.push(0);
                for pair in sharp.windows(2) {
                    n += u32::from(pair[0] != pair[1]);
                    changes.push(n);
                }
                let mut levels = [0u16; TILE_PX];
                for c0 in (pad / TILE_PX * TILE_PX..pad + w).step_by(TILE_PX) {
                    let r = field.radius_bound(c0, py);
                    let cols = c0.max(pad)..(c0 + TILE_PX).min(pad + w);
                    let flat = |c: usize| changes[c + r] == changes[c - r];
                    if cols.clone().all(flat) {
                        continue;
                    }
                    field.tile_row_levels(c0, py, &mut levels);
                    for c in cols.filter(|&c| !flat(c)) {
                        let k = kernels.get(levels[c - c0]);
                        row[c] = dot(k, &sharp[c - k.len() / 2..], 1);
                    }
                }
            },
        );
        let mut vdiff = vec![0u8; mask_bytes * ph];
        vdiff.par_chunks_mut(mask_bytes).enumerate().skip(1).for_each(|(py, bits)| {
            let (above, row) = (&image[(py - 1) * pw + pad..py * pw - pad], &image[py * pw + pad..(py + 1) * pw - pad]);
            for (x, (a, b)) in above.iter().zip(row).enumerate() {
                let c = x + pad;
                bits[c / TILE_PX] |= u8::from(a != b) << (c % TILE_PX);
            }
        });
        Blur { field, kernels, pw, pad, w, image, mask_bytes, vdiff, identity: false }
    }

    /// Output row `y` (padded row `y + pad`): the vertical pass over the horizontally
    /// blurred rows, into `out` (`w` long).
    pub fn row(&self, y: usize, out: &mut [f32]) {
        let (pad, pw) = (self.pad, self.pw);
        let py = y + pad;
        let centre = &self.image[py * pw + pad..py * pw + pad + self.w];
        if self.identity {
            out.copy_from_slice(centre);
            return;
        }
        let mut levels = [0u16; TILE_PX];
        for c0 in (pad / TILE_PX * TILE_PX..pad + self.w).step_by(TILE_PX) {
            let r = self.field.radius_bound(c0, py);
            let t = c0 / TILE_PX;
            // Changes between rows py - r .. py + r, i.e. of rows py - r + 1 ..= py + r.
            let window = &self.vdiff[(py + 1 - r) * self.mask_bytes..(py + r + 1) * self.mask_bytes];
            let mask = window.iter().skip(t).step_by(self.mask_bytes).fold(0u8, |m, b| m | b);
            let (x0, x1) = (c0.max(pad) - pad, (c0 + TILE_PX).min(pad + self.w) - pad);
            out[x0..x1].copy_from_slice(&centre[x0..x1]);
            if mask == 0 {
                continue;
            }
            self.field.tile_row_levels(c0, py, &mut levels);
            for x in (x0..x1).filter(|x| mask & (1 << ((x + pad) % TILE_PX)) != 0) {
                let c = x + pad;
                let k = self.kernels.get(levels[c - c0]);
                out[x] = dot(k, &self.image[(py - k.len() / 2) * pw + c..], pw);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_lens_blur() {
        assert_eq!(defocus_sigma_px(5000.0, 2.0, 100.0, 100.0), 0.0);
        // Symmetric in dioptres, not in millimetres.
        let near = defocus_sigma_px(5000.0, 2.0, 50.0, 100.0);
        assert!((near - 0.25 * 2.0 * 5000.0 * 0.01).abs() < 1e-12);
        assert!(defocus_sigma_px(5000.0, 2.0, -1.0, 100.0).is_infinite());
        assert_eq!(total_sigma_px(3.0, 4.0), 5.0);
        assert_eq!(total_sigma_px(1e9, 0.0), MAX_SIGMA_PX);
        assert_eq!(sigma_level(0.1), 0);
        assert_eq!(sigma_level(1.234), 123);
    }

    #[test]
    fn uniform_blur_keeps_the_mean_and_spreads_a_point() {
        // The window holds the point's blur to 4.5 sigma on every side.
        let (w, h, pad) = (21usize, 21usize, 9usize);
        let (pw, ph) = (w + 2 * pad, h + 2 * pad);
        let mut src = vec![0.0f32; pw * ph];
        src[(pad + 10) * pw + pad + 10] = 1.0;
        let field = BlurField::constant(sigma_level(2.0), (pw, ph));
        let blur = Blur::new(src, &field, (pw, ph), pad, w);
        let mut dst = vec![0.0f32; w * h];
        for (y, row) in dst.chunks_mut(w).enumerate() {
            blur.row(y, row);
        }
        let sum: f32 = dst.iter().sum();
        assert!((sum - 1.0).abs() < 1e-4, "{sum}");
        // Second moment along x is sigma^2 = 4 (a sampled, truncated Gaussian: to 0.05 %).
        let m2: f32 = dst.iter().enumerate().map(|(i, v)| v * ((i % w) as f32 - 10.0).powi(2)).sum();
        assert!((m2 - 4.0).abs() < 2e-3, "{m2}");
        // The point's own row and column are blurred, the far corner is left alone.
        assert!(dst[10 * w + 10] < 0.05 && dst[10 * w + 10] > 0.03, "{}", dst[10 * w + 10]);
        assert_eq!(dst[0], 0.0);
    }

    /// Skipping flat windows gives the full convolution, on the paper's view with the
    /// varying defocus (sigma 0 to 4 px) and some isolated bright pixels.
    #[test]
    fn skipping_flat_windows_changes_nothing() {
        use super::super::board::{BoardLayout, Levels};
        use super::super::coverage::render_sharp;
        use super::super::mapping::PixelToBoard;
        use etl_core::model::CameraModel;
        let truth = CameraModel::paper_rig();
        let (e, z) = (150.0, 25.0);
        let map = PixelToBoard::new(&truth, e, z).unwrap();
        let layout = BoardLayout::new([14, 12], 1.5, 1.5, Levels { dark: 40.0, light: 210.0, background: 120.0 });
        let (w, h, pad) = (700usize, 500usize, 24usize);
        let (pw, ph) = (w + 2 * pad, h + 2 * pad);
        let nodes = Nodes::new(&map, (pw, ph), pad);
        let (fx, fy) = truth.focal_lengths(e);
        let field = BlurField::new(&nodes, &Optics::paper_focus(&truth, e, 2.5), 0.5 * (fx + fy));
        assert!(field.max_level() > 150 && kernel_radius(field.max_level() as f64 * SIGMA_STEP_PX) <= pad);
        // The interpolated level is that of the depth the pixel's centre sees (to one
        // quantisation step, where the rounding falls the other way).
        let optics = Optics::paper_focus(&truth, e, 2.5);
        for (px, py) in [(0usize, 0usize), (pw - 1, ph - 1), (301, 17), (5, 400), (333, 222)] {
            let [u, v] = map.undistort_exact(px as f64 - pad as f64, py as f64 - pad as f64).unwrap();
            let w = map.board_of_undistorted(u, v).unwrap().inv_depth;
            let want = sigma_level(optics.sigma_px(0.5 * (fx + fy), 1.0 / w));
            assert!(field.level(px, py).abs_diff(want) <= 1, "{} {want}", field.level(px, py));
        }
        let mut src = render_sharp(&map, &layout, &nodes, (pw, ph), pad);
        for k in 0..40 {
            src[(37 * k + 11) % ph * pw + (53 * k + 7) % pw] = 255.0;
        }
        let blur = Blur::new(src.clone(), &field, (pw, ph), pad, w);
        // Reference: every pixel convolved with its own kernel.
        let kernels = Kernels::new(0, field.max_level());
        let mut tmp = vec![0.0f32; w * ph];
        for py in 0..ph {
            for x in 0..w {
                let k = kernels.get(field.level(x + pad, py));
                let s = py * pw + x + pad - k.len() / 2;
                tmp[py * w + x] = k.iter().zip(&src[s..s + k.len()]).map(|(a, b)| a * b).sum();
            }
        }
        let (mut worst, mut flat) = (0.0f32, 0usize);
        let mut row = vec![0.0f32; w];
        for y in 0..h {
            blur.row(y, &mut row);
            for (x, got) in row.iter().enumerate() {
                let k = kernels.get(field.level(x + pad, y + pad));
                let s = y + pad - k.len() / 2;
                let want: f32 = k.iter().enumerate().map(|(t, a)| a * tmp[(s + t) * w + x]).sum();
                worst = worst.max((got - want).abs());
                flat += usize::from(*got == src[(y + pad) * pw + x + pad]);
            }
        }
        assert!(worst < 1e-3, "{worst} grey levels");
        assert!(flat > w * h / 2, "{flat}");
    }
}
