//! How far a defocused spot's centroid leaves the ray a central model follows
//! (docs/RESULTS.md, "Where the coverage is lost: defocus"):
//! `cargo run --release -p etl-studies --example optics_defocus -- [OPTICS_FILE]`
//! (default the Cooke fixture).
//!
//! At every other procedure current, 300 points at random pixels and at depths within
//! +-35 % of the distance in focus (measured from the paraxial entrance pupil) are traced.
//! For each, the shift of its spot's centroid from its chief ray's hit is compared with
//! the same shift for the in-focus point on the same line through the pupil: what defocus
//! alone adds, in px. A blurred spot's centroid is the ray bundle's through the vignetted,
//! aberrated pupil, and the line of sight through the pupil's centre is what a central
//! model fits, so this is what no central model can follow. Printed: its quantiles, and
//! how much of it a law linear in the defocus D (dioptres) times a polynomial in the
//! normalised field (x, y, r^2 = x^2 + y^2) explains, per sensor axis, by least squares
//! with the terms D, D x, D y, D x r^2, D y r^2, D^2, D^2 x, D^2 y.

use std::path::PathBuf;

use etl_formats::optics::OpticsFile;
use etl_formats::Result;
use etl_sim::optics::OpticalRig;
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One traced point: its defocus (dpt), its normalised field (x, y), and the centroid
/// shift defocus adds (sensor axes, px).
struct Sample {
    defocus_dpt: f64,
    field: [f64; 2],
    shift_px: [f64; 2],
}

/// The samples at current `e_ma` (module docs).
fn samples_at(rig: &OpticalRig, e_ma: f64, rng: &mut ChaCha8Rng) -> Result<Vec<Sample>> {
    let at = rig.at(e_ma).map_err(|e| etl_formats::Error::invalid("optics", e.to_string()))?;
    let pupil_z = at.pupil.z_mm;
    let in_focus = rig.focus_distance_mm(e_ma)? + pupil_z;
    let pitch = rig.file.sensor.pixel_pitch_mm;
    let [w, h] = rig.file.sensor.size_px.map(|n| n as f64);
    // Pixels per unit of normalised field, from the chief ray of a point 1 mm off axis.
    let hit = |p: [f64; 3]| at.spot(p).map(|s| s.chief_mm[0]);
    let f_px = match (hit([1.0, 0.0, in_focus - pupil_z]), hit([0.0, 0.0, in_focus - pupil_z])) {
        (Ok(a), Ok(b)) => (a - b).abs() / pitch * in_focus,
        _ => return Ok(vec![]),
    };
    let mut out = vec![];
    for _ in 0..300 {
        let field = [(rng.random_range(0.0..w) - w / 2.0) / f_px, (rng.random_range(0.0..h) - h / 2.0) / f_px];
        let depth = in_focus * (1.0 + rng.random_range(-0.35..0.35));
        let point = |d: f64| [field[0] * d, field[1] * d, d - pupil_z];
        let (Ok(blurred), Ok(sharp)) = (at.spot(point(depth)), at.spot(point(in_focus))) else { continue };
        let shift = |i: usize| {
            ((blurred.centroid_mm[i] - blurred.chief_mm[i]) - (sharp.centroid_mm[i] - sharp.chief_mm[i])) / pitch
        };
        out.push(Sample { defocus_dpt: 1000.0 / depth - 1000.0 / in_focus, field, shift_px: [shift(0), shift(1)] });
    }
    Ok(out)
}

/// The fraction of the shift's mean square along sensor axis `axis` that the module docs'
/// law leaves, and the RMS shift, px.
fn unexplained(samples: &[Sample], axis: usize) -> (f64, f64) {
    let terms = |s: &Sample| {
        let (d, [x, y]) = (s.defocus_dpt, s.field);
        let r2 = x * x + y * y;
        [d, d * x, d * y, d * x * r2, d * y * r2, d * d, d * d * x, d * d * y]
    };
    let a = DMatrix::from_fn(samples.len(), 8, |i, k| terms(&samples[i])[k]);
    let b = DVector::from_fn(samples.len(), |i, _| samples[i].shift_px[axis]);
    let Ok(x) = a.clone().svd(true, true).solve(&b, 1e-12) else { return (f64::NAN, f64::NAN) };
    let residual = &b - &a * x;
    (residual.norm_squared() / b.norm_squared(), (b.norm_squared() / samples.len() as f64).sqrt())
}

fn main() -> Result<()> {
    let fixture = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics/cooke-16mm-centred.json");
    let path = std::env::args().nth(1).map_or(fixture, PathBuf::from);
    let rig = OpticalRig::new(OpticsFile::load(&path)?)?;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut samples = vec![];
    for &e in rig.file.procedure.e_com_ma.clone().iter().step_by(2) {
        samples.extend(samples_at(&rig, e, &mut rng)?);
    }
    let mut size: Vec<f64> = samples.iter().map(|s| s.shift_px[0].hypot(s.shift_px[1])).collect();
    size.sort_by(f64::total_cmp);
    let q = |p: f64| size[((p * size.len() as f64) as usize).min(size.len() - 1)];
    println!("{}: {} points, defocus up to +-35 % of the distance in focus", rig.file.name, samples.len());
    println!(
        "centroid shift added by defocus, px: median {:.3}, 68 % {:.3}, 90 % {:.3}, 99 % {:.3}",
        q(0.5),
        q(0.68),
        q(0.9),
        q(0.99)
    );
    for (axis, name) in ["x", "y"].iter().enumerate() {
        let (left, rms) = unexplained(&samples, axis);
        println!("sensor {name}: RMS {rms:.3} px; the 8-term law leaves {:.0} % of its mean square", 100.0 * left);
    }
    Ok(())
}
