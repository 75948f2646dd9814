//! The layout of a model's numbers as one parameter vector ([`Layout`]), of the per-view
//! variables through which a view's projection depends on them, and masks of parameters
//! held by the solvers ([`ParamMask`]).
//!
//! Parameter vector (also the names used in studies, reports and files' covariances), for
//! focal degree d and a distortion family with n_a numbers:
//! `om1 om2 om3 tx ty tz kf0x .. kf{d}x kf0y .. kf{d}y u0 v0 a1 .. a{n_a}`, and with a
//! moving centre ([`super::centre`], Eq. C1-C3) `dz1 dz2 u1 v1` after them. The paper's
//! model ([`Layout::PAPER`]: cubic, paper family, fixed centre) has 25 numbers; the largest
//! (degree 5, opencv, moving centre) has [`MAX_PARAMS`] = 39.
//!
//! Per-view variables (one current E fixed): `om1 om2 om3 tx ty tz fx fy u0 v0` and the
//! family's coefficients (`k1 p1 p2`, or `k1 k2 p1 p2 k3`): 13 or 15.

use crate::error::{count_in_range, Result};
use crate::model::{
    CameraModel, DistortionModel, OpenCvFlags, CENTRE_DZ_LEN, CENTRE_PP_LEN, MAX_COEFFICIENTS, MAX_DISTORTION_A,
    MAX_FOCAL_DEGREE,
};

/// A run of consecutive entries of a parameter vector: `start..start + len`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// Index of the first entry.
    pub start: usize,
    /// Number of entries.
    pub len: usize,
}

impl Span {
    /// One past the last entry.
    pub const fn end(&self) -> usize {
        self.start + self.len
    }

    /// Index of the span's entry `k` (k < len).
    pub const fn at(&self, k: usize) -> usize {
        self.start + k
    }

    /// Whether index `i` lies in the span.
    pub const fn contains(&self, i: usize) -> bool {
        i >= self.start && i < self.end()
    }
}

/// Numbers a moving centre adds (dz1 dz2 u1 v1).
pub const CENTRE_LEN: usize = CENTRE_DZ_LEN + 2 * CENTRE_PP_LEN;

/// The most model parameters of any layout (degree 5, opencv family, moving centre).
pub const MAX_PARAMS: usize = 6 + 2 * (MAX_FOCAL_DEGREE + 1) + 2 + MAX_DISTORTION_A + CENTRE_LEN;

/// Rodrigues rotation vector om1..om3 (every layout).
pub const ROTATION: Span = Span { start: 0, len: 3 };
/// Translation tx, ty, tz, mm (every layout).
pub const TRANSLATION: Span = Span { start: ROTATION.end(), len: 3 };

/// The layout of the parameter vector of a model with distortion family `model` and focal
/// polynomials of degree `focal_degree` (1..=5), with a fixed or a moving centre: where
/// each group of numbers lies, their names, the per-view variables. A value, so that every
/// solver is generic over it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Layout {
    model: DistortionModel,
    focal_degree: usize,
    moving_centre: bool,
}

impl Default for Layout {
    fn default() -> Self {
        Layout::PAPER
    }
}

const KF_X_NAMES: [&str; MAX_FOCAL_DEGREE + 1] = ["kf0x", "kf1x", "kf2x", "kf3x", "kf4x", "kf5x"];
const KF_Y_NAMES: [&str; MAX_FOCAL_DEGREE + 1] = ["kf0y", "kf1y", "kf2y", "kf3y", "kf4y", "kf5y"];
const A_NAMES: [&str; MAX_DISTORTION_A] =
    ["a1", "a2", "a3", "a4", "a5", "a6", "a7", "a8", "a9", "a10", "a11", "a12", "a13", "a14", "a15"];
const POSE_NAMES: [&str; 6] = ["om1", "om2", "om3", "tx", "ty", "tz"];
const PP_NAMES: [&str; 2] = ["u0", "v0"];
const CENTRE_NAMES: [&str; CENTRE_LEN] = ["dz1", "dz2", "u1", "v1"];

impl Layout {
    /// The paper's model: the cubic focal polynomial and the paper's distortion (25
    /// numbers).
    pub const PAPER: Layout = Layout { model: DistortionModel::Paper, focal_degree: 3, moving_centre: false };

