//! A refracting surface in its own frame: a sphere of curvature c (or a plane, c = 0) with
//! its vertex at the local origin and its axis along local z, placed in the lens frame by
//! a rotation and a vertex position (decentre and tilt are placements).

use super::ray::{add, dot, mul, mul_t, scale, sub, Ray, M3, V3};
use super::OpticsError;

/// Where a surface (or the sensor) stands: global = origin + R local.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// The local origin in the lens frame, mm.
    pub origin_mm: V3,
    /// Local to lens frame.
    pub rotation: M3,
}

impl Placement {
    /// A ray in local coordinates.
    pub fn to_local(&self, ray: &Ray) -> Ray {
        Ray {
            origin_mm: mul_t(&self.rotation, sub(ray.origin_mm, self.origin_mm)),
            direction: mul_t(&self.rotation, ray.direction),
        }
    }

    /// A local ray in lens coordinates.
    pub fn to_global(&self, ray: &Ray) -> Ray {
        Ray {
            origin_mm: add(self.origin_mm, mul(&self.rotation, ray.origin_mm)),
            direction: mul(&self.rotation, ray.direction),
        }
    }

    /// Where a local ray crosses the local plane z = 0 (x, y, mm); `None` if parallel to it.
    pub fn plane_hit(local: &Ray) -> Option<[f64; 2]> {
        let t = -local.origin_mm[2] / local.direction[2];
        let p = local.at(t);
        t.is_finite().then_some([p[0], p[1]])
    }
}

/// A refracting surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Its name in the optics file (errors name it).
    pub name: String,
    /// Curvature 1/R, 1/mm (0: a plane).
    pub curvature_per_mm: f64,
    /// Refractive index after the surface.
    pub index_after: f64,
    /// Clear radius, mm.
    pub semi_diameter_mm: f64,
    /// Its placement in the lens frame.
    pub placement: Placement,
}

impl Surface {
    /// The local point where `local` (a ray in this surface's frame, travelling towards
    /// +z) meets the surface c (x^2 + y^2 + z^2) - 2 z = 0, by Welford's form without
    /// cancellation: transfer to the vertex plane z = 0, point p0, then the distance
    /// s = C / (B + sqrt(B^2 - c C)) with B = d_z - c (d . p0), C = c |p0|^2 (the root
    /// nearest the vertex; exact for a plane, c = 0). Errors: the ray misses the sphere.
    pub fn intersect(&self, local: &Ray) -> Result<V3, OpticsError> {
        let missed = || OpticsError::Missed { surface: self.name.clone() };
        let d = local.direction;
        let t0 = -local.origin_mm[2] / d[2];
        if !t0.is_finite() {
            return Err(missed());
        }
        let p0 = local.at(t0);
        let c = self.curvature_per_mm;
        let b = d[2] - c * dot(d, p0);
        let cc = c * dot(p0, p0);
        let disc = b * b - c * cc;
        if !(disc >= 0.0) || b <= 0.0 {
            return Err(missed());
        }
        let s = cc / (b + disc.sqrt());
        Ok(add(p0, scale(d, s)))
    }

    /// The unit normal at local point `p` of the surface: (-c x, -c y, 1 - c z), which
    /// has unit length on the sphere.
    pub fn normal(&self, p: V3) -> V3 {
        let c = self.curvature_per_mm;
        [-c * p[0], -c * p[1], 1.0 - c * p[2]]
    }

    /// Refracts unit direction `d` at unit normal `n` from index `n1` to `n2` (vector
    /// Snell's law): with mu = n1 / n2 and cos i = d . n (n turned to the side d goes),
    /// d' = mu d + (sqrt(1 - mu^2 (1 - cos^2 i)) - mu cos i) n. Errors: total internal
    /// reflection (the root's argument negative).
    pub fn refract(&self, d: V3, n: V3, n1: f64, n2: f64) -> Result<V3, OpticsError> {
        let mut cos_i = dot(d, n);
        let n = if cos_i < 0.0 {
            cos_i = -cos_i;
            scale(n, -1.0)
        } else {
            n
        };
        let mu = n1 / n2;
        let k = 1.0 - mu * mu * (1.0 - cos_i * cos_i);
        if k < 0.0 {
            return Err(OpticsError::TotalInternalReflection { surface: self.name.clone() });
        }
        Ok(add(scale(d, mu), scale(n, k.sqrt() - mu * cos_i)))
    }
}
