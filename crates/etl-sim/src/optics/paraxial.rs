//! First-order optics of the centred system by the y-nu trace ([`etl_formats::optics`]):
//! focal length, back focus, entrance pupil.

use etl_formats::optics::{system_matrix, CentredSurface};

use super::OpticsError;

/// The effective focal length of `surfaces`, mm: with the system matrix M from the first
/// vertex to the last (air on both sides), f = -1 / C. Errors: an afocal system.
pub fn focal_length_mm(surfaces: &[CentredSurface]) -> Result<f64, OpticsError> {
    let (z0, z1) = ends(surfaces);
    let [_, [c, _]] = system_matrix(surfaces, z0, z1);
    if c.abs() < etl_formats::optics::MIN_POWER_PER_MM {
        return Err(OpticsError::Singular { what: "the system is afocal (no power)".into() });
    }
    Ok(-1.0 / c)
}

/// The back focal distance, mm from the last vertex: -A / C (where a ray parallel to the
/// axis crosses it). Errors: an afocal system.
pub fn back_focus_mm(surfaces: &[CentredSurface]) -> Result<f64, OpticsError> {
    let (z0, z1) = ends(surfaces);
    let [[a, _], _] = system_matrix(surfaces, z0, z1);
    Ok(a * focal_length_mm(surfaces)?)
}

fn ends(surfaces: &[CentredSurface]) -> (f64, f64) {
    (surfaces.first().map_or(0.0, |s| s.z_mm), surfaces.last().map_or(0.0, |s| s.z_mm))
}

/// The entrance pupil: the image of the stop by the surfaces in front of it, seen from
/// object space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EntrancePupil {
    /// Its position on the axis, mm (lens frame).
    pub z_mm: f64,
    /// Its radius, mm.
    pub radius_mm: f64,
}

/// The entrance pupil of `surfaces` with the stop at index `stop`. With the matrix M from
/// the plane z = 0 (in object space) to the stop, a ray (y, nu) reaches the stop at
/// A y + B nu: the chief ray (stop centre) has y / nu = -B / A and crosses the axis at
/// z = B / A. From there, M' to the stop has B' = 0 (the pupil is conjugate to the stop)
/// and a pupil height maps to A' times it on the stop: radius = stop radius / A'.
/// Errors: A = 0 (the stop imaged to infinity: a telecentric front).
pub fn entrance_pupil(surfaces: &[CentredSurface], stop: usize) -> Result<EntrancePupil, OpticsError> {
    let front = &surfaces[..stop];
    let z_stop = surfaces[stop].z_mm;
    let [[a, b], _] = system_matrix(front, 0.0, z_stop);
    if a.abs() < 1e-12 {
        return Err(OpticsError::Singular { what: "the entrance pupil is at infinity".into() });
    }
    let z_mm = b / a;
    let [[a2, _], _] = system_matrix(front, z_mm, z_stop);
    Ok(EntrancePupil { z_mm, radius_mm: surfaces[stop].semi_diameter_mm / a2 })
}
