//! The image of a point: the chief ray (through the stop's centre) and the centroid of a
//! ray fan spread evenly over the stop, what a corner detector sees of a defocused,
//! aberrated spot.
//!
//! The fan is hexapolar: the centre and rings k = 1..R at radius k / R of the stop with
//! 6 k rays each, every ray weighted by the stop area nearest it (the centre pi/(4 R^2);
//! ring k < R: pi/(3 R^2) a ray; the rim ring: pi (R - 1/4) / (6 R^3) a ray), so the
//! centroid is the irradiance centroid of a uniformly lit stop. Fan rays stopped by a
//! surface's aperture are vignetted: left out, their weight reported.

use super::aim::{aim, paraxial_start, Aimed};
use super::paraxial::EntrancePupil;
use super::ray::V3;
use super::trace::{Apertures, System};
use super::OpticsError;

/// The fan over the unit disc: (x, y) and weight (summing to pi).
pub fn fan(rings: usize) -> Vec<([f64; 2], f64)> {
    let r = rings as f64;
    let mut out = vec![([0.0, 0.0], std::f64::consts::PI / (4.0 * r * r))];
    for k in 1..=rings {
        let n = 6 * k;
        let w = if k < rings {
            std::f64::consts::PI / (3.0 * r * r)
        } else {
            std::f64::consts::PI * (r - 0.25) / (6.0 * r * r * r)
        };
        for j in 0..n {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
            out.push(([k as f64 / r * phi.cos(), k as f64 / r * phi.sin()], w));
        }
    }
    out
}

/// A traced image point on the sensor (sensor-local, mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spot {
    /// The chief ray's hit.
    pub chief_mm: [f64; 2],
    /// The fan's centroid.
    pub centroid_mm: [f64; 2],
    /// RMS distance of the fan's hits from the centroid.
    pub rms_mm: f64,
    /// The fraction of the fan's weight that reached the sensor (1: no vignetting).
    pub transmitted: f64,
    /// The aimed chief ray.
    pub chief: Aimed,
}

/// The spot of `object_mm` (lens frame) through `system`, with `rings` rings; `pupil`
/// (the centred system's, paraxial) starts the aiming. Errors: the chief ray's (it must
/// pass every aperture), or a fan that no ray passes.
pub fn spot(system: &System, object_mm: V3, rings: usize, pupil: &EntrancePupil) -> Result<Spot, OpticsError> {
    let stop_r = system.surfaces[system.stop].semi_diameter_mm;
    let chief = aim(system, object_mm, [0.0, 0.0], paraxial_start(object_mm, [0.0, 0.0], pupil, stop_r), None)?;
    let chief_mm = system.to_sensor(&chief.ray, Apertures::Check)?;
    let (mut sw, mut sx, mut sy, mut sxx) = (0.0, 0.0, 0.0, 0.0);
    let mut total = 0.0;
    let j = chief.jacobian;
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    for (p, w) in fan(rings) {
        total += w;
        let t = [p[0] * stop_r, p[1] * stop_r];
        // The chord start: q0 + J^-1 t.
        let dq = [(j[1][1] * t[0] - j[0][1] * t[1]) / det, (j[0][0] * t[1] - j[1][0] * t[0]) / det];
        let start = [chief.aim_mm[0] + dq[0], chief.aim_mm[1] + dq[1]];
        let hit = aim(system, object_mm, t, start, Some(j)).and_then(|a| system.to_sensor(&a.ray, Apertures::Check));
        if let Ok(h) = hit {
            sw += w;
            sx += w * h[0];
            sy += w * h[1];
            sxx += w * (h[0] * h[0] + h[1] * h[1]);
        }
    }
    if sw <= 0.0 {
        let s = &system.surfaces[system.stop];
        return Err(OpticsError::Blocked {
            surface: s.name.clone(),
            height_mm: stop_r,
            semi_diameter_mm: s.semi_diameter_mm,
        });
    }
    let centroid_mm = [sx / sw, sy / sw];
    let rms_mm = (sxx / sw - centroid_mm[0] * centroid_mm[0] - centroid_mm[1] * centroid_mm[1]).max(0.0).sqrt();
    Ok(Spot { chief_mm, centroid_mm, rms_mm, transmitted: sw / total, chief })
}
