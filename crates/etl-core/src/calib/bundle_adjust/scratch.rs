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
/// itself, for blocks of `$m` parameters: `$blocks` the enum, `$storage` the public
/// newtype. Two layouts of one length (paper degree 4 and opencv degree 1: 27) hold the
/// same type; the solver finds its size by type ([`Any`]), whichever variant holds it.
macro_rules! view_scratch {
    ($blocks:ident, $storage:ident, $m:literal;
     $($family:ident: [$(($degree:literal, $centre:literal) => $name:ident),*],)*) => {
        #[derive(Debug, Clone, Copy, PartialEq)]
        enum $blocks {
            $($($name(BlockScratch<{ Layout::of_table(DistortionModel::$family, $degree, $centre).len() }, $m>),)*)*
        }

        impl $blocks {
            fn y(&self) -> [f64; $m] {
                match self {
                    $($($blocks::$name(b) => *b.y(),)*)*
                }
            }
        }

        // The block of size `N`, if the storage holds one (else `None`, which the block
        // solver refuses with an error).
        impl<const N: usize> BlockStorage<N, $m> for $storage {
            fn block(&self) -> Option<&BlockScratch<N, $m>> {
                match &self.0 {
                    $($($blocks::$name(b) => (b as &dyn Any).downcast_ref(),)*)*
                }
            }
            fn block_mut(&mut self) -> Option<&mut BlockScratch<N, $m>> {
                match &mut self.0 {
                    $($($blocks::$name(b) => (b as &mut dyn Any).downcast_mut(),)*)*
                }
            }
        }

        // Storage of size `N` if a layout of the table has that length (else left as it
        // is, and the solver refuses it).
        impl<const N: usize> Prepare<N> for $storage {
            fn prepare(&mut self) {
                $($(
                    if N == Layout::of_table(DistortionModel::$family, $degree, $centre).len() {
                        self.0 = $blocks::$name(BlockScratch::ZERO);
                        return;
                    }
                )*)*
            }
        }
    };
}

layout_table!([view_scratch] Blocks, ViewScratch, 2;);
layout_table!([view_scratch] JointBlocks, JointScratch, 7;);

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

/// Block parameters of a view in [`super::bundle_adjust_free_views`]: a stage view's
/// (dZ_j mm, dE_j mA, then 5 unused), a free-pose view's (Rodrigues 3, translation 3 mm,
/// dE_f mA).
pub const JOINT_BLOCK: usize = 7;

/// One view's storage of [`super::bundle_adjust_free_views`]: the stage views' first, then
/// the free-pose views'. A stage view's block holds its correction (dZ_j mm, dE_j mA, the
/// rest unused), a free view's its board pose (Rodrigues, translation mm: board ->
/// camera, as [`crate::pnp::BoardPose`]) and its current correction dE_f mA (zero for the
/// paper's estimator). Read them with [`JointScratch::correction`] and
/// [`JointScratch::board_pose`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointScratch(JointBlocks);

impl JointScratch {
    /// Zeroed storage (sized by the bundle adjustment on entry).
    pub const ZERO: JointScratch = JointScratch(JointBlocks::Paper3(BlockScratch::ZERO));

    /// The block's parameters (module docs of [`super::free_views`]).
    pub fn y(&self) -> [f64; JOINT_BLOCK] {
        self.0.y()
    }

    /// A stage view's correction (dZ_j mm, dE_j mA).
    pub fn correction(&self) -> ViewCorrection {
        let y = self.y();
        ViewCorrection { dz_mm: y[0], de_ma: y[1] }
    }

    /// A free-pose view's board pose: (Rodrigues, translation mm) and its current
    /// correction dE_f, mA.
    pub fn board_pose(&self) -> ([f64; 3], [f64; 3], f64) {
        let y = self.y();
        ([y[0], y[1], y[2]], [y[3], y[4], y[5]], y[6])
    }
}

impl Default for JointScratch {
    fn default() -> Self {
        Self::ZERO
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
