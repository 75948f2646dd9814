//! Checkerboard detection against ground truth: rendered boards (a small supersampled
//! renderer here: exact homography, area-sampled pixels, Gaussian blur, Gaussian noise),
//! bad input, and real photographs (fixtures/detect).

use std::path::{Path, PathBuf};

use etl_formats::Error;
use etl_image::checkerboard::{detect_corners, detect_corners_u16, detect_file, detect_many, Pattern};
use image::{GrayImage, ImageBuffer, Luma};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// A board seen through a pinhole camera: pixel = H (X, Y, 1) with (X, Y) in squares.
struct Board {
    cols: usize,
    rows: usize,
    h: [[f64; 3]; 3],
    hinv: [[f64; 3]; 3],
}

fn mat3_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn inv3(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let (a, b) = ((j + 1) % 3, (j + 2) % 3);
            let (c, d) = ((i + 1) % 3, (i + 2) % 3);
            r[i][j] = (m[a][c] * m[b][d] - m[a][d] * m[b][c]) / det;
        }
    }
    r
}

impl Board {
    /// The board (square `square_px` px at the image centre when facing the camera) rotated
    /// by `rot` (rx, ry, rz in radians) about its own centre, centred at `centre` px.
    fn new(cols: usize, rows: usize, size: [u32; 2], square_px: f64, rot: [f64; 3], centre: [f64; 2]) -> Self {
        let f = 1500.0;
        let z = f / square_px; // board at depth z (in squares) so that one square is square_px.
        let (sx, cx) = (rot[0].sin(), rot[0].cos());
        let (sy, cy) = (rot[1].sin(), rot[1].cos());
        let (sz, cz) = (rot[2].sin(), rot[2].cos());
        let rxm = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
        let rym = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
        let rzm = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
        let r = mat3_mul(&rzm, &mat3_mul(&rym, &rxm));
        // Board point (X, Y) -> camera R (X - Xc, Y - Yc, 0) + (tx, ty, z).
        let (xc, yc) = ((cols as f64 - 1.0) / 2.0, (rows as f64 - 1.0) / 2.0);
        let (u0, v0) = (size[0] as f64 / 2.0 - 0.5, size[1] as f64 / 2.0 - 0.5);
        let t = [(centre[0] - u0) * z / f, (centre[1] - v0) * z / f, z];
        let k = [[f, 0.0, u0], [0.0, f, v0], [0.0, 0.0, 1.0]];
        let m = [
            [r[0][0], r[0][1], t[0] - r[0][0] * xc - r[0][1] * yc],
            [r[1][0], r[1][1], t[1] - r[1][0] * xc - r[1][1] * yc],
            [r[2][0], r[2][1], t[2] - r[2][0] * xc - r[2][1] * yc],
        ];
        let h = mat3_mul(&k, &m);
        Self { cols, rows, h, hinv: inv3(&h) }
    }

    fn project(&self, x: f64, y: f64) -> [f64; 2] {
        let h = &self.h;
        let w = h[2][0] * x + h[2][1] * y + h[2][2];
        [(h[0][0] * x + h[0][1] * y + h[0][2]) / w, (h[1][0] * x + h[1][1] * y + h[1][2]) / w]
    }

    fn truth(&self) -> Vec<[f64; 2]> {
        (0..self.rows).flat_map(|j| (0..self.cols).map(move |i| self.project(i as f64, j as f64))).collect()
    }

    /// Reflectance in [0, 1] at pixel (u, v): square [i, i+1] x [j, j+1] is dark when i + j
    /// is even; squares from -1 to cols (rows); then a white margin of `margin` squares;
    /// then `background`.
    fn value(&self, u: f64, v: f64, margin: f64, background: f64) -> f64 {
        let h = &self.hinv;
        let w = h[2][0] * u + h[2][1] * v + h[2][2];
        let x = (h[0][0] * u + h[0][1] * v + h[0][2]) / w;
        let y = (h[1][0] * u + h[1][1] * v + h[1][2]) / w;
        let (c, r) = (self.cols as f64, self.rows as f64);
        if x >= -1.0 && y >= -1.0 && x < c && y < r {
            let (i, j) = (x.floor() as i64, y.floor() as i64);
            if (i + j).rem_euclid(2) == 0 {
                0.0
            } else {
                1.0
            }
        } else if x >= -1.0 - margin && y >= -1.0 - margin && x < c + margin && y < r + margin {
            1.0
        } else {
            background
        }
    }
}

struct Look {
    blur: f64,
    noise: f64,
    dark: f64,
    light: f64,
    margin: f64,
    background: f64,
}

