//! The synthetic camera: renders a board (a checkerboard or a ChArUco board) seen through a
//! [`CameraModel`] at a lens current, with exact anti-aliasing, the model's distortion,
//! thin-lens defocus, shading, photon and read noise, and returns the true pixel of every
//! corner with its id.
//!
//! Pipeline of [`render`]:
//! 1. Geometry ([`mapping`]): pixel corners (x +- 0.5, y +- 0.5) are mapped back to the
//!    board plane through the model's inverse (undistortion of Eq. 17, A(E)^-1, the plane's
//!    homography), exactly (Newton to 1e-10 px).
//! 2. Coverage ([`coverage`], [`board`]): a pixel's grey level is the exact mean of the
//!    printed board over its footprint, the quadrilateral through its four mapped corners
//!    (polygon clipping against the squares and the markers' cells). The footprint's edges are straight on the
//!    board while the true images of the pixel's edges bend with the distortion and
//!    perspective by far less than 1e-4 px over one pixel; that is the only approximation
//!    of the coverage. Tiles of 8 x 8 pixels that provably lie inside one square (or cell) are
//!    filled without mapping their pixels; only the tiles along the squares' edges are
//!    done pixel by pixel.
//! 3. Defocus ([`defocus`]): each pixel is blurred by the Gaussian of the thin-lens circle
//!    of confusion of the board point it sees ([`defocus_sigma_px`]), combined in
//!    quadrature with a fixed optical blur; a separable Gaussian whose sigma varies per
//!    pixel (the board is planar, so the blur varies smoothly; it is interpolated from the
//!    tile corners). Pixels whose neighbourhood is flat are left as they are (the blur
//!    would not change them), so the convolutions are paid only near the edges. The image
//!    is rendered with a border of the largest kernel radius so that the blur near the
//!    edges sees the scene beyond.
//! 4. Photometry ([`Photometry`]): vignetting and illumination gradient, Poisson photon
//!    noise, Gaussian read noise (SplitMix64 seeded per row: the result does not depend on
//!    the thread count) and quantisation to 8 or 16 bits; fused with the vertical blur,
//!    row by row.
//!
//! Conventions: pixel (x, y) has its centre at pixel coordinates (x, y), those of
//! [`CameraModel::project`]. The board layout (colours, margin) is in [`board`].

use etl_core::model::CameraModel;
use rayon::prelude::*;

use crate::rig::{focus_depth_mm, focus_law_depth_mm, PAPER_BOARD};
use etl_formats::{Error, Result};

pub mod board;
pub mod coverage;
pub mod defocus;
pub mod image;
pub mod mapping;
pub mod photometry;
pub mod request;

pub use defocus::{defocus_sigma_px, MAX_SIGMA_PX};
pub use etl_formats::board::{Board, Checkerboard};
pub use image::{BitDepth, Image};
pub use photometry::Photometry;
pub use request::PaperRender;

use board::{BoardLayout, Levels};
use coverage::Nodes;
use defocus::{Blur, BlurField};
use mapping::PixelToBoard;

/// Largest image side accepted, px.
pub const MAX_IMAGE_SIDE_PX: u32 = 1 << 15;

/// The scene: a board in the plane Z_W = `board_z_mm` of the model's world frame.
///
/// The paper rig: the stage moves the board along Z_W ([`Scene::paper_view`]). Lens-off or
/// tilted views: a `CameraModel` whose rotation and translation put the board frame where
/// wanted, and `board_z_mm = 0`. Board point (X, Y) of the board's frame
/// ([`Board::corner_mm`]: a checkerboard's inner corner (i, j) at (i s, j s), a ChArUco
/// board's frame OpenCV's) is at world (X, Y, board_z_mm); around the printed pattern lies
/// a white margin of `margin_mm`, then the background (a flat surface in the same plane).
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The camera (pose and intrinsics as functions of the current).
    pub model: CameraModel,
    /// Compensated lens current, mA.
    pub e_com_ma: f64,
    /// The board.
    pub board: Board,
    /// Z_W of the board plane, mm.
    pub board_z_mm: f64,
    /// Image width and height, px.
    pub image_size: [u32; 2],
    /// Width of the white margin around the pattern, mm.
    pub margin_mm: f64,
}

