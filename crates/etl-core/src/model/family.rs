//! The distortion families of the ETL camera model, and the coefficients of a family as
//! functions of the focal length (Eq. 18 generalised).
//!
//! | family | coefficients at one current | acting on | numbers a_i |
//! |---|---|---|---|
//! | `paper` | k1, p1, p2 (Eq. 17, Weng's decentering) | centred pixels u, v | 9 |
//! | `opencv` | k1, k2, p1, p2, k3 (OpenCV's signs and order) | normalised x = u / fx, y = v / fy | 15 |
//!
//! In both, coefficient c is a quadratic in w = 1 / f_mean, f_mean = (fx + fy) / 2
//! (Eq. 18): c(w) = a_{3c+1} w^2 + a_{3c+2} w + a_{3c+3}, so the a_i come in triples in
//! the order of the coefficients, each triple ordered (w^2, w, 1).

use serde::{Deserialize, Serialize};

use crate::error::{all_finite, Error, Result};

/// Most distortion coefficients of a family at one current (OpenCV's five).
pub const MAX_COEFFICIENTS: usize = 5;
/// Most numbers a_i of a family (five quadratics in w).
pub const MAX_DISTORTION_A: usize = 3 * MAX_COEFFICIENTS;

/// Which distortion model the ETL camera model uses (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DistortionModel {
    /// The paper's Eq. 17: k1, p1, p2 in centred pixel coordinates (docs/METHOD.md).
    #[default]
    Paper,
    /// OpenCV's model (`cv2.projectPoints`): k1, k2, p1, p2, k3 in normalised coordinates.
    #[serde(rename = "opencv")]
    OpenCv,
}

const PAPER_NAMES: [&str; 3] = ["k1", "p1", "p2"];
const OPENCV_NAMES: [&str; 5] = ["k1", "k2", "p1", "p2", "k3"];

impl DistortionModel {
    /// Every family, the default first.
    pub const ALL: [DistortionModel; 2] = [DistortionModel::Paper, DistortionModel::OpenCv];

    /// The name used in files, on the command line and in Python: `"paper"`, `"opencv"`.
    pub const fn name(self) -> &'static str {
        match self {
            DistortionModel::Paper => "paper",
            DistortionModel::OpenCv => "opencv",
        }
    }

    /// The family of a name ([`Self::name`]); `None` for any other string.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Number of distortion coefficients at one current: 3 (paper) or 5 (opencv).
    pub const fn coefficient_count(self) -> usize {
        match self {
            DistortionModel::Paper => PAPER_NAMES.len(),
            DistortionModel::OpenCv => OPENCV_NAMES.len(),
        }
    }

    /// Number of a_i: three per coefficient (Eq. 18), 9 or 15.
    pub const fn a_len(self) -> usize {
        3 * self.coefficient_count()
    }

    /// The coefficients' names in their order: `k1 p1 p2` or `k1 k2 p1 p2 k3`.
    pub const fn coefficient_names(self) -> &'static [&'static str] {
        match self {
            DistortionModel::Paper => &PAPER_NAMES,
            DistortionModel::OpenCv => &OPENCV_NAMES,
        }
    }

    /// Index of k3 among the coefficients (opencv only).
    pub const fn k3_index(self) -> Option<usize> {
        match self {
            DistortionModel::Paper => None,
            DistortionModel::OpenCv => Some(4),
        }
    }

    /// Indices of the tangential (decentering) coefficients p1, p2.
    pub const fn tangential_indices(self) -> [usize; 2] {
        match self {
            DistortionModel::Paper => [1, 2],
            DistortionModel::OpenCv => [2, 3],
        }
    }
}

/// OpenCV's options on its distortion model, as `cv2.calibrateCamera`'s flags: hold k3 at
/// its start (`CALIB_FIX_K3`; the start is 0 unless given) and hold p1 = p2 = 0
/// (`CALIB_ZERO_TANGENT_DIST`). Meaningful for the `opencv` family only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct OpenCvFlags {
    /// Hold k3 (its three a_i) at its start value, 0 from the initialisers.
    pub fix_k3: bool,
    /// Hold p1 and p2 (their six a_i) at zero.
    pub zero_tangent: bool,
}

impl OpenCvFlags {
    /// Every coefficient free.
    pub const NONE: OpenCvFlags = OpenCvFlags { fix_k3: false, zero_tangent: false };

    /// Whether any flag is set.
    pub const fn any(&self) -> bool {
        self.fix_k3 || self.zero_tangent
    }

    /// Checks the flags against a family: they are OpenCV's and mean nothing for `paper`.
    /// Errors: a flag set with the paper family ([`Error::InvalidArgument`] naming it).
    pub fn check(&self, model: DistortionModel) -> Result<()> {
        if model == DistortionModel::OpenCv {
            return Ok(());
        }
        if self.fix_k3 {
            return Err(Error::InvalidArgument { what: "fix_k3 needs the opencv distortion model (paper has no k3)" });
        }
        if self.zero_tangent {
            return Err(Error::InvalidArgument { what: "zero_tangent needs the opencv distortion model" });
        }
        Ok(())
    }

    /// Whether coefficient `c` of the opencv family is held by these flags.
    pub const fn holds(&self, model: DistortionModel, c: usize) -> bool {
        let k3 = match model.k3_index() {
            Some(i) => self.fix_k3 && c == i,
            None => false,
        };
        let [t1, t2] = model.tangential_indices();
        let tangent = matches!(model, DistortionModel::OpenCv) && self.zero_tangent && (c == t1 || c == t2);
        k3 || tangent
    }
}