const LOOK: Look = Look { blur: 1.5, noise: 2.0, dark: 40.0, light: 210.0, margin: 1.0, background: 0.6 };

/// Renders grey levels (8-bit scale, f64): area sampling (8 x 8 where the pixel straddles
/// an edge), Gaussian blur, Gaussian noise.
fn render_f64(b: &Board, size: [u32; 2], look: &Look, seed: u64) -> Vec<f64> {
    let (w, h) = (size[0] as usize, size[1] as usize);
    let mut img = vec![0.0; w * h];
    const N: usize = 8;
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f64, y as f64);
            let probe = [
                b.value(u - 0.5, v - 0.5, look.margin, look.background),
                b.value(u + 0.5, v - 0.5, look.margin, look.background),
                b.value(u - 0.5, v + 0.5, look.margin, look.background),
                b.value(u + 0.5, v + 0.5, look.margin, look.background),
                b.value(u, v, look.margin, look.background),
            ];
            let refl = if probe.iter().all(|&p| p == probe[0]) {
                probe[0]
            } else {
                let mut s = 0.0;
                for sy in 0..N {
                    for sx in 0..N {
                        let du = (sx as f64 + 0.5) / N as f64 - 0.5;
                        let dv = (sy as f64 + 0.5) / N as f64 - 0.5;
                        s += b.value(u + du, v + dv, look.margin, look.background);
                    }
                }
                s / (N * N) as f64
            };
            img[y * w + x] = look.dark + (look.light - look.dark) * refl;
        }
    }
    if look.blur > 0.0 {
        img = blur(&img, w, h, look.blur);
    }
    if look.noise > 0.0 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = Normal::new(0.0, look.noise).unwrap();
        for p in &mut img {
            *p += n.sample(&mut rng);
        }
    }
    img
}

fn blur(img: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    let r = (4.0 * sigma).ceil() as isize;
    let k: Vec<f64> = (-r..=r).map(|i| (-0.5 * (i * i) as f64 / (sigma * sigma)).exp()).collect();
    let s: f64 = k.iter().sum();
    let k: Vec<f64> = k.iter().map(|v| v / s).collect();
    let mut tmp = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut a = 0.0;
            for (t, kv) in k.iter().enumerate() {
                let sx = (x as isize + t as isize - r).clamp(0, w as isize - 1) as usize;
                a += kv * img[y * w + sx];
            }
            tmp[y * w + x] = a;
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut a = 0.0;
            for (t, kv) in k.iter().enumerate() {
                let sy = (y as isize + t as isize - r).clamp(0, h as isize - 1) as usize;
                a += kv * tmp[sy * w + x];
            }
            out[y * w + x] = a;
        }
    }
    out
}

fn to_u8(img: &[f64], size: [u32; 2]) -> GrayImage {
    GrayImage::from_raw(size[0], size[1], img.iter().map(|v| v.round().clamp(0.0, 255.0) as u8).collect()).unwrap()
}

fn to_u16(img: &[f64], size: [u32; 2]) -> ImageBuffer<Luma<u16>, Vec<u16>> {
    ImageBuffer::from_raw(
        size[0],
        size[1],
        img.iter().map(|v| (v * 257.0).round().clamp(0.0, 65535.0) as u16).collect(),
    )
    .unwrap()
}

fn rms(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    assert_eq!(a.len(), b.len());
    let s: f64 = a.iter().zip(b).map(|(p, q)| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sum();
    (s / a.len() as f64).sqrt()
}

fn max_err(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max)
}

fn pat(s: &str) -> Pattern {
    s.parse().unwrap()
}

fn not_found(r: etl_formats::Result<etl_image::checkerboard::Detection>) -> String {
    match r {
        Err(Error::BoardNotFound(m)) => m,
        Err(e) => panic!("expected BoardNotFound, got {e}"),
        Ok(d) => panic!("expected BoardNotFound, got a grid of {} corners", d.corners_px.len()),
    }
}

