//! Rays and the little vector algebra the tracer needs (f64, mm).

/// A point or a direction, mm (x, y, z).
pub type V3 = [f64; 3];
/// A 3 x 3 rotation, row major.
pub type M3 = [[f64; 3]; 3];

/// A ray: a point on it and its unit direction (light travels along `direction`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// A point of the ray, mm.
    pub origin_mm: V3,
    /// Unit direction.
    pub direction: V3,
}

impl Ray {
    /// The ray from `from_mm` towards `to_mm`. Precondition: the points differ.
    pub fn through(from_mm: V3, to_mm: V3) -> Ray {
        Ray { origin_mm: from_mm, direction: normalize(sub(to_mm, from_mm)) }
    }

    /// The point `t` mm along the ray.
    pub fn at(&self, t_mm: f64) -> V3 {
        add(self.origin_mm, scale(self.direction, t_mm))
    }
}

/// a + b.
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// a - b.
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// s a.
pub fn scale(a: V3, s: f64) -> V3 {
    [s * a[0], s * a[1], s * a[2]]
}

/// a . b.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a / |a|.
pub fn normalize(a: V3) -> V3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}

/// M a.
pub fn mul(m: &M3, a: V3) -> V3 {
    [dot(m[0], a), dot(m[1], a), dot(m[2], a)]
}

/// M^T a (the inverse of a rotation).
pub fn mul_t(m: &M3, a: V3) -> V3 {
    [
        m[0][0] * a[0] + m[1][0] * a[1] + m[2][0] * a[2],
        m[0][1] * a[0] + m[1][1] * a[1] + m[2][1] * a[2],
        m[0][2] * a[0] + m[1][2] * a[1] + m[2][2] * a[2],
    ]
}

/// The identity.
pub const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The rotation by `ax` about x, then by `ay` about y (radians): R = Ry(ay) Rx(ax).
pub fn tilt(ax: f64, ay: f64) -> M3 {
    let (sx, cx) = ax.sin_cos();
    let (sy, cy) = ay.sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
    let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| ry[i][k] * rx[k][j]).sum();
        }
    }
    r
}
