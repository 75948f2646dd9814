//! The synthetic camera against the model: corners where the model projects them (from the
//! image's point symmetry, to 0.01 px), the exact coverage against independent
//! supersampling through `CameraModel::ray`, the thin-lens blur, determinism and bad input.
use etl_core::model::CameraModel;
use etl_sim::render::{
    defocus_sigma_px, render, BitDepth, Board, Checkerboard, Image, Optics, Photometry, RenderOptions, Rendered, Scene,
};

/// Noise-free 16-bit options with the given optics.
fn clean(optics: Optics) -> RenderOptions {
    RenderOptions { optics, photometry: Photometry::default().noise_free(), bit_depth: BitDepth::Sixteen, seed: 0 }
}

/// A tilted lens-off-like view: an 11 x 8 board of 4 mm squares about 125 mm away, at E = 0.
fn tilted_scene() -> Scene {
    let om = [0.3f64, -0.25, 0.1];
    let r = etl_core::model::rotation::rodrigues_to_matrix(om);
    let c = etl_core::model::rotation::mat_vec(&r, [20.0, 14.0, 0.0]);
    let model = CameraModel {
        rotation_rodrigues: om,
        translation_mm: [2.0 - c[0], -1.0 - c[1], 125.0 - c[2]],
        ..CameraModel::paper_rig()
    };
    Scene::new(
        model,
        0.0,
        Board::Checkerboard(Checkerboard { inner_corners: [11, 8], square_mm: 4.0 }),
        0.0,
        [1936, 1458],
    )
}

/// Lanczos window of `A` lobes: near-exact interpolation of an image blurred by sigma >= 2
/// px (its spectrum is below 1e-17 at the Nyquist frequency).
const A: i64 = 6;

fn lanczos(t: f64) -> f64 {
    let a = A as f64;
    if t.abs() < 1e-12 {
        1.0
    } else if t.abs() >= a {
        0.0
    } else {
        let pt = std::f64::consts::PI * t;
        a * pt.sin() * (pt / a).sin() / (pt * pt)
    }
}

fn interpolate(img: &Image, x: f64, y: f64) -> f64 {
    let (x0, y0) = (x.floor() as i64, y.floor() as i64);
    let wx: Vec<f64> = (x0 - A + 1..=x0 + A).map(|i| lanczos(x - i as f64)).collect();
    let (mut s, mut norm) = (0.0, 0.0);
    for j in y0 - A + 1..=y0 + A {
        let wy = lanczos(y - j as f64);
        for (k, i) in (x0 - A + 1..=x0 + A).enumerate() {
            let v = f64::from(img.get(i as u32, j as u32).unwrap());
            s += v * wx[k] * wy;
            norm += wx[k] * wy;
        }
    }
    s / norm
}