impl Scene {
    /// A scene with a white margin of one square.
    pub fn new(model: CameraModel, e_com_ma: f64, board: Board, board_z_mm: f64, image_size: [u32; 2]) -> Self {
        Scene { model, e_com_ma, board, board_z_mm, image_size, margin_mm: board.square_mm() }
    }

    /// The paper rig's view: its board (14 x 12 inner corners, 1.5 mm squares, a margin of
    /// one square) at stage position `z_w_mm`, seen by `truth` at `e_com_ma` on the
    /// 1936 x 1458 sensor. Pair it with [`Optics::paper_focus`] for the blur the lens gives.
    pub fn paper_view(truth: &CameraModel, e_com_ma: f64, z_w_mm: f64) -> Self {
        let (inner_corners, square_mm) = PAPER_BOARD;
        let board = Board::Checkerboard(Checkerboard { inner_corners, square_mm });
        Scene::new(*truth, e_com_ma, board, z_w_mm, CameraModel::PAPER_IMAGE_SIZE)
    }

    /// World coordinates of corner `id` (row by row over the board's corner grid), mm;
    /// `None` beyond the board.
    pub fn corner_world_mm(&self, id: u32) -> Option<[f64; 3]> {
        self.board.corner_mm(id).map(|[x, y]| [x, y, self.board_z_mm])
    }

    /// World coordinates of the centre of the corner grid, mm.
    pub fn board_centre_world_mm(&self) -> [f64; 3] {
        let [x0, y0] = self.board.corner_mm(0).unwrap_or([0.0; 2]);
        let last = (self.board.corner_count() as u32).saturating_sub(1);
        let [x1, y1] = self.board.corner_mm(last).unwrap_or([0.0; 2]);
        [0.5 * (x0 + x1), 0.5 * (y0 + y1), self.board_z_mm]
    }

    /// Checks the scene: a valid model and board, a finite current and plane, a focal
    /// length positive at the current, a margin not negative, image sides in
    /// 1..=[`MAX_IMAGE_SIDE_PX`].
    pub fn validate(&self) -> Result<()> {
        self.board.validate().map_err(|e| e.under("board"))?;
        self.model.validate()?;
        self.model.intrinsics(self.e_com_ma)?;
        if !self.board_z_mm.is_finite() {
            return Err(Error::invalid_value(
                "board_z_mm",
                self.board_z_mm,
                format!("board plane Z must be finite, got {}", self.board_z_mm),
            ));
        }
        if !(self.margin_mm.is_finite() && self.margin_mm >= 0.0) {
            return Err(Error::invalid_value(
                "margin_mm",
                self.margin_mm,
                format!("margin must be finite and not negative, got {} mm", self.margin_mm),
            ));
        }
        let [w, h] = self.image_size;
        if !(1..=MAX_IMAGE_SIDE_PX).contains(&w) || !(1..=MAX_IMAGE_SIDE_PX).contains(&h) {
            return Err(Error::invalid_value(
                "image_size",
                self.image_size,
                format!("image size must be 1..={MAX_IMAGE_SIDE_PX} px per side, got {w} x {h}"),
            ));
        }
        Ok(())
    }
}

/// The lens's blur.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Optics {
    /// Camera depth Z_c of the plane in focus, mm; `None` = no defocus.
    pub focus_depth_mm: Option<f64>,
    /// Diameter of the aperture (entrance pupil), mm.
    pub aperture_mm: f64,
    /// A fixed Gaussian blur (lens aberrations, sensor), px, added in quadrature to the
    /// defocus; also the way to ask for a uniform blur of a given sigma.
    pub base_sigma_px: f64,
}

impl Default for Optics {
    /// No defocus, no blur, aperture 2.5 mm (that of the per-setting rig).
    fn default() -> Self {
        Optics { focus_depth_mm: None, aperture_mm: 2.5, base_sigma_px: 0.0 }
    }
}

impl Optics {
    /// A perfectly sharp lens.
    pub fn sharp() -> Self {
        Optics::default()
    }

    /// The same Gaussian blur `sigma_px` everywhere (no defocus).
    pub fn uniform_blur(sigma_px: f64) -> Self {
        Optics { base_sigma_px: sigma_px, ..Optics::default() }
    }

