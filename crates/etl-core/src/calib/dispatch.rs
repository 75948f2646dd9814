//! From a [`super::params::Layout`] value to the sizes the solvers are compiled for.
//!
//! The solvers keep their matrices on the stack at the exact size of the parameter vector
//! (const generics: no allocation, and the paper's 25 numbers solved exactly as before the
//! families existed). [`with_layout!`] runs a body with `N` (the layout's length) and `P`
//! (the padded row length of a view's reduced normal equations: the per-view variables but
//! u0, v0, rounded up to a multiple of 4 so that their accumulation vectorises) bound as
//! constants, with `O` the number of those per-view variables, for each layout of the
//! one table of distortion families and focal degrees ([`layout_table!`]).

/// The layouts the solvers are compiled for, one row per distortion family: the
/// [`DistortionModel`](crate::model::DistortionModel) variant and, for each focal degree
/// 1..=5 with a fixed and a moving centre, the name of its storage in
/// [`ViewScratch`](super::ViewScratch). Every size comes
/// from the layout itself ([`Layout::len`](super::params::Layout::len),
/// [`Layout::reduced_len`](super::params::Layout::reduced_len)), so a new family is one
/// row here. Expands `$callback! { $args TABLE }` (the callback given as a path in
/// brackets), so that [`with_layout!`] and the bundle adjustment's per-view storage are
/// both made from this one table.
macro_rules! layout_table {
    ([$($callback:tt)+] $($args:tt)*) => {
        $($callback)+! {
            $($args)*
            Paper: [
                (1, false) => Paper1, (2, false) => Paper2, (3, false) => Paper3,
                (4, false) => Paper4, (5, false) => Paper5,
                (1, true) => PaperMoving1, (2, true) => PaperMoving2, (3, true) => PaperMoving3,
                (4, true) => PaperMoving4, (5, true) => PaperMoving5
            ],
            OpenCv: [
                (1, false) => OpenCv1, (2, false) => OpenCv2, (3, false) => OpenCv3,
                (4, false) => OpenCv4, (5, false) => OpenCv5,
                (1, true) => OpenCvMoving1, (2, true) => OpenCvMoving2, (3, true) => OpenCvMoving3,
                (4, true) => OpenCvMoving4, (5, true) => OpenCvMoving5
            ],
        }
    };
}

/// Runs `$body` (an expression of type `Result<_>`) with the constants `$n` = the layout's
/// length, `$o` = the per-view variables other than u0, v0 (11 for the paper family, 13
/// for opencv) and `$p` = their row length padded to a multiple of 4 (12, 16), for each
/// layout of [`layout_table!`].
macro_rules! with_layout {
    ($layout:expr, $n:ident, $o:ident, $p:ident, $body:expr) => {
        $crate::calib::dispatch::layout_table!(
            [$crate::calib::dispatch::with_layout] @arms ($layout, $n, $o, $p, $body)
        )
    };
    (@arms ($layout:expr, $n:ident, $o:ident, $p:ident, $body:expr)
        $($family:ident: [$(($degree:literal, $centre:literal) => $name:ident),*],)*) => {{
        use $crate::model::DistortionModel;
        match ($layout.model(), $layout.focal_degree(), $layout.moving_centre()) {
            $($((DistortionModel::$family, $degree, $centre) => {
                const $n: usize =
                    $crate::calib::params::Layout::of_table(DistortionModel::$family, $degree, $centre).len();
                const $o: usize = $crate::calib::params::Layout::of_table(DistortionModel::$family, $degree, $centre)
                    .reduced_len()
                    - 2;
                const $p: usize = $o.div_ceil(4) * 4;
                $body
            })*)*
            _ => Err($crate::Error::InvalidArgument { what: "focal degree outside 1..=5" }),
        }
    }};
}

pub(crate) use layout_table;
pub(crate) use with_layout;

#[cfg(test)]
mod tests {
    use crate::calib::params::Layout;
    use crate::model::{DistortionModel, MAX_FOCAL_DEGREE};
    use crate::Result;

    /// The sizes of today's layouts, as they were kept by hand before the table: the
    /// paper family 19 + 2 d numbers (11 per-view variables but u0, v0, padded to 12),
    /// opencv 25 + 2 d (13, padded to 16).
    #[test]
    fn the_table_gives_the_sizes_of_before() {
        for d in 1..=MAX_FOCAL_DEGREE {
            let paper = Layout::new(DistortionModel::Paper, d).unwrap();
            let opencv = Layout::new(DistortionModel::OpenCv, d).unwrap();
            let sizes = |l: Layout| with_layout!(l, N, O, P, Result::Ok((N, O, P))).unwrap();
            assert_eq!(sizes(paper), (19 + 2 * d, 11, 12));
            assert_eq!(sizes(opencv), (25 + 2 * d, 13, 16));
        }
    }

    /// Every layout gets its own length, the count of its per-view variables but u0, v0,
    /// and a padded row that holds them.
    #[test]
    fn every_layout_maps_to_its_sizes() {
        for model in DistortionModel::ALL {
            for d in 1..=MAX_FOCAL_DEGREE {
                for moving in [false, true] {
                    let l = Layout::new(model, d).unwrap().with_moving_centre(moving);
                    let (n, o, p): (usize, usize, usize) = with_layout!(l, N, O, P, Result::Ok((N, O, P))).unwrap();
                    assert_eq!(n, l.len());
                    assert_eq!(o, l.reduced_len() - 2);
                    assert!(p >= o && p % 4 == 0 && p < o + 4, "{l:?}");
                    assert_eq!(Layout::of_table(model, d, moving), l);
                }
            }
        }
    }
}