    /// The layout of family `model` with focal degree `focal_degree` and a fixed centre.
    /// Errors: a degree outside 1..=5 ([`Error::OutOfRange`](crate::Error::OutOfRange)
    /// naming `focal_degree`).
    pub fn new(model: DistortionModel, focal_degree: usize) -> Result<Self> {
        let focal_degree = count_in_range(focal_degree, 1, MAX_FOCAL_DEGREE, "focal_degree")?;
        Ok(Layout { model, focal_degree, moving_centre: false })
    }

    /// This layout with a moving centre (`true`: Eq. C1-C3) or a fixed one.
    pub const fn with_moving_centre(self, moving_centre: bool) -> Self {
        Layout { moving_centre, ..self }
    }

    /// The layout of family `model`, focal degree `focal_degree` and centre, unchecked: for
    /// the table of the layouts the solvers are compiled for (`calib::dispatch`), whose
    /// degrees are 1..=5. Everywhere else use [`Layout::new`], which checks the degree.
    pub(crate) const fn of_table(model: DistortionModel, focal_degree: usize, moving_centre: bool) -> Self {
        Layout { model, focal_degree, moving_centre }
    }

    /// The layout of `model`'s numbers (its family, kf_x's degree, its centre).
    pub const fn of(model: &CameraModel) -> Self {
        Layout {
            model: model.distortion_a.model(),
            focal_degree: model.kf_x.degree(),
            moving_centre: model.centre.is_some(),
        }
    }

    /// Whether the centre moves with E (Eq. C1-C3).
    pub const fn moving_centre(&self) -> bool {
        self.moving_centre
    }

    /// The distortion family.
    pub const fn model(&self) -> DistortionModel {
        self.model
    }

    /// The degree of the focal polynomials.
    pub const fn focal_degree(&self) -> usize {
        self.focal_degree
    }

    /// Number of parameters: 6 + 2 (d + 1) + 2 + 3 n_c (+ 4 with a moving centre).
    pub const fn len(&self) -> usize {
        self.centre_principal_point().end()
    }

    /// Never empty (a pose at least); for the `len`/`is_empty` convention.
    pub const fn is_empty(&self) -> bool {
        false
    }

    /// om1..om3.
    pub const fn rotation(&self) -> Span {
        ROTATION
    }

    /// tx, ty, tz.
    pub const fn translation(&self) -> Span {
        TRANSLATION
    }

    /// kf0x..kf{d}x: fx(E) = sum kf_xi E^i (Eq. 16), px.
    pub const fn kf_x(&self) -> Span {
        Span { start: TRANSLATION.end(), len: self.focal_degree + 1 }
    }

    /// kf0y..kf{d}y.
    pub const fn kf_y(&self) -> Span {
        Span { start: self.kf_x().end(), len: self.focal_degree + 1 }
    }

    /// u0, v0, px.
    pub const fn principal_point(&self) -> Span {
        Span { start: self.kf_y().end(), len: 2 }
    }

    /// The a_i (Eq. 18 generalised): one triple per distortion coefficient.
    pub const fn distortion_a(&self) -> Span {
        Span { start: self.principal_point().end(), len: self.model.a_len() }
    }

    /// dz1, dz2 of Eq. C1 (mm / mA, mm / mA^2; empty with a fixed centre).
    pub const fn centre_dz(&self) -> Span {
        Span { start: self.distortion_a().end(), len: if self.moving_centre { CENTRE_DZ_LEN } else { 0 } }
    }

    /// u1, v1 of Eq. C3 (px / mA; empty with a fixed centre).
    pub const fn centre_principal_point(&self) -> Span {
        Span { start: self.centre_dz().end(), len: if self.moving_centre { 2 * CENTRE_PP_LEN } else { 0 } }
    }

    /// The a-triple of distortion coefficient `c` (in the family's order), (w^2, w, 1).
    pub const fn distortion_triple(&self, c: usize) -> Span {
        Span { start: self.distortion_a().start + 3 * c, len: 3 }
    }

    /// Index of kf0x.
    pub const fn kf0x(&self) -> usize {
        self.kf_x().start
    }

    /// Index of kf0y.
    pub const fn kf0y(&self) -> usize {
        self.kf_y().start
    }

    /// Index of u0 (v0 follows).
    pub const fn u0(&self) -> usize {
        self.principal_point().start
    }

    /// Index of v0.
    pub const fn v0(&self) -> usize {
        self.u0() + 1
    }

    /// The four numbers the hold-A0 option pins (kf0x, kf0y, u0, v0), ascending.
    pub const fn a0_indices(&self) -> [usize; 4] {
        [self.kf0x(), self.kf0y(), self.u0(), self.v0()]
    }

