//! [`ViewScratch`]: one view's storage of the bundle adjustment, for any parameter layout.
//!
//! The block solver ([`crate::lm::solve_blocks`]) keeps per block a [`BlockScratch`] whose
//! size is the number of shared parameters, which depends on the layout (21..35). A
//! `ViewScratch` holds the one of the layout being solved: callers allocate one type,
//! whatever the family and focal degree, and the bundle adjustment sizes it on entry.
//! Its sizes come from the one table of layouts ([`layout_table!`]).

use core::any::Any;

use crate::calib::dispatch::layout_table;
use crate::calib::params::Layout;
use crate::lm::{BlockScratch, BlockStorage};
use crate::model::DistortionModel;

use super::ViewCorrection;

/// Sets a storage up for the block solver of `N` shared parameters, its block parameters
/// (the view's correction) at zero.
pub(crate) trait Prepare<const N: usize> {
    /// Replaces the content by a zeroed [`BlockScratch`] of size `N`.
    fn prepare(&mut self);
}

/// The storage of every layout of [`layout_table!`], one variant each, sized by the layout
/// itself. Two layouts of one length (paper degree 4 and opencv degree 1: 27) hold the
/// same type; the solver finds its size by type ([`Any`]), whichever variant holds it.
macro_rules! view_scratch {
    ($($family:ident: [$(($degree:literal, $centre:literal) => $name:ident),*],)*) => {
        #[derive(Debug, Clone, Copy, PartialEq)]
        enum Blocks {
            $($($name(BlockScratch<{ Layout::of_table(DistortionModel::$family, $degree, $centre).len() }, 2>),)*)*
        }

        impl Blocks {
            fn y(&self) -> [f64; 2] {
                match self {
                    $($(Blocks::$name(b) => *b.y(),)*)*
                }
            }
        }

        // The block of size `N`, if the storage holds one (else `None`, which the block
        // solver refuses with an error).
        impl<const N: usize> BlockStorage<N, 2> for ViewScratch {
            fn block(&self) -> Option<&BlockScratch<N, 2>> {
                match &self.0 {
                    $($(Blocks::$name(b) => (b as &dyn Any).downcast_ref(),)*)*
                }
            }
            fn block_mut(&mut self) -> Option<&mut BlockScratch<N, 2>> {
                match &mut self.0 {
                    $($(Blocks::$name(b) => (b as &mut dyn Any).downcast_mut(),)*)*
                }
            }
        }

        // Storage of size `N` if a layout of the table has that length (else left as it
        // is, and the solver refuses it).
        impl<const N: usize> Prepare<N> for ViewScratch {
            fn prepare(&mut self) {
                $($(
                    if N == Layout::of_table(DistortionModel::$family, $degree, $centre).len() {
                        self.0 = Blocks::$name(BlockScratch::ZERO);
                        return;
                    }
                )*)*
            }
        }
    };
}

layout_table!([view_scratch]);

/// One view's storage of [`super::bundle_adjust`]: the view's correction (dZ_j mm, dE_j mA:
/// the block parameters of the errors-in-variables solve, zeros for the paper's estimator)
/// and the block solver's working state, for any layout of the model's numbers. Read the
/// correction with [`ViewCorrection::from`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewScratch(Blocks);

impl ViewScratch {
    /// Zeroed storage (sized by the bundle adjustment on entry).
    pub const ZERO: ViewScratch = ViewScratch(Blocks::Paper3(BlockScratch::ZERO));

    /// The view's correction (dZ_j mm, dE_j mA).
    pub fn y(&self) -> [f64; 2] {
        self.0.y()
    }
}

impl Default for ViewScratch {
    fn default() -> Self {
        Self::ZERO
    }
}

impl From<&ViewScratch> for ViewCorrection {
    fn from(scratch: &ViewScratch) -> Self {
        let [dz_mm, de_ma] = scratch.y();
        ViewCorrection { dz_mm, de_ma }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Storage prepared for `N`, asked for its block of size `N`.
    fn holds<const N: usize>() -> bool {
        let mut s = ViewScratch::ZERO;
        <ViewScratch as Prepare<N>>::prepare(&mut s);
        BlockStorage::<N, 2>::block(&s).is_some() && BlockStorage::<N, 2>::block_mut(&mut s).is_some()
    }

    /// Every length of the table (the paper family's 21..=29, opencv's 27..=35, odd) has
    /// storage; no other size does, and storage of one size holds no block of another.
    #[test]
    fn every_layout_length_has_storage_and_no_other() {
        assert!(holds::<21>() && holds::<23>() && holds::<25>() && holds::<27>() && holds::<29>());
        assert!(holds::<31>() && holds::<33>() && holds::<35>());
        // A moving centre adds 4 numbers: up to opencv's 39.
        assert!(holds::<37>() && holds::<39>());
        assert!(!holds::<19>() && !holds::<22>() && !holds::<41>());
        let paper = ViewScratch::ZERO;
        assert!(BlockStorage::<25, 2>::block(&paper).is_some());
        assert!(BlockStorage::<27, 2>::block(&paper).is_none());
        assert_eq!(paper.y(), [0.0, 0.0]);
    }
}