/// A view of the 14x12 board (1.5 mm squares, a one-square white margin) through the
/// paper rig's camera (its distortion) at 150 mA, rotated by `rot` (Rodrigues) about the
/// board's centre, which sits on the optical axis at the distance giving ~`square_px` px
/// squares; rendered by `etl_sim::render` (blur sigma `blur` px, dark 40, light 210, read
/// noise 2 grey levels, 8-bit).
fn rendered_view(rot: [f64; 3], square_px: f64, blur: f64, seed: u64) -> etl_sim::render::Rendered {
    use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
    use etl_core::model::CameraModel;
    use etl_sim::render::{render, BitDepth, Board, Checkerboard, Optics, Photometry, RenderOptions, Scene};
    let e_com_ma = 150.0;
    let mut model = CameraModel::paper_rig();
    let (fx, _) = model.focal_lengths(e_com_ma);
    let board = Board::Checkerboard(Checkerboard { inner_corners: [14, 12], square_mm: 1.5 });
    let z_mm = fx * board.square_mm() / square_px;
    let centre = [6.5 * 1.5, 5.5 * 1.5, 0.0];
    let rc = mat_vec(&rodrigues_to_matrix(rot), centre);
    model.rotation_rodrigues = rot;
    model.translation_mm = [-rc[0], -rc[1], z_mm - rc[2]];
    let scene = Scene::new(model, e_com_ma, board, 0.0, [1936, 1458]);
    let opts = RenderOptions {
        optics: Optics::uniform_blur(blur),
        photometry: Photometry { dark: 40.0, light: 210.0, read_noise: 2.0, ..Photometry::default() },
        bit_depth: BitDepth::Eight,
        seed,
    };
    render(&scene, &opts).unwrap()
}

/// Poses (Rodrigues vectors) of the board: facing the camera, tilted both ways, turned.
const POSES: [[f64; 3]; 4] = [[0.0, 0.0, 0.05], [0.35, -0.25, 0.1], [-0.3, 0.4, -0.3], [0.1, 0.45, 2.0]];

#[test]
fn accuracy_on_rendered_boards_at_three_blurs() {
    for blur in [0.5, 1.5, 3.0] {
        let mut all_est = Vec::new();
        let mut all_true = Vec::new();
        for (k, rot) in POSES.into_iter().enumerate() {
            let r = rendered_view(rot, 66.0, blur, 7 + k as u64);
            assert!(r.corners_in_image.iter().all(|&b| b));
            let img = r.image.to_dynamic();
            let det = etl_image::checkerboard::detect_dynamic(&img, pat("14x12"))
                .unwrap_or_else(|e| panic!("blur {blur} pose {k}: {e}"));
            let truth = r.corners_px.clone();
            // Symmetric board: corner 0 is the one nearest the top-left; compare either way.
            let mut est = det.corners_px.clone();
            if rms(&est, &truth) > 5.0 {
                est.reverse();
            }
            assert!(max_err(&est, &truth) < 0.12, "blur {blur} pose {k}: max {}", max_err(&est, &truth));
            all_est.extend(est);
            all_true.extend(truth);
        }
        let e = rms(&all_est, &all_true);
        println!("blur {blur}: rms {e:.4} px over {} corners", all_est.len());
        // Acceptance: 0.03 px; measured 0.009 / 0.008 / 0.010 px.
        assert!(e <= 0.015, "blur {blur}: rms {e} px");
    }
}

/// A smaller scene for the robustness tests (fast in debug builds).
fn small(cols: usize, rows: usize, rot: [f64; 3], centre: [f64; 2], look: &Look, seed: u64) -> (Board, GrayImage) {
    let size = [640, 480];
    let b = Board::new(cols, rows, size, 40.0, rot, centre);
    let img = to_u8(&render_f64(&b, size, look, seed), size);
    (b, img)
}

#[test]
fn asymmetric_board_keeps_its_order_when_turned_half_way() {
    // 9x6: cols + rows odd, so the dark square at corner (0, 0) fixes the order at any turn.
    for (k, rz) in [0.1f64, 1.2, 3.1, -2.0, 4.5].into_iter().enumerate() {
        let (b, img) = small(9, 6, [0.2, -0.1, rz], [320.0, 240.0], &LOOK, k as u64);
        let det = detect_corners(&img, pat("9x6")).unwrap_or_else(|e| panic!("rz {rz}: {e}"));
        let truth = b.truth();
        let e = max_err(&det.corners_px, &truth);
        assert!(e < 0.1, "rz {rz}: corners not in the true order (max error {e} px)");
    }
}

#[test]
fn transposed_pattern_finds_the_same_corners_in_its_own_order() {
    let (b, img) = small(9, 6, [0.0, 0.0, 0.3], [320.0, 240.0], &LOOK, 3);
    let det = detect_corners(&img, pat("6x9")).unwrap();
    let truth = b.truth();
    // Every returned corner is a true corner.
    for p in &det.corners_px {
        let d = truth.iter().map(|q| (p[0] - q[0]).hypot(p[1] - q[1])).fold(f64::MAX, f64::min);
        assert!(d < 0.1);
    }
    // Handedness: (p(1,0) - p(0,0)) x (p(0,1) - p(0,0)) > 0 (u right, v down).
    let c = &det.corners_px;
    let a = [c[1][0] - c[0][0], c[1][1] - c[0][1]];
    let bb = [c[6][0] - c[0][0], c[6][1] - c[0][1]];
    assert!(a[0] * bb[1] - a[1] * bb[0] > 0.0);
}