    /// The mask of the A0 numbers ([`Self::a0_indices`]).
    pub const fn a0_mask(&self) -> ParamMask {
        let [a, b, c, d] = self.a0_indices();
        ParamMask::NONE.with(a).with(b).with(c).with(d)
    }

    /// The a_i OpenCV's flags hold ([`OpenCvFlags`]: k3's triple, p1's and p2's).
    /// Errors: a flag with the paper family ([`OpenCvFlags::check`]).
    pub fn opencv_mask(&self, flags: OpenCvFlags) -> Result<ParamMask> {
        flags.check(self.model)?;
        let mut m = ParamMask::NONE;
        for c in 0..self.model.coefficient_count() {
            if flags.holds(self.model, c) {
                let t = self.distortion_triple(c);
                m = m.with(t.at(0)).with(t.at(1)).with(t.at(2));
            }
        }
        Ok(m)
    }

    /// The name of parameter `i` (`""` past the end).
    pub fn name(&self, i: usize) -> &'static str {
        let pick = |names: &[&'static str], span: Span| {
            i.checked_sub(span.start).and_then(|k| names.get(k)).copied().unwrap_or("")
        };
        if i < TRANSLATION.end() {
            POSE_NAMES.get(i).copied().unwrap_or("")
        } else if self.kf_x().contains(i) {
            pick(&KF_X_NAMES, self.kf_x())
        } else if self.kf_y().contains(i) {
            pick(&KF_Y_NAMES, self.kf_y())
        } else if self.principal_point().contains(i) {
            pick(&PP_NAMES, self.principal_point())
        } else if self.distortion_a().contains(i) {
            pick(&A_NAMES, self.distortion_a())
        } else if i < self.len() {
            pick(&CENTRE_NAMES, self.centre_dz())
        } else {
            ""
        }
    }

    /// The names of the parameters in vector order.
    pub fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        (0..self.len()).map(|i| self.name(i))
    }

    /// The index of the parameter named `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        (0..self.len()).find(|&i| self.name(i) == name)
    }

    /// Number of per-view variables: pose, fx, fy, u0, v0 and the family's coefficients.
    pub const fn reduced_len(&self) -> usize {
        R_K1 + self.model.coefficient_count()
    }

    /// The family's coefficients among the per-view variables.
    pub const fn reduced_distortion(&self) -> Span {
        Span { start: R_K1, len: self.model.coefficient_count() }
    }
}

/// The most per-view variables of any layout (opencv: 15).
pub const MAX_REDUCED: usize = R_K1 + MAX_COEFFICIENTS;
/// The pose (om, T) among the per-view variables: the same entries as in the parameter
/// vector.
pub const R_POSE: Span = Span { start: 0, len: ROTATION.len + TRANSLATION.len };
/// Index of fx among the per-view variables (fy follows, then u0, v0, the coefficients).
pub const R_FX: usize = R_POSE.end();
/// Index of fy among the per-view variables.
pub const R_FY: usize = R_FX + 1;
/// Index of u0 among the per-view variables (v0 follows).
pub const R_U0: usize = R_FY + 1;
/// Index of v0 among the per-view variables.
pub const R_V0: usize = R_U0 + 1;
/// Index of the first distortion coefficient (k1) among the per-view variables.
pub const R_K1: usize = R_V0 + 1;

/// A set of parameter indices (< 64) the solvers hold at their start values: hold-A0
/// ([`Layout::a0_mask`]) and OpenCV's flags ([`Layout::opencv_mask`]) are cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct ParamMask(u64);

impl ParamMask {
    /// No parameter held.
    pub const NONE: ParamMask = ParamMask(0);

    /// This mask with index `i` added (indices >= 64 are ignored: no layout has them).
    pub const fn with(self, i: usize) -> Self {
        if i < 64 {
            ParamMask(self.0 | (1u64 << i))
        } else {
            self
        }
    }

    /// The union of two masks.
    pub const fn union(self, other: ParamMask) -> Self {
        ParamMask(self.0 | other.0)
    }

    /// Whether index `i` is held.
    pub const fn contains(&self, i: usize) -> bool {
        i < 64 && self.0 & (1u64 << i) != 0
    }

    /// Whether no index is held.
    pub const fn is_empty(&self) -> bool {
        self.0 == 0
    }

    /// Number of held indices.
    pub const fn count(&self) -> usize {
        self.0.count_ones() as usize
    }

    /// The held indices, ascending.
    pub fn indices(&self) -> impl Iterator<Item = usize> + use<> {
        let bits = self.0;
        (0..64).filter(move |&i| bits & (1u64 << i) != 0)
    }

