//! The layout of the 25 numbers of the model as one parameter vector, and of the 13
//! per-view variables through which a view's projection depends on them.
//!
//! Parameter vector (also the names used in studies and reports):
//! `om1 om2 om3 tx ty tz kf0x kf1x kf2x kf3x kf0y kf1y kf2y kf3y u0 v0 a1 .. a9`.
//!
//! Per-view variables (one current E fixed): `om1 om2 om3 tx ty tz fx fy u0 v0 k1 p1 p2`.

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
}

/// Number of model parameters.
pub const PARAMS: usize = 25;

/// Rodrigues rotation vector om1..om3.
pub const ROTATION: Span = Span { start: 0, len: 3 };
/// Translation tx, ty, tz, mm.
pub const TRANSLATION: Span = Span { start: ROTATION.end(), len: 3 };
/// kf0x..kf3x: fx(E) = sum kf_xi E^i (Eq. 16), px.
pub const KF_X: Span = Span { start: TRANSLATION.end(), len: 4 };
/// kf0y..kf3y: fy(E), px.
pub const KF_Y: Span = Span { start: KF_X.end(), len: 4 };
/// Principal point u0, v0, px.
pub const PRINCIPAL_POINT: Span = Span { start: KF_Y.end(), len: 2 };
/// a1..a9 (Eq. 18): k1, p1, p2 each a quadratic in w = 2 / (fx + fy).
pub const DISTORTION_A: Span = Span { start: PRINCIPAL_POINT.end(), len: 9 };
/// The three a-triples of [`DISTORTION_A`], one per distortion coefficient (k1, p1, p2),
/// each in the order (w^2, w, 1).
pub const DISTORTION_TRIPLES: [Span; 3] = [
    Span { start: DISTORTION_A.start, len: 3 },
    Span { start: DISTORTION_A.start + 3, len: 3 },
    Span { start: DISTORTION_A.start + 6, len: 3 },
];

/// Index of kf0x.
pub const KF0X: usize = KF_X.start;
/// Index of kf0y.
pub const KF0Y: usize = KF_Y.start;
/// Index of u0 (v0 follows).
pub const U0: usize = PRINCIPAL_POINT.start;
/// Index of v0.
pub const V0: usize = U0 + 1;
/// The four numbers the hold-A0 option pins (kf0x, kf0y, u0, v0).
pub const A0_INDICES: [usize; 4] = [KF0X, KF0Y, U0, V0];

/// Names of the 25 parameters, in vector order.
pub const PARAM_NAMES: [&str; PARAMS] = [
    "om1", "om2", "om3", "tx", "ty", "tz", "kf0x", "kf1x", "kf2x", "kf3x", "kf0y", "kf1y", "kf2y", "kf3y", "u0", "v0",
    "a1", "a2", "a3", "a4", "a5", "a6", "a7", "a8", "a9",
];

/// Number of per-view variables: at one current the pixel depends on the 25 numbers only
/// through om1..om3, tx..tz, fx, fy, u0, v0, k1, p1, p2 (Eq. 13-18 with E fixed).
pub const REDUCED: usize = 13;
/// The pose (om, T) among the per-view variables: the same entries as in the parameter
/// vector.
pub const R_POSE: Span = Span { start: 0, len: ROTATION.len + TRANSLATION.len };
/// Index of fx among the per-view variables (fy follows, then u0, v0, k1, p1, p2).
pub const R_FX: usize = R_POSE.end();
/// Index of fy among the per-view variables.
pub const R_FY: usize = R_FX + 1;
/// Index of u0 among the per-view variables (v0 follows).
pub const R_U0: usize = R_FY + 1;
/// Index of v0 among the per-view variables.
pub const R_V0: usize = R_U0 + 1;
/// Index of k1 among the per-view variables (p1, p2 follow).
pub const R_K1: usize = R_V0 + 1;
/// k1, p1, p2 among the per-view variables.
pub const R_DISTORTION: Span = Span { start: R_K1, len: 3 };

#[cfg(test)]
mod tests {
    use super::*;

    /// The spans tile both vectors in the documented order, and the names agree.
    #[test]
    fn spans_tile_the_vectors_in_name_order() {
        let spans = [ROTATION, TRANSLATION, KF_X, KF_Y, PRINCIPAL_POINT, DISTORTION_A];
        let mut next = 0;
        for s in spans {
            assert_eq!(s.start, next);
            next = s.end();
        }
        assert_eq!(next, PARAMS);
        assert_eq!(PARAM_NAMES[KF0X], "kf0x");
        assert_eq!(PARAM_NAMES[KF0Y], "kf0y");
        assert_eq!(PARAM_NAMES[U0], "u0");
        assert_eq!(PARAM_NAMES[V0], "v0");
        assert_eq!(PARAM_NAMES[DISTORTION_A.start], "a1");
        assert_eq!(PARAM_NAMES[DISTORTION_TRIPLES[2].at(2)], "a9");
        assert_eq!((R_FX, R_FY, R_U0, R_V0, R_K1, R_DISTORTION.end()), (6, 7, 8, 9, 10, REDUCED));
    }
}