#[test]
fn symmetric_board_starts_nearest_the_top_left() {
    for rz in [0.2f64, 3.0] {
        let (b, img) = small(8, 6, [0.0, 0.1, rz], [320.0, 240.0], &LOOK, 5);
        let det = detect_corners(&img, pat("8x6")).unwrap();
        let mut truth = b.truth();
        let first = |t: &[[f64; 2]]| t[0][0].hypot(t[0][1]);
        let last = |t: &[[f64; 2]]| t[t.len() - 1][0].hypot(t[t.len() - 1][1]);
        if last(&truth) < first(&truth) {
            truth.reverse();
        }
        assert!(max_err(&det.corners_px, &truth) < 0.1, "rz {rz}");
    }
}

#[test]
fn wrong_size_is_not_found() {
    let (_, img) = small(9, 6, [0.1, 0.2, 0.15], [320.0, 240.0], &LOOK, 11);
    for wrong in ["10x6", "9x7", "8x6", "9x5", "10x7", "6x10"] {
        not_found(detect_corners(&img, pat(wrong)));
    }
    // When the count of corners would allow it, the reason names the grid found.
    let m = not_found(detect_corners(&img, pat("8x6")));
    assert!(m.contains("9x6") || m.contains("6x9"), "{m}");
}

#[test]
fn board_against_a_dark_or_grey_background_without_margin() {
    for background in [0.0, 0.35, 0.6, 1.0] {
        let look = Look { margin: 0.0, background, ..LOOK };
        let (b, img) = small(9, 6, [0.15, -0.2, 0.4], [330.0, 230.0], &look, 13);
        let det = detect_corners(&img, pat("9x6")).unwrap_or_else(|e| panic!("background {background}: {e}"));
        assert!(max_err(&det.corners_px, &b.truth()) < 0.1);
        not_found(detect_corners(&img, pat("10x6")));
        not_found(detect_corners(&img, pat("9x7")));
    }
}

#[test]
fn half_board_is_not_found() {
    // The board's centre near the right edge: half of it out of the image.
    let (_, img) = small(9, 6, [0.0, 0.0, 0.1], [620.0, 240.0], &LOOK, 17);
    not_found(detect_corners(&img, pat("9x6")));
}

#[test]
fn noise_only_constant_and_tiny_images_are_not_found() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let n = Normal::<f64>::new(128.0, 40.0).unwrap();
    let noise = GrayImage::from_fn(640, 480, |_, _| Luma([n.sample(&mut rng).clamp(0.0f64, 255.0) as u8]));
    not_found(detect_corners(&noise, pat("9x6")));
    // Smoothed noise has saddles everywhere.
    let raw: Vec<f64> = noise.as_raw().iter().map(|&v| v as f64).collect();
    let smooth = blur(&raw, 640, 480, 3.0);
    let smooth: Vec<f64> = smooth.iter().map(|v| 128.0 + (v - 128.0) * 8.0).collect();
    not_found(detect_corners(&to_u8(&smooth, [640, 480]), pat("9x6")));
    not_found(detect_corners(&GrayImage::from_pixel(640, 480, Luma([128])), pat("9x6")));
    let m = not_found(detect_corners(&GrayImage::new(5, 5), pat("9x6")));
    assert!(m.contains("too small"), "{m}");
    not_found(detect_corners(&GrayImage::new(0, 0), pat("9x6")));
}

#[test]
fn sixteen_bit_input_gives_the_same_corners() {
    let size = [640, 480];
    let b = Board::new(9, 6, size, 40.0, [0.1, 0.1, 0.2], [320.0, 240.0]);
    let f = render_f64(&b, size, &LOOK, 21);
    let d8 = detect_corners(&to_u8(&f, size), pat("9x6")).unwrap();
    let d16 = detect_corners_u16(&to_u16(&f, size), pat("9x6")).unwrap();
    assert!(rms(&d16.corners_px, &b.truth()) < 0.05);
    assert!(max_err(&d8.corners_px, &d16.corners_px) < 0.05);
}