    /// The paper rig's lens at current `e_com_ma` with aperture `aperture_mm`: in focus at
    /// the camera depth [`crate::rig::focus_law_depth_mm`] of the simulated lens's smooth
    /// focus law ([`crate::rig::PAPER_FOCUS_LAW_MA`], fitted to the paper's 15 views; the
    /// views themselves are off it by the law's residual, 2.7 mA RMS). `truth` is kept for
    /// the callers: the law is the paper rig's, in its camera's depth.
    pub fn paper_focus(truth: &CameraModel, e_com_ma: f64, aperture_mm: f64) -> Self {
        let _ = truth;
        Optics { focus_depth_mm: Some(focus_law_depth_mm(e_com_ma)), aperture_mm, base_sigma_px: 0.0 }
    }

    /// The paper rig's lens with a focus law smooth in the current, for focus searches: the
    /// dioptric distance of the plane in focus is affine in the current,
    ///
    /// ```text
    /// 1/Z_f(E) = 1/Z_80 + (1/Z_225 - 1/Z_80) (E - 80) / 145,
    /// ```
    ///
    /// through the in-focus depths Z_80, Z_225 of [`Optics::paper_focus`] at 80 and 225 mA
    /// (an ETL's optical power is close to affine in its current, and with the sensor fixed
    /// so is 1/Z_f), plus a fixed blur `base_sigma_px` for diffraction and aberrations.
    ///
    /// Why not the stage positions of [`crate::rig::focused_z_mm`] for autofocus (this
    /// lens predates the smooth [`Optics::paper_focus`], and the autofocus study keeps its
    /// exact truth): they interpolate the paper's stage positions,
    /// whole millimetres, piecewise linearly, so its dioptric slope jumps at every view (by
    /// a factor of 1.8 at 150 mA) and the blur grows at different rates on the two sides of
    /// focus. And without a base blur the renderer leaves blurs under
    /// [`defocus::MIN_SIGMA_PX`] unapplied, which gives the sharpness curve a flat top 1.5
    /// to 3 mA wide; a real lens is never sharper than its diffraction limit (about 0.5 px for
    /// the paper rig: f/7.5, 550 nm, 3.45 um pixels, Airy sigma 0.42 lambda N).
    ///
    /// ```
    /// use etl_sim::render::Optics;
    /// use etl_core::model::CameraModel;
    /// let truth = CameraModel::paper_rig();
    /// let z = |e| Optics::smooth_focus(&truth, e, 2.5, 0.5).focus_depth_mm.unwrap();
    /// let p = |e| etl_sim::rig::focus_depth_mm(&truth, e);
    /// assert!((z(80.0) - p(80.0)).abs() < 1e-9 && (z(225.0) - p(225.0)).abs() < 1e-9);
    /// assert!((1.0 / z(150.0) - 0.5 * (1.0 / z(80.0) + 1.0 / z(220.0))).abs() < 1e-12);
    /// ```
    pub fn smooth_focus(truth: &CameraModel, e_com_ma: f64, aperture_mm: f64, base_sigma_px: f64) -> Self {
        let (e0, e1) = (80.0, 225.0);
        let d0 = 1.0 / focus_depth_mm(truth, e0);
        let d1 = 1.0 / focus_depth_mm(truth, e1);
        let dioptric = d0 + (d1 - d0) * (e_com_ma - e0) / (e1 - e0);
        Optics { focus_depth_mm: Some(1.0 / dioptric), aperture_mm, base_sigma_px }
    }

    /// The current (mA) at which [`Optics::smooth_focus`] is in focus at camera depth `z_mm`
    /// (the inverse of its focus law).
    pub fn smooth_focus_current_ma(truth: &CameraModel, z_mm: f64) -> f64 {
        let (e0, e1) = (80.0, 225.0);
        let d0 = 1.0 / focus_depth_mm(truth, e0);
        let d1 = 1.0 / focus_depth_mm(truth, e1);
        e0 + (e1 - e0) * (1.0 / z_mm - d0) / (d1 - d0)
    }

    /// Checks: focus depth positive and finite when given, aperture and base blur finite
    /// and not negative.
    pub fn validate(&self) -> Result<()> {
        if let Some(z) = self.focus_depth_mm {
            if !(z.is_finite() && z > 0.0) {
                return Err(Error::invalid_value(
                    "focus_depth_mm",
                    z,
                    format!("focus depth must be positive and finite, got {z} mm"),
                ));
            }
        }
        if !(self.aperture_mm.is_finite() && self.aperture_mm >= 0.0) {
            return Err(Error::invalid_value(
                "aperture_mm",
                self.aperture_mm,
                format!("aperture must be finite and not negative, got {} mm", self.aperture_mm),
            ));
        }
        if !(self.base_sigma_px.is_finite() && (0.0..=MAX_SIGMA_PX).contains(&self.base_sigma_px)) {
            return Err(Error::invalid_value(
                "base_sigma_px",
                self.base_sigma_px,
                format!("blur sigma must be within 0..={MAX_SIGMA_PX} px, got {}", self.base_sigma_px),
            ));
        }
        Ok(())
    }