/// The centre of point symmetry of the image near `start`: minimises
/// sum_d (I(c + d) - I(c - d))^2 over offsets d within 5 px (Gauss-Newton, numerical
/// derivatives).
fn symmetry_centre(img: &Image, start: [f64; 2]) -> [f64; 2] {
    let offsets: Vec<[f64; 2]> = (-10..=10)
        .flat_map(|a| (0..=10).map(move |b| [0.5 * a as f64, 0.5 * b as f64]))
        .filter(|d| (d[1] > 0.0 || d[0] > 0.0) && d[0].hypot(d[1]) <= 5.0)
        .collect();
    let resid = |c: [f64; 2]| -> Vec<f64> {
        offsets
            .iter()
            .map(|d| interpolate(img, c[0] + d[0], c[1] + d[1]) - interpolate(img, c[0] - d[0], c[1] - d[1]))
            .collect()
    };
    let mut c = start;
    for _ in 0..5 {
        let r = resid(c);
        let h = 1e-3;
        let rx = resid([c[0] + h, c[1]]);
        let ry = resid([c[0], c[1] + h]);
        let (mut a, mut b, mut d, mut gx, mut gy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for k in 0..r.len() {
            let (jx, jy) = ((rx[k] - r[k]) / h, (ry[k] - r[k]) / h);
            a += jx * jx;
            b += jx * jy;
            d += jy * jy;
            gx += jx * r[k];
            gy += jy * r[k];
        }
        let det = a * d - b * b;
        c = [c[0] - (d * gx - b * gy) / det, c[1] - (a * gy - b * gx) / det];
    }
    c
}

/// RMS and largest distance between the image's centres of symmetry and `corners_px`, over
/// the corners at least 15 px inside the image, and their count.
fn symmetry_errors(scene: &Scene, r: &Rendered) -> (f64, f64, usize) {
    let [w, h] = scene.image_size;
    let (mut sum2, mut worst, mut n) = (0.0f64, 0.0f64, 0usize);
    for (c, inside) in r.corners_px.iter().zip(&r.corners_in_image) {
        if !inside || c[0] < 15.0 || c[1] < 15.0 || c[0] > w as f64 - 16.0 || c[1] > h as f64 - 16.0 {
            continue;
        }
        let found = symmetry_centre(&r.image, [c[0] + 0.3, c[1] - 0.2]);
        let err = (found[0] - c[0]).hypot(found[1] - c[1]);
        sum2 += err * err;
        worst = worst.max(err);
        n += 1;
    }
    ((sum2 / n.max(1) as f64).sqrt(), worst, n)
}

#[test]
fn corners_px_are_the_model_projections_and_the_image_agrees() {
    let truth = CameraModel::paper_rig();
    for scene in [Scene::paper_view(&truth, 150.0, 22.0), tilted_scene()] {
        let r = render(&scene, &clean(Optics::uniform_blur(2.0))).unwrap();
        let [cols, rows] = scene.board.corner_grid();
        assert_eq!(r.corners_px.len(), cols * rows);
        for j in 0..rows {
            for i in 0..cols {
                let w = [i as f64 * scene.board.square_mm(), j as f64 * scene.board.square_mm(), scene.board_z_mm];
                let p = scene.model.project(w, scene.e_com_ma).unwrap();
                assert_eq!(r.corners_px[j * cols + i], p);
            }
        }
        // The estimator itself is exact to 6e-4 px on an exactly symmetric blurred corner;
        // what remains is the renderer's: the discrete Gaussian applied to area-coverage
        // samples aliases the edges' high frequencies (module docs of render::defocus).
        let (rms, worst, n) = symmetry_errors(&scene, &r);
        assert!(n >= 60, "only {n} corners checked");
        eprintln!("symmetry: rms {rms} px, worst {worst} px over {n} corners");
        assert!(rms < 0.012 && worst < 0.025, "rms {rms} px, worst {worst} px over {n} corners");
    }
}

/// The largest and mean difference between the rendered grey level and the mean of a
/// 48 x 48 point sampling through `CameraModel::ray` of the board's `colour`, over the
/// 5 x 5 pixels around each of `centres`.
fn supersampling_errors(
    scene: &Scene,
    r: &Rendered,
    colour: &dyn Fn(f64, f64) -> f64,
    centres: &[[f64; 2]],
) -> (f64, f64) {
    let n = 48;
    let (mut worst, mut sum, mut count) = (0.0f64, 0.0, 0);
    for c in centres {
        for dy in -2..=2 {
            for dx in -2..=2 {
                let (px, py) = (c[0].round() as i64 + dx, c[1].round() as i64 + dy);
                let mut acc = 0.0;
                for sy in 0..n {
                    for sx in 0..n {
                        let q = [
                            px as f64 - 0.5 + (sx as f64 + 0.5) / n as f64,
                            py as f64 - 0.5 + (sy as f64 + 0.5) / n as f64,
                        ];
                        let ray = scene.model.ray(q, scene.e_com_ma).unwrap();
                        let t = (scene.board_z_mm - ray.origin_mm[2]) / ray.direction[2];
                        let p = ray.at(t);
                        acc += colour(p[0], p[1]);
                    }
                }
                let expect = acc / (n * n) as f64;
                let got = f64::from(r.image.get(px as u32, py as u32).unwrap()) / 257.0;
                let d = (got - expect).abs();
                worst = worst.max(d);
                sum += d;
                count += 1;
            }
        }
    }
    (worst, sum / count as f64)
}

#[test]
fn sharp_coverage_matches_supersampling_through_the_ray() {
    let scene = tilted_scene();
    let r = render(&scene, &clean(Optics::sharp())).unwrap();
    let s = scene.board.square_mm();
    let [cols, rows] = scene.board.corner_grid();
    let colour = |x: f64, y: f64| -> f64 {
        let (a, b) = ((x / s).floor(), (y / s).floor());
        let inside = a >= -1.0 && a <= (cols - 1) as f64 && b >= -1.0 && b <= (rows - 1) as f64;
        assert!(inside, "test pixels stay on the pattern");
        if (a + b).rem_euclid(2.0) == 0.0 {
            40.0
        } else {
            210.0
        }
    };
    let inner: Vec<usize> = (0..r.corners_px.len())
        .filter(|&k| {
            let c = r.corners_px[k];
            r.corners_in_image[k] && c[0] > 5.0 && c[1] > 5.0 && c[0] < 1930.0 && c[1] < 1452.0
        })
        .collect();
    assert!(inner.len() >= 60, "{}", inner.len());
    let centres: Vec<[f64; 2]> = [inner[0], inner[inner.len() / 3], inner[inner.len() / 2], inner[inner.len() - 1]]
        .map(|k| r.corners_px[k])
        .into();
    let (worst, mean) = supersampling_errors(&scene, &r, &colour, &centres);
    // Point sampling on a 48 x 48 grid is within 170 / 48 grey levels of the true area
    // mean for a straight edge; the mean difference is far smaller.
    assert!(worst < 170.0 / 48.0 + 0.05, "worst {worst}");
    assert!(mean < 0.5, "mean {mean}");
}

/// The tilted view with a ChArUco board of 12 x 9 squares of 4 mm, markers 3 mm of
/// DICT_4X4_100 (cells of 0.5 mm, about 10 px), its centre where the checkerboard's is.
fn tilted_charuco() -> Scene {
    let mut scene = tilted_scene();
    scene.board = Board::charuco([12, 9], 4.0, 3.0, "DICT_4X4_100").unwrap();
    // The ChArUco frame starts one square before the checkerboard's first inner corner.
    let r = etl_core::model::rotation::rodrigues_to_matrix(scene.model.rotation_rodrigues);
    let o = etl_core::model::rotation::mat_vec(&r, [-4.0, -4.0, 0.0]);
    let t = scene.model.translation_mm;
    scene.model.translation_mm = [t[0] + o[0], t[1] + o[1], t[2] + o[2]];
    scene
}

/// A ChArUco board's grey level at board point (x, y) from etl-core's geometry and codes
/// alone: black squares, and in the white ones the marker's cells (border black, data
/// cells white for a 1 bit).
fn charuco_colour(b: &etl_core::board::CharucoBoard, x: f64, y: f64) -> f64 {
    let s = b.square_mm();
    let (a, c) = ((x / s).floor(), (y / s).floor());
    assert!(a >= 0.0 && c >= 0.0 && a < b.squares()[0] as f64 && c < b.squares()[1] as f64, "on the pattern");
    if b.is_black(a as u32, c as u32) {
        return 40.0;
    }
    let id = b.marker_at(a as u32, c as u32).unwrap();
    let [tl, _, br, _] = b.marker_corners_mm(id).unwrap();
    if x < tl[0] || y < tl[1] || x >= br[0] || y >= br[1] {
        return 210.0;
    }
    let n = b.dictionary().marker_bits();
    let cell = b.marker_mm() / (n + 2) as f64;
    let (col, row) = (((x - tl[0]) / cell) as usize, ((y - tl[1]) / cell) as usize);
    if col == 0 || row == 0 || col > n || row > n {
        return 40.0;
    }
    if b.dictionary().is_white(id, row - 1, col - 1).unwrap() {
        210.0
    } else {
        40.0
    }
}

/// The ChArUco board renders with the same exact coverage: every marker cell's centre has
/// its code's grey level, and the pixels across the markers' cell edges and the squares'
/// corners are the area means of independent supersampling; its corners are the model's
/// projections of OpenCV's corner coordinates, the visible ones listed with their ids.
#[test]
fn charuco_markers_are_their_codes_and_covered_exactly() {
    let scene = tilted_charuco();
    let b = *scene.board.as_charuco().unwrap();
    let r = render(&scene, &clean(Optics::sharp())).unwrap();
    assert_eq!(r.corners_px.len(), 11 * 8);
    for id in 0..88u32 {
        let [x, y] = b.corner_mm(id).unwrap();
        assert_eq!(r.corners_px[id as usize], scene.model.project([x, y, 0.0], 0.0).unwrap());
    }
    let (ids, px) = r.visible();
    assert_eq!(ids.len(), px.len());
    assert!(ids.iter().all(|&id| r.corners_in_image[id as usize]));
    assert!(ids.len() >= 60, "{}", ids.len());
    // Cell centres: exactly their level (cells are about 10 px wide).
    let n = b.dictionary().marker_bits();
    let cell = b.marker_mm() / (n + 2) as f64;
    let (mut checked, mut dark) = (0, 0);
    for id in 0..b.markers() as u32 {
        let [tl, ..] = b.marker_corners_mm(id).unwrap();
        for row in 0..n + 2 {
            for col in 0..n + 2 {
                let (x, y) = (tl[0] + (col as f64 + 0.5) * cell, tl[1] + (row as f64 + 0.5) * cell);
                let p = scene.model.project([x, y, 0.0], 0.0).unwrap();
                let (u, v) = (p[0].round(), p[1].round());
                if u < 0.0 || v < 0.0 || u > 1935.0 || v > 1457.0 {
                    continue;
                }
                let got = f64::from(r.image.get(u as u32, v as u32).unwrap()) / 257.0;
                let want = charuco_colour(&b, x, y);
                assert!((got - want).abs() < 0.01, "marker {id} cell ({row}, {col}): {got} vs {want}");
                checked += 1;
                dark += usize::from(want == 40.0);
            }
        }
    }
    assert!(checked > 1500 && dark > checked / 2 && dark < checked, "{checked} {dark}");
    // Edges: around marker corners and a cell corner inside each of a few markers.
    let mut centres = vec![];
    for id in [0u32, 20, 33, 50] {
        let [tl, _, br, _] = b.marker_corners_mm(id).unwrap();
        for q in [tl, br, [tl[0] + 2.0 * cell, tl[1] + 3.0 * cell]] {
            centres.push(scene.model.project([q[0], q[1], 0.0], 0.0).unwrap());
        }
    }
    centres.push(r.corners_px[40]);
    centres.retain(|c| c[0] > 3.0 && c[1] > 3.0 && c[0] < 1932.0 && c[1] < 1454.0);
    assert!(centres.len() >= 8, "{}", centres.len());
    let (worst, mean) = supersampling_errors(&scene, &r, &|x, y| charuco_colour(&b, x, y), &centres);
    assert!(worst < 170.0 / 48.0 + 0.05, "worst {worst}");
    assert!(mean < 0.5, "mean {mean}");
}

/// A lens focused at the camera depth of the paper board's centre with the stage where the
/// paper's view at `e` stands, aperture 2.5 mm.
fn stage_focus(truth: &CameraModel, e: f64) -> Optics {
    Optics { focus_depth_mm: Some(etl_sim::rig::focus_depth_mm(truth, e)), aperture_mm: 2.5, base_sigma_px: 0.0 }
}

#[test]
fn thin_lens_blur_at_the_board_centre() {
    let truth = CameraModel::paper_rig();
    let e = 150.0;
    // In focus: at the board centre's depth with the stage where the paper's view at
    // 150 mA stands (the renderer's physics, not the rig's focus law).
    let optics = stage_focus(&truth, e);
    let mut scene = Scene::paper_view(&truth, e, 22.0);
    scene.image_size = [64, 48];
    assert!(render(&scene, &clean(optics)).unwrap().blur_sigma_px < 1e-9);
    // 3 mm farther: the formula with the board centre's camera depth.
    scene.board_z_mm = 25.0;
    let zc = truth.world_to_camera(scene.board_centre_world_mm())[2];
    let (fx, fy) = truth.focal_lengths(e);
    let expect = defocus_sigma_px(0.5 * (fx + fy), 2.5, zc, optics.focus_depth_mm.unwrap());
    let got = render(&scene, &clean(optics)).unwrap().blur_sigma_px;
    assert!((got - expect).abs() < 1e-12 && expect > 1.0, "{got} {expect}");
}

#[test]
fn varying_defocus_matches_a_uniform_blur_where_the_sigmas_agree() {
    let truth = CameraModel::paper_rig();
    let e = 150.0;
    let scene = Scene::paper_view(&truth, e, 24.0);
    let optics = stage_focus(&truth, e);
    let varying = render(&scene, &clean(optics)).unwrap();
    // The depth of field is shallow (0.6 px of sigma per mm here): compare around corner
    // (6, 6) with the uniform blur of that corner's own depth.
    let zc = truth.world_to_camera(scene.corner_world_mm(6 * 14 + 6).unwrap())[2];
    let (fx, fy) = truth.focal_lengths(e);
    let sigma = defocus_sigma_px(0.5 * (fx + fy), 2.5, zc, optics.focus_depth_mm.unwrap());
    assert!(sigma > 1.0, "{sigma}");
    let uniform = render(&scene, &clean(Optics::uniform_blur(sigma))).unwrap();
    let c = varying.corners_px[6 * 14 + 6];
    let mut worst = 0.0f64;
    for dy in -3..=3 {
        for dx in -3..=3 {
            let (x, y) = ((c[0].round() as i64 + dx) as u32, (c[1].round() as i64 + dy) as u32);
            let a = f64::from(varying.image.get(x, y).unwrap()) / 257.0;
            let b = f64::from(uniform.image.get(x, y).unwrap()) / 257.0;
            worst = worst.max((a - b).abs());
        }
    }
    assert!(worst < 1.0, "{worst} grey levels");
}

#[test]
fn noise_is_seeded_and_has_the_asked_level() {
    let truth = CameraModel::paper_rig();
    let mut scene = Scene::paper_view(&truth, 150.0, 22.0);
    scene.image_size = [200, 150];
    let opts = RenderOptions::default();
    let a = render(&scene, &opts).unwrap();
    assert_eq!(a.image, render(&scene, &opts).unwrap().image);
    assert_ne!(a.image, render(&scene, &RenderOptions { seed: 1, ..opts }).unwrap().image);
    let clean8 = RenderOptions { photometry: Photometry::default().noise_free(), ..opts };
    let b = render(&scene, &clean8).unwrap();
    let d: Vec<f64> = a.image.data.iter().zip(&b.image.data).map(|(x, y)| f64::from(*x) - f64::from(*y)).collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    let sd = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
    // Read noise 2 grey levels, quantised twice (1/12 each).
    assert!(mean.abs() < 0.05 && (sd - (4.0f64 + 1.0 / 6.0).sqrt()).abs() < 0.05, "{mean} {sd}");
    assert!(a.image.data.iter().all(|&v| v <= 255));
}

#[test]
fn bad_input_is_refused() {
    let truth = CameraModel::paper_rig();
    let good = Scene::paper_view(&truth, 150.0, 22.0);
    let opts = RenderOptions::default();
    let err = |s: &Scene, o: &RenderOptions| render(s, o).unwrap_err().to_string();
    let cases: Vec<(Scene, RenderOptions, &str)> = vec![
        (
            Scene {
                board: Board::Checkerboard(Checkerboard { inner_corners: [2, 5], square_mm: 1.5 }),
                ..good.clone()
            },
            opts,
            "3 x 3",
        ),
        (
            Scene {
                board: Board::Checkerboard(Checkerboard { inner_corners: [14, 12], square_mm: -1.0 }),
                ..good.clone()
            },
            opts,
            "square",
        ),
        (Scene { e_com_ma: f64::NAN, ..good.clone() }, opts, "e_com_ma"),
        (Scene { board_z_mm: f64::INFINITY, ..good.clone() }, opts, "board plane"),
        (Scene { image_size: [0, 10], ..good.clone() }, opts, "image size"),
        (Scene { margin_mm: -1.0, ..good.clone() }, opts, "margin"),
        (Scene { board_z_mm: -1000.0, ..good.clone() }, opts, "cannot be projected"),
        (
            good.clone(),
            RenderOptions { optics: Optics { focus_depth_mm: Some(-3.0), ..Optics::default() }, ..opts },
            "focus depth",
        ),
        (
            good.clone(),
            RenderOptions { optics: Optics { aperture_mm: f64::NAN, ..Optics::default() }, ..opts },
            "aperture",
        ),
        (good.clone(), RenderOptions { optics: Optics::uniform_blur(-1.0), ..opts }, "blur sigma"),
        (
            good.clone(),
            RenderOptions { photometry: Photometry { read_noise: -2.0, ..Photometry::default() }, ..opts },
            "read noise",
        ),
    ];
    for (s, o, what) in &cases {
        let e = err(s, o);
        assert!(e.contains(what), "expected '{what}' in: {e}");
        assert!(!e.contains('\n'));
    }
    // Edge-on: the camera centre in the board plane.
    let edge = Scene {
        model: CameraModel { rotation_rodrigues: [0.0, 1.2, 0.0], translation_mm: [0.0, 0.0, 0.0], ..truth },
        board_z_mm: 0.0,
        ..good
    };
    assert!(render(&edge, &opts).is_err());
}
