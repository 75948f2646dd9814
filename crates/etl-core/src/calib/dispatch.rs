//! From a [`super::params::Layout`] value to the sizes the solvers are compiled for.
//!
//! The solvers keep their matrices on the stack at the exact size of the parameter vector
//! (const generics: no allocation, and the paper's 25 numbers solved exactly as before the
//! families existed). [`with_layout!`] runs a body with `N` (the layout's length) and `P`
//! (the padded row length of a view's reduced normal equations: the per-view variables but
//! u0, v0, rounded up to a multiple of 4 so that their accumulation vectorises) bound as
//! constants, with `O` the number of those per-view variables, for each of the ten
//! layouts.

/// Runs `$body` (an expression of type `Result<_>`) with the constants `$n` = the layout's
/// length, `$o` = the per-view variables other than u0, v0 (11 for the paper family, 13
/// for opencv) and `$p` = their row length padded to a multiple of 4 (12, 16).
macro_rules! with_layout {
    ($layout:expr, $n:ident, $o:ident, $p:ident, $body:expr) => {{
        use $crate::model::DistortionModel::{OpenCv, Paper};
        match ($layout.model(), $layout.focal_degree()) {
            (Paper, 1) => with_layout!(@ $n = 21, $o = 11, $p = 12, $body),
            (Paper, 2) => with_layout!(@ $n = 23, $o = 11, $p = 12, $body),
            (Paper, 3) => with_layout!(@ $n = 25, $o = 11, $p = 12, $body),
            (Paper, 4) => with_layout!(@ $n = 27, $o = 11, $p = 12, $body),
            (Paper, 5) => with_layout!(@ $n = 29, $o = 11, $p = 12, $body),
            (OpenCv, 1) => with_layout!(@ $n = 27, $o = 13, $p = 16, $body),
            (OpenCv, 2) => with_layout!(@ $n = 29, $o = 13, $p = 16, $body),
            (OpenCv, 3) => with_layout!(@ $n = 31, $o = 13, $p = 16, $body),
            (OpenCv, 4) => with_layout!(@ $n = 33, $o = 13, $p = 16, $body),
            (OpenCv, 5) => with_layout!(@ $n = 35, $o = 13, $p = 16, $body),
            _ => Err($crate::Error::InvalidArgument { what: "focal degree outside 1..=5" }),
        }
    }};
    (@ $n:ident = $nv:literal, $o:ident = $ov:literal, $p:ident = $pv:literal, $body:expr) => {{
        const $n: usize = $nv;
        const $o: usize = $ov;
        const $p: usize = $pv;
        $body
    }};
}

pub(crate) use with_layout;

#[cfg(test)]
mod tests {
    use crate::calib::params::Layout;
    use crate::model::{DistortionModel, MAX_FOCAL_DEGREE};
    use crate::Result;

    /// Every layout gets its own length, the count of its per-view variables but u0, v0,
    /// and a padded row that holds them.
    #[test]
    fn every_layout_maps_to_its_sizes() {
        for model in DistortionModel::ALL {
            for d in 1..=MAX_FOCAL_DEGREE {
                let l = Layout::new(model, d).unwrap();
                let (n, o, p): (usize, usize, usize) = with_layout!(l, N, O, P, Result::Ok((N, O, P))).unwrap();
                assert_eq!(n, l.len());
                assert_eq!(o, l.reduced_len() - 2);
                assert!(p >= o && p % 4 == 0 && p < o + 4, "{l:?}");
            }
        }
    }
}
