//! From a [`super::params::Layout`] value to the sizes the solvers are compiled for.
//!
//! The solvers keep their matrices on the stack at the exact size of the parameter vector
//! (const generics: no allocation, and the paper's 25 numbers solved exactly as before the
//! families existed). [`with_layout!`] runs a body with `N` (the layout's length) and `P`
//! (the padded row length of a view's reduced normal equations: the per-view variables but
//! u0, v0, rounded up to a multiple of 4 so that their accumulation vectorises) bound as
//! constants, for each of the ten layouts.

/// Runs `$body` (an expression of type `Result<_>`) with the constants `$n` = the layout's
/// length and `$p` = the padded per-view row length (12 for the paper family's 11 other
/// variables, 16 for opencv's 13).
macro_rules! with_layout {
    ($layout:expr, $n:ident, $p:ident, $body:expr) => {{
        use $crate::model::DistortionModel::{OpenCv, Paper};
        match ($layout.model(), $layout.focal_degree()) {
            (Paper, 1) => with_layout!(@ $n = 21, $p = 12, $body),
            (Paper, 2) => with_layout!(@ $n = 23, $p = 12, $body),
            (Paper, 3) => with_layout!(@ $n = 25, $p = 12, $body),
            (Paper, 4) => with_layout!(@ $n = 27, $p = 12, $body),
            (Paper, 5) => with_layout!(@ $n = 29, $p = 12, $body),
            (OpenCv, 1) => with_layout!(@ $n = 27, $p = 16, $body),
            (OpenCv, 2) => with_layout!(@ $n = 29, $p = 16, $body),
            (OpenCv, 3) => with_layout!(@ $n = 31, $p = 16, $body),
            (OpenCv, 4) => with_layout!(@ $n = 33, $p = 16, $body),
            (OpenCv, 5) => with_layout!(@ $n = 35, $p = 16, $body),
            _ => Err($crate::Error::InvalidArgument { what: "focal degree outside 1..=5" }),
        }
    }};
    (@ $n:ident = $nv:literal, $p:ident = $pv:literal, $body:expr) => {{
        const $n: usize = $nv;
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

    /// Every layout gets its own length, and a padded row that holds its per-view
    /// variables but u0, v0.
    #[test]
    fn every_layout_maps_to_its_sizes() {
        for model in DistortionModel::ALL {
            for d in 1..=MAX_FOCAL_DEGREE {
                let l = Layout::new(model, d).unwrap();
                let (n, p): (usize, usize) = with_layout!(l, N, P, Result::Ok((N, P))).unwrap();
                assert_eq!(n, l.len());
                assert!(p >= l.reduced_len() - 2 && p % 4 == 0 && p < l.reduced_len() + 2, "{l:?}");
            }
        }
    }
}
