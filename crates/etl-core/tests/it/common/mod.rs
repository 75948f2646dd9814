//! What the integration tests share: the paper rig's views (docs/METHOD.md) with its noise
//! model, for any true model.
#![allow(dead_code)] // each test file uses its part

use etl_core::calib::{Point, View, A0};
use etl_core::model::CameraModel;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

pub const Z_W: [f64; 15] = [75.0, 60.0, 48.0, 43.0, 35.0, 31.0, 28.0, 22.0, 19.0, 16.0, 13.0, 10.0, 8.0, 4.0, 2.0];
pub const E_COM: [f64; 15] =
    [80.0, 90.0, 100.0, 110.0, 120.0, 130.0, 140.0, 150.0, 160.0, 170.0, 180.0, 190.0, 200.0, 210.0, 225.0];

pub struct Noise {
    pub xy_mm: f64,
    pub z_mm: f64,
    pub e_ma: f64,
    pub px: f64,
    pub kf0_rel: f64,
    pub pp_px: f64,
}

pub const NO_NOISE: Noise = Noise { xy_mm: 0.0, z_mm: 0.0, e_ma: 0.0, px: 0.0, kf0_rel: 0.0, pp_px: 0.0 };
pub const PAPER_NOISE: Noise = Noise { xy_mm: 0.001, z_mm: 0.010, e_ma: 0.4, px: 0.2, kf0_rel: 0.003, pp_px: 1.0 };

/// The paper rig's views: recorded (noisy) world points, currents and observed pixels, and
/// the A0 a lens-off calibration would give.
pub fn paper_rig(noise: &Noise, seed: u64) -> (Vec<Vec<Point>>, Vec<f64>, A0) {
    paper_rig_of(&CameraModel::paper_rig(), noise, seed)
}

/// [`paper_rig`] seen through another true model `cam` (its views, the same boards and
/// stage positions).
pub fn paper_rig_of(cam: &CameraModel, noise: &Noise, seed: u64) -> (Vec<Vec<Point>>, Vec<f64>, A0) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let g = |s: f64, rng: &mut ChaCha8Rng| if s > 0.0 { Normal::new(0.0, s).unwrap().sample(rng) } else { 0.0 };
    let mut views = vec![];
    let mut currents = vec![];
    for (&z, &e) in Z_W.iter().zip(&E_COM) {
        // The true stage position and current differ from the recorded ones.
        let (dz, de) = (g(noise.z_mm, &mut rng), g(noise.e_ma, &mut rng));
        let mut pts = vec![];
        for j in 0..12 {
            for i in 0..14 {
                let recorded = [1.5 * i as f64, 1.5 * j as f64, z];
                let truth = [recorded[0] + g(noise.xy_mm, &mut rng), recorded[1] + g(noise.xy_mm, &mut rng), z + dz];
                let clean = cam.project(recorded, e).unwrap();
                if !(0.0..=1935.0).contains(&clean[0]) || !(0.0..=1457.0).contains(&clean[1]) {
                    continue;
                }
                let px = cam.project(truth, e + de).unwrap();
                pts.push(Point {
                    world_mm: recorded,
                    pixel: [px[0] + g(noise.px, &mut rng), px[1] + g(noise.px, &mut rng)],
                });
            }
        }
        views.push(pts);
        currents.push(e);
    }
    let a0 = A0 {
        kf0x: cam.kf_x.coefficients()[0] * (1.0 + g(noise.kf0_rel, &mut rng)),
        kf0y: cam.kf_y.coefficients()[0] * (1.0 + g(noise.kf0_rel, &mut rng)),
        u0: cam.principal_point[0] + g(noise.pp_px, &mut rng),
        v0: cam.principal_point[1] + g(noise.pp_px, &mut rng),
    };
    (views, currents, a0)
}

pub fn as_views<'a>(pts: &'a [Vec<Point>], e: &[f64]) -> Vec<View<'a>> {
    pts.iter().zip(e).map(|(p, &e)| View { e_com_ma: e, points: p }).collect()
}