#[test]
fn patterns_parse_and_bad_ones_are_refused() {
    assert_eq!(pat("14x12"), Pattern { cols: 14, rows: 12 });
    assert_eq!(pat(" 9X6 "), Pattern { cols: 9, rows: 6 });
    for bad in ["", "14", "14x", "x12", "14x12x3", "-3x5", "ax5", "2x5", "5x2", "0x0", "5x100000"] {
        match bad.parse::<Pattern>() {
            Err(Error::InvalidInput { what, value, message }) => {
                assert!(message.contains("pattern"), "{bad}: {message}");
                assert_eq!(what, "pattern", "{bad}");
                assert!(value.is_some_and(|v| !v.is_empty() || bad.is_empty()), "{bad}");
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/detect")
}

#[test]
fn corrupt_and_truncated_files_are_image_errors() {
    let dir = tempfile::tempdir().unwrap();
    let size = [160, 120];
    let b = Board::new(5, 4, size, 20.0, [0.0, 0.0, 0.1], [80.0, 60.0]);
    let img = to_u8(&render_f64(&b, size, &LOOK, 1), size);
    let mut cases = Vec::new();
    for (ext, fmt) in
        [("png", image::ImageFormat::Png), ("jpg", image::ImageFormat::Jpeg), ("tif", image::ImageFormat::Tiff)]
    {
        let good = dir.path().join(format!("good.{ext}"));
        img.save_with_format(&good, fmt).unwrap();
        assert!(detect_file(&good, pat("5x4")).is_ok(), "{ext}");
        let bytes = std::fs::read(&good).unwrap();
        let trunc = dir.path().join(format!("trunc.{ext}"));
        std::fs::write(&trunc, &bytes[..bytes.len().min(60)]).unwrap();
        // Cut after the headers: PNG and TIFF refuse it; the JPEG decoder fills the missing
        // part, leaving at most part of a board: an error either way, never a grid.
        let cut = dir.path().join(format!("cut.{ext}"));
        std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
        match detect_file(&cut, pat("5x4")) {
            Err(Error::Image { .. }) | Err(Error::BoardNotFound(_)) => {}
            other => panic!("{ext} cut: {other:?}"),
        }
        let garbage = dir.path().join(format!("garbage.{ext}"));
        std::fs::write(&garbage, b"this is not an image at all").unwrap();
        cases.push(trunc);
        cases.push(garbage);
    }
    let empty = dir.path().join("empty.png");
    std::fs::write(&empty, b"").unwrap();
    cases.push(empty);
    for p in &cases {
        match detect_file(p, pat("5x4")) {
            Err(Error::Image { path, .. }) => assert_eq!(&path, p),
            other => panic!("{}: {other:?}", p.display()),
        }
    }
    match detect_file(&dir.path().join("missing.png"), pat("5x4")) {
        Err(Error::Io { .. }) => {}
        other => panic!("missing file: {other:?}"),
    }
}

#[test]
fn real_photographs_are_found_and_one_column_more_is_not() {
    // fixtures/detect/SOURCE.md: 9x6 boards (640 x 512 grey) and an 8x8-square chessboard
    // (7x7 inner corners) on a wooden desk seen by a webcam (640 x 480 colour JPEG).
    let cases = [
        ("stereo_left01.jpg", "9x6", "10x6"),
        ("stereo_left05.jpg", "9x6", "10x6"),
        ("stereo_left12.jpg", "9x6", "9x7"),
        ("stereo_right03.jpg", "9x6", "10x6"),
        ("webcam_01.jpg", "7x7", "8x7"),
        ("webcam_02.jpg", "7x7", "8x7"),
        ("webcam_07.jpg", "7x7", "7x8"),
    ];
    let paths: Vec<PathBuf> = cases.iter().map(|c| fixtures().join(c.0)).collect();
    let found = detect_many(&paths, pat("9x6"));
    for ((name, size, wrong), r) in cases.iter().zip(found) {
        let p = pat(size);
        let det = if *size == "9x6" { r.unwrap() } else { detect_file(&fixtures().join(name), p).unwrap() };
        assert_eq!(det.corners_px.len(), p.len(), "{name}");
        // Neighbouring corners are about equally spaced along each row (no skipped corner).
        for row in det.corners_px.chunks(p.cols) {
            let d: Vec<f64> = row.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).collect();
            let mean = d.iter().sum::<f64>() / d.len() as f64;
            assert!(d.iter().all(|&x| (x / mean - 1.0).abs() < 0.35), "{name}: uneven row {d:?}");
        }
        not_found(detect_file(&fixtures().join(name), pat(wrong)));
    }
}
