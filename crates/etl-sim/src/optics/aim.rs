//! Ray aiming: the ray from an object point that crosses the stop at a given point, found
//! by Newton's method on the stop coordinates.
//!
//! A ray from object point P is fixed by where it crosses the aiming plane z = 0 (the
//! ETL's rim plane), q = (a, b); its stop coordinates s(q) are smooth in q. Newton's step
//! solves J dq = target - s(q) with J = ds/dq by central differences. Started from the
//! paraxial entrance pupil (the line from P to the target's paraxial image on the pupil),
//! it converges in a few steps; a ray fan reuses the chief ray's Jacobian (the chord
//! method: linear convergence, one trace a step).

use super::paraxial::EntrancePupil;
use super::ray::{Ray, V3};
use super::trace::{Apertures, System};
use super::OpticsError;

/// The distance to the target on the stop at which aiming stops, mm.
pub const AIM_TOLERANCE_MM: f64 = 1e-11;
/// The most Newton (or chord) steps.
pub const MAX_STEPS: usize = 50;
/// Central-difference step of the Jacobian, mm.
const DIFF_MM: f64 = 1e-5;

/// An aimed ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aimed {
    /// The ray in object space (from the object point).
    pub ray: Ray,
    /// Where it crosses the aiming plane z = 0, mm.
    pub aim_mm: [f64; 2],
    /// Its distance from the target on the stop, mm.
    pub residual_mm: f64,
    /// Steps taken.
    pub steps: usize,
    /// ds/dq at the solution (stop mm per aiming-plane mm).
    pub jacobian: [[f64; 2]; 2],
}

fn ray_of(object_mm: V3, q: [f64; 2]) -> Ray {
    Ray::through(object_mm, [q[0], q[1], 0.0])
}

/// The paraxial guess: the line from the object point to the target's image on the
/// entrance pupil, where it crosses z = 0. Precondition: the object in front (z < 0).
pub fn paraxial_start(object_mm: V3, target_mm: [f64; 2], pupil: &EntrancePupil, stop_radius_mm: f64) -> [f64; 2] {
    let m = pupil.radius_mm / stop_radius_mm;
    let q = [target_mm[0] * m, target_mm[1] * m, pupil.z_mm];
    let t = -object_mm[2] / (q[2] - object_mm[2]);
    [object_mm[0] + t * (q[0] - object_mm[0]), object_mm[1] + t * (q[1] - object_mm[1])]
}

fn jacobian(system: &System, object_mm: V3, q: [f64; 2]) -> Result<[[f64; 2]; 2], OpticsError> {
    let mut j = [[0.0; 2]; 2];
    for k in 0..2 {
        let (mut hi, mut lo) = (q, q);
        hi[k] += DIFF_MM;
        lo[k] -= DIFF_MM;
        let (sh, sl) = (
            system.to_stop(&ray_of(object_mm, hi), Apertures::Ignore)?,
            system.to_stop(&ray_of(object_mm, lo), Apertures::Ignore)?,
        );
        for i in 0..2 {
            j[i][k] = (sh[i] - sl[i]) / (2.0 * DIFF_MM);
        }
    }
    Ok(j)
}

fn solve2(j: &[[f64; 2]; 2], r: [f64; 2]) -> Option<[f64; 2]> {
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    let x = [(j[1][1] * r[0] - j[0][1] * r[1]) / det, (j[0][0] * r[1] - j[1][0] * r[0]) / det];
    (x[0].is_finite() && x[1].is_finite()).then_some(x)
}

/// Aims the ray from `object_mm` (lens frame, z < 0) at stop-local `target_mm`, from the
/// aiming-plane guess `start`: Newton's method, or with `chord` the chord method with
/// that fixed Jacobian. Errors: a trace error of the iterations (naming the surface), or
/// [`OpticsError::StopMissed`] when the target is not reached within [`MAX_STEPS`].
pub fn aim(
    system: &System,
    object_mm: V3,
    target_mm: [f64; 2],
    start: [f64; 2],
    chord: Option<[[f64; 2]; 2]>,
) -> Result<Aimed, OpticsError> {
    let mut q = start;
    let mut residual = f64::INFINITY;
    let stop_name = || system.surfaces[system.stop].name.clone();
    for steps in 0..=MAX_STEPS {
        let s = system.to_stop(&ray_of(object_mm, q), Apertures::Ignore)?;
        let r = [target_mm[0] - s[0], target_mm[1] - s[1]];
        residual = r[0].hypot(r[1]);
        if residual <= AIM_TOLERANCE_MM {
            let jacobian = match chord {
                Some(j) => j,
                None => jacobian(system, object_mm, q)?,
            };
            return Ok(Aimed { ray: ray_of(object_mm, q), aim_mm: q, residual_mm: residual, steps, jacobian });
        }
        let j = match chord {
            Some(j) => j,
            None => jacobian(system, object_mm, q)?,
        };
        let dq =
            solve2(&j, r).ok_or_else(|| OpticsError::StopMissed { surface: stop_name(), residual_mm: residual })?;
        q = [q[0] + dq[0], q[1] + dq[1]];
    }
    Err(OpticsError::StopMissed { surface: stop_name(), residual_mm: residual })
}