/// The numbers a_i of a distortion family (Eq. 18 generalised): for each coefficient, in
/// the family's order, its quadratic in w = 1 / f_mean as (w^2, w, 1). Fixed capacity
/// ([`MAX_DISTORTION_A`]); the entries past the family's [`DistortionModel::a_len`] are
/// zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistortionA {
    model: DistortionModel,
    a: [f64; MAX_DISTORTION_A],
}

/// As the list of the family's numbers (the form of the calibration file).
impl Serialize for DistortionA {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> core::result::Result<S::Ok, S::Error> {
        serializer.collect_seq(self.as_slice())
    }
}

impl Default for DistortionA {
    fn default() -> Self {
        Self::zero(DistortionModel::Paper)
    }
}

impl DistortionA {
    /// The paper's a1..a9 (k1, p1, p2).
    pub const fn paper(a: [f64; 9]) -> Self {
        let mut all = [0.0; MAX_DISTORTION_A];
        let mut i = 0;
        while i < 9 {
            all[i] = a[i];
            i += 1;
        }
        DistortionA { model: DistortionModel::Paper, a: all }
    }

    /// OpenCV's family: a1..a15 (k1, k2, p1, p2, k3, each as (w^2, w, 1)).
    pub const fn opencv(a: [f64; 15]) -> Self {
        DistortionA { model: DistortionModel::OpenCv, a }
    }

    /// All zero (no distortion) in `model`.
    pub const fn zero(model: DistortionModel) -> Self {
        DistortionA { model, a: [0.0; MAX_DISTORTION_A] }
    }

    /// The numbers of `model` from a slice. Errors: a slice that is not the family's
    /// length ([`Error::InvalidArgument`] naming `distortion_a`).
    pub fn new(model: DistortionModel, a: &[f64]) -> Result<Self> {
        if a.len() != model.a_len() {
            return Err(match model {
                DistortionModel::Paper => {
                    Error::InvalidArgument { what: "distortion_a must have 9 numbers for the paper model" }
                }
                DistortionModel::OpenCv => {
                    Error::InvalidArgument { what: "distortion_a must have 15 numbers for the opencv model" }
                }
            });
        }
        let mut out = Self::zero(model);
        for (slot, &v) in out.a.iter_mut().zip(a) {
            *slot = v;
        }
        Ok(out)
    }

    /// The family.
    pub const fn model(&self) -> DistortionModel {
        self.model
    }

    /// The family's numbers ([`DistortionModel::a_len`] of them).
    pub fn as_slice(&self) -> &[f64] {
        self.a.get(..self.model.a_len()).unwrap_or(&self.a)
    }

    /// The family's numbers, mutable.
    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        let n = self.model.a_len();
        let (head, _) = self.a.split_at_mut(n.min(MAX_DISTORTION_A));
        head
    }

    /// The numbers a_i at capacity (zeros past the family's length).
    pub const fn padded(&self) -> &[f64; MAX_DISTORTION_A] {
        &self.a
    }

    /// Checks that every number is finite (naming `distortion_a`).
    pub fn validate(&self) -> Result<()> {
        all_finite(self.as_slice(), "distortion_a")
    }

    /// The coefficients at mean focal length `f_mean_px` (Eq. 18): with w = 1 / f_mean,
    /// c = a_{3c+1} w^2 + a_{3c+2} w + a_{3c+3}, in the family's order (zeros past its
    /// [`DistortionModel::coefficient_count`]).
    #[inline(always)]
    pub fn coefficients_at(&self, f_mean_px: f64) -> [f64; MAX_COEFFICIENTS] {
        let w = 1.0 / f_mean_px;
        let w2 = w * w;
        let a = &self.a;
        let q = |c: usize| a[3 * c] * w2 + a[3 * c + 1] * w + a[3 * c + 2];
        match self.model {
            DistortionModel::Paper => [q(0), q(1), q(2), 0.0, 0.0],
            DistortionModel::OpenCv => [q(0), q(1), q(2), q(3), q(4)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_lengths() {
        for m in DistortionModel::ALL {
            assert_eq!(DistortionModel::from_name(m.name()), Some(m));
            assert_eq!(m.coefficient_names().len(), m.coefficient_count());
            assert_eq!(DistortionA::zero(m).as_slice().len(), m.a_len());
        }
        assert_eq!(DistortionModel::from_name("brown"), None);
        assert_eq!((DistortionModel::Paper.a_len(), DistortionModel::OpenCv.a_len()), (9, 15));
    }

    #[test]
    fn wrong_lengths_name_the_field() {
        let e = DistortionA::new(DistortionModel::OpenCv, &[0.0; 9]).unwrap_err();
        assert!(matches!(e, Error::InvalidArgument { what } if what.starts_with("distortion_a")), "{e:?}");
        assert!(DistortionA::new(DistortionModel::Paper, &[0.0; 15]).is_err());
        assert_eq!(DistortionA::new(DistortionModel::Paper, &[1.0; 9]).unwrap().as_slice(), &[1.0; 9]);
    }

    #[test]
    fn flags_belong_to_opencv() {
        let k3 = OpenCvFlags { fix_k3: true, zero_tangent: false };
        assert!(k3.check(DistortionModel::Paper).is_err());
        assert!(k3.check(DistortionModel::OpenCv).is_ok());
        assert!(k3.holds(DistortionModel::OpenCv, 4) && !k3.holds(DistortionModel::OpenCv, 3));
        let t = OpenCvFlags { fix_k3: false, zero_tangent: true };
        assert!(t.holds(DistortionModel::OpenCv, 2) && t.holds(DistortionModel::OpenCv, 3));
        assert!(!t.holds(DistortionModel::Paper, 1));
    }
}