    /// Blur (sigma, px) of a point at camera depth `z_mm` for a lens of focal length `f_px`.
    pub fn sigma_px(&self, f_px: f64, z_mm: f64) -> f64 {
        let d = match self.focus_depth_mm {
            Some(zf) => defocus_sigma_px(f_px, self.aperture_mm, z_mm, zf),
            None => 0.0,
        };
        defocus::total_sigma_px(d, self.base_sigma_px)
    }
}

/// Everything about a render except the scene.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct RenderOptions {
    /// Blur.
    pub optics: Optics,
    /// Grey levels, shading and noise.
    pub photometry: Photometry,
    /// 8 or 16 bits.
    pub bit_depth: BitDepth,
    /// Seed of the noise.
    pub seed: u64,
}

/// A rendered image and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// The image.
    pub image: Image,
    /// The true pixel of every corner, in id order (row by row over the board's corner
    /// grid, column fastest: entry `id` is corner `id`): exactly
    /// `model.project(corner_world_mm(id), e_com_ma)`. Corners outside the image are
    /// listed too (see `corners_in_image` and [`Rendered::visible`]).
    pub corners_px: Vec<[f64; 2]>,
    /// Whether each corner lies inside the image, 0 <= u <= width - 1 and
    /// 0 <= v <= height - 1.
    pub corners_in_image: Vec<bool>,
    /// The blur (sigma, px) at the board's centre (centre of the corner grid).
    pub blur_sigma_px: f64,
}

impl Rendered {
    /// The corners inside the image with their ids, in id order: what a detector can find
    /// (a ChArUco detector by the ids; a checkerboard's ids are its row-major index).
    ///
    /// ```
    /// use etl_sim::render::{render, Board, RenderOptions, Scene};
    /// use etl_core::model::CameraModel;
    /// let board = Board::charuco([12, 9], 1.5, 1.1, "DICT_5X5_100").unwrap();
    /// let scene = Scene::new(CameraModel::paper_rig(), 225.0, board, 2.0, [1936, 1458]);
    /// let r = render(&scene, &RenderOptions::default()).unwrap();
    /// let (ids, px) = r.visible();
    /// // The near view at high magnification sees part of the board only.
    /// assert!(ids.len() > 10 && ids.len() < board.corner_count());
    /// assert!(px.iter().all(|p| p[0] >= 0.0 && p[0] <= 1935.0));
    /// ```
    pub fn visible(&self) -> (Vec<u32>, Vec<[f64; 2]>) {
        self.corners_px
            .iter()
            .zip(&self.corners_in_image)
            .enumerate()
            .filter(|&(_, (_, &inside))| inside)
            .map(|(id, (&p, _))| (id as u32, p))
            .unzip()
    }
}