    /// Whether every held index lies below `len` (inside a layout of `len` numbers).
    pub const fn fits(&self, len: usize) -> bool {
        len >= 64 || self.0 >> len == 0
    }
}

impl core::ops::BitOr for ParamMask {
    type Output = ParamMask;
    fn bitor(self, rhs: ParamMask) -> ParamMask {
        self.union(rhs)
    }
}

// Here rather than beside the model's fields: the layout is this module's, and the model
// (`super::projection`) does not depend on it.
impl CameraModel {
    /// The layout of this model's parameter vector (family and focal degree).
    pub fn layout(&self) -> Layout {
        Layout::of(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spans tile the vector in the documented order, for every layout; the names
    /// agree; the paper's layout is today's 25 numbers.
    #[test]
    fn spans_tile_the_vectors_in_name_order() {
        for model in DistortionModel::ALL {
            for d in 1..=MAX_FOCAL_DEGREE {
                for moving in [false, true] {
                    let l = Layout::new(model, d).unwrap().with_moving_centre(moving);
                    let spans = [
                        l.rotation(),
                        l.translation(),
                        l.kf_x(),
                        l.kf_y(),
                        l.principal_point(),
                        l.distortion_a(),
                        l.centre_dz(),
                        l.centre_principal_point(),
                    ];
                    let mut next = 0;
                    for s in spans {
                        assert_eq!(s.start, next);
                        next = s.end();
                    }
                    assert_eq!(next, l.len());
                    assert!(l.len() <= MAX_PARAMS);
                    assert_eq!(l.name(l.kf0x()), "kf0x");
                    assert_eq!(l.name(l.kf0y()), "kf0y");
                    assert_eq!(l.name(l.u0()), "u0");
                    assert_eq!(l.name(l.v0()), "v0");
                    assert_eq!(l.name(l.distortion_a().start), "a1");
                    let last = match (moving, model) {
                        (true, _) => "v1",
                        (false, DistortionModel::Paper) => "a9",
                        (false, DistortionModel::OpenCv) => "a15",
                    };
                    assert_eq!(l.name(l.len() - 1), last);
                    assert_eq!(l.name(l.len()), "");
                    assert_eq!(l.names().filter(|n| n.is_empty()).count(), 0);
                    assert_eq!(l.index_of("v0"), Some(l.v0()));
                    assert!(l.a0_mask().fits(l.len()) && l.a0_mask().count() == 4);
                    assert!(l.reduced_len() <= MAX_REDUCED);
                    assert_eq!(l.len(), Layout::new(model, d).unwrap().len() + if moving { CENTRE_LEN } else { 0 });
                }
            }
        }
        let p = Layout::PAPER;
        assert_eq!(p.len(), 25);
        assert_eq!((p.kf0x(), p.kf0y(), p.u0(), p.v0(), p.distortion_a().start), (6, 10, 14, 15, 16));
        assert_eq!((R_FX, R_FY, R_U0, R_V0, R_K1, p.reduced_len()), (6, 7, 8, 9, 10, 13));
        assert_eq!(Layout::new(DistortionModel::OpenCv, 5).unwrap().with_moving_centre(true).len(), MAX_PARAMS);
        let c = Layout::PAPER.with_moving_centre(true);
        assert_eq!((c.len(), c.centre_dz().start, c.index_of("dz1"), c.index_of("v1")), (29, 25, Some(25), Some(28)));
        assert!(Layout::new(DistortionModel::Paper, 0).is_err() && Layout::new(DistortionModel::Paper, 6).is_err());
    }

    #[test]
    fn masks() {
        let l = Layout::new(DistortionModel::OpenCv, 3).unwrap();
        let k3 = l.opencv_mask(OpenCvFlags { fix_k3: true, zero_tangent: false }).unwrap();
        let t4 = l.distortion_triple(4);
        assert!(k3.count() == 3 && (0..3).all(|k| k3.contains(t4.at(k))));
        let t = l.opencv_mask(OpenCvFlags { fix_k3: false, zero_tangent: true }).unwrap();
        assert_eq!(t.count(), 6);
        assert!(t.contains(l.distortion_triple(2).start) && t.contains(l.distortion_triple(3).at(2)));
        assert!(Layout::PAPER.opencv_mask(OpenCvFlags { fix_k3: true, zero_tangent: false }).is_err());
        let a0: [usize; 4] = Layout::PAPER.a0_indices();
        assert!(Layout::PAPER.a0_mask().indices().eq(a0.into_iter()));
    }
}
