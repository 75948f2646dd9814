//! The sequential trace: a ray through the surfaces in order, each in its own frame.

use super::ray::Ray;
use super::surface::{Placement, Surface};
use super::OpticsError;

/// A lens at one ETL current: its surfaces in order (object space is air), the index of
/// the aperture stop among them, and the sensor plane (local z = 0).
#[derive(Debug, Clone, PartialEq)]
pub struct System {
    /// The surfaces, in the order light meets them.
    pub surfaces: Vec<Surface>,
    /// Index of the aperture stop in `surfaces`.
    pub stop: usize,
    /// The sensor's placement (its plane is local z = 0, its centre the local origin).
    pub sensor: Placement,
}

/// Whether a trace checks the surfaces' clear apertures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Apertures {
    /// A ray outside a surface's semi-diameter is blocked ([`OpticsError::Blocked`]).
    Check,
    /// Apertures ignored (the iterations of ray aiming).
    Ignore,
}

impl System {
    /// Traces `ray` (lens frame, in object space) through the first `count` surfaces:
    /// intersection and vector refraction at each, in its frame. Returns the ray after
    /// the last of them (lens frame) and where it met that surface in its local frame
    /// (x, y, mm). Errors name the surface: missed, blocked by its aperture, or total
    /// internal reflection.
    pub fn trace(&self, ray: &Ray, count: usize, apertures: Apertures) -> Result<(Ray, [f64; 2]), OpticsError> {
        let (mut ray, mut n, mut hit) = (*ray, 1.0, [0.0, 0.0]);
        for s in self.surfaces.iter().take(count) {
            let local = s.placement.to_local(&ray);
            let p = s.intersect(&local)?;
            let h2 = p[0] * p[0] + p[1] * p[1];
            if apertures == Apertures::Check && h2 > s.semi_diameter_mm * s.semi_diameter_mm {
                return Err(OpticsError::Blocked {
                    surface: s.name.clone(),
                    height_mm: h2.sqrt(),
                    semi_diameter_mm: s.semi_diameter_mm,
                });
            }
            let d = s.refract(local.direction, s.normal(p), n, s.index_after)?;
            ray = s.placement.to_global(&Ray { origin_mm: p, direction: d });
            (n, hit) = (s.index_after, [p[0], p[1]]);
        }
        Ok((ray, hit))
    }

    /// Where `ray` (object space) lands on the sensor, sensor-local (x, y), mm.
    pub fn to_sensor(&self, ray: &Ray, apertures: Apertures) -> Result<[f64; 2], OpticsError> {
        let (out, _) = self.trace(ray, self.surfaces.len(), apertures)?;
        Placement::plane_hit(&self.sensor.to_local(&out)).ok_or(OpticsError::Missed { surface: "sensor".into() })
    }

    /// Where `ray` (object space) crosses the stop plane, stop-local (x, y), mm.
    pub fn to_stop(&self, ray: &Ray, apertures: Apertures) -> Result<[f64; 2], OpticsError> {
        Ok(self.trace(ray, self.stop + 1, apertures)?.1)
    }
}