/// Renders `scene` with `opts`.
///
/// Errors ([`Error::InvalidInput`] or the core's): an invalid scene or options
/// ([`Scene::validate`], [`Optics::validate`], [`Photometry::validate`]); a corner at
/// or behind the camera (its pixel would not exist); the board seen edge-on.
///
/// ```
/// use etl_sim::render::{render, Optics, RenderOptions, Scene};
/// use etl_core::model::CameraModel;
/// let truth = CameraModel::paper_rig();
/// let mut scene = Scene::paper_view(&truth, 150.0, 22.0);
/// scene.image_size = [320, 240]; // a small crop of the sensor
/// let opts = RenderOptions { optics: Optics::paper_focus(&truth, 150.0, 2.5), ..Default::default() };
/// let r = render(&scene, &opts).unwrap();
/// assert_eq!(r.image.data.len(), 320 * 240);
/// assert_eq!(r.corners_px.len(), 14 * 12);
/// let c = truth.project([0.0, 0.0, 22.0], 150.0).unwrap();
/// assert_eq!(r.corners_px[0], c);
/// // Nearly in focus at the board's centre (the view is off the smooth focus law by its
/// // residual, -0.5 mA here).
/// assert!(r.blur_sigma_px < 0.5);
/// ```
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<Rendered> {
    scene.validate()?;
    opts.optics.validate()?;
    opts.photometry.validate()?;
    let [w, h] = scene.image_size;
    let (w, h) = (w as usize, h as usize);

    let [cols, _] = scene.board.corner_grid();
    let mut corners_px = Vec::with_capacity(scene.board.corner_count());
    for id in 0..scene.board.corner_count() as u32 {
        let (i, j) = (id as usize % cols, id as usize / cols);
        let p = scene
            .corner_world_mm(id)
            .ok_or(etl_core::Error::BehindCamera)
            .and_then(|w| scene.model.project(w, scene.e_com_ma))
            .map_err(|e| {
                let message = format!("corner {id} ({i}, {j}) cannot be projected: {e}");
                Error::invalid_value("board_z_mm", scene.board_z_mm, message)
            })?;
        corners_px.push(p);
    }
    let corners_in_image = corners_px
        .iter()
        .map(|p| (0.0..=(w - 1) as f64).contains(&p[0]) && (0.0..=(h - 1) as f64).contains(&p[1]))
        .collect();

    let map = PixelToBoard::new(&scene.model, scene.e_com_ma, scene.board_z_mm)?;
    let (fx, fy) = scene.model.focal_lengths(scene.e_com_ma);
    let f_px = 0.5 * (fx + fy);
    let centre = scene.board_centre_world_mm();
    let blur_sigma_px = opts.optics.sigma_px(f_px, map.depth_mm(centre[0], centre[1]));

    let p = &opts.photometry;
    let layout = BoardLayout::of(
        &scene.board,
        scene.margin_mm,
        Levels { dark: p.dark, light: p.light, background: p.background },
    );

    // The border must hold every kernel radius; the probe of `border_px` is refined by the
    // tile nodes' own blur (the border grows the image, so repeat until it holds: sigma
    // is clamped, so this ends).
    let mut pad = border_px(&map, &opts.optics, f_px, (w, h));
    let (nodes, field) = loop {
        let nodes = Nodes::new(&map, (w + 2 * pad, h + 2 * pad), pad);
        let field = BlurField::new(&nodes, &opts.optics, f_px);
        let needed = defocus::kernel_radius(f64::from(field.max_level()) * defocus::SIGMA_STEP_PX);
        if needed <= pad {
            break (nodes, field);
        }
        pad = needed;
    };
    let (pw, ph) = (w + 2 * pad, h + 2 * pad);

    let sharp = coverage::render_sharp(&map, &layout, &nodes, (pw, ph), pad);
    let blur = Blur::new(sharp, &field, (pw, ph), pad, w);
    let mut data = vec![0u16; w * h];
    data.par_chunks_mut(w).enumerate().for_each_init(
        || vec![0.0f32; w],
        |radiance, (y, out)| {
            blur.row(y, radiance);
            p.finish_row(radiance, y, (w, h), opts.bit_depth, opts.seed, out);
        },
    );
    let image = Image { width: scene.image_size[0], height: scene.image_size[1], bit_depth: opts.bit_depth, data };
    Ok(Rendered { image, corners_px, corners_in_image, blur_sigma_px })
}

/// The border (px) to render around the image so that the blur near its edges sees the
/// scene: the kernel radius of the largest blur over the image. The reciprocal depth is
/// affine in the undistorted image plane, so its extremes lie at the corners of the image
/// (probed a little outside them for the distortion's bending).
fn border_px(map: &PixelToBoard, optics: &Optics, f_px: f64, (w, h): (usize, usize)) -> usize {
    let mut smax = optics.sigma_px(f_px, f64::NAN);
    if optics.focus_depth_mm.is_some() && optics.aperture_mm > 0.0 {
        let m = 0.05 * (w.max(h) as f64) + 8.0;
        for x in [-m, 0.5 * w as f64, w as f64 + m] {
            for y in [-m, 0.5 * h as f64, h as f64 + m] {
                let s = match map.undistort_exact(x, y).and_then(|[u, v]| map.board_of_undistorted(u, v)) {
                    Some(p) => optics.sigma_px(f_px, 1.0 / p.inv_depth),
                    None => MAX_SIGMA_PX,
                };
                smax = smax.max(s);
            }
        }
    }
    defocus::kernel_radius(smax.min(MAX_SIGMA_PX) * 1.02) + 2
}
