//! [`ViewScratch`]: one view's storage of the bundle adjustment, for any parameter layout.
//!
//! The block solver ([`crate::lm::solve_blocks`]) keeps per block a [`BlockScratch`] whose
//! size is the number of shared parameters, which depends on the layout (21..35). A
//! `ViewScratch` holds the one of the layout being solved: callers allocate one type,
//! whatever the family and focal degree, and the bundle adjustment sizes it on entry.

use crate::lm::{BlockScratch, BlockStorage};

use super::ViewCorrection;

/// Sets a storage up for the block solver of `N` shared parameters, its block parameters
/// (the view's correction) at zero.
pub(crate) trait Prepare<const N: usize> {
    /// Replaces the content by a zeroed [`BlockScratch`] of size `N`.
    fn prepare(&mut self);
}

macro_rules! view_scratch {
    ($($variant:ident = $n:literal),* $(,)?) => {
        #[derive(Debug, Clone, Copy, PartialEq)]
        enum Blocks {
            $($variant(BlockScratch<$n, 2>),)*
        }

        impl Blocks {
            fn y(&self) -> [f64; 2] {
                match self {
                    $(Blocks::$variant(b) => *b.y(),)*
                }
            }
        }

        $(
            impl BlockStorage<$n, 2> for ViewScratch {
                fn block(&self) -> Option<&BlockScratch<$n, 2>> {
                    match &self.0 {
                        Blocks::$variant(b) => Some(b),
                        #[allow(unreachable_patterns)]
                        _ => None,
                    }
                }
                fn block_mut(&mut self) -> Option<&mut BlockScratch<$n, 2>> {
                    match &mut self.0 {
                        Blocks::$variant(b) => Some(b),
                        #[allow(unreachable_patterns)]
                        _ => None,
                    }
                }
            }

            impl Prepare<$n> for ViewScratch {
                fn prepare(&mut self) {
                    self.0 = Blocks::$variant(BlockScratch::ZERO);
                }
            }
        )*
    };
}

// Every layout's length: paper 19 + 2 d (d = 1..=5), opencv 25 + 2 d.
view_scratch!(P21 = 21, P23 = 23, P25 = 25, P27 = 27, P29 = 29, P31 = 31, P33 = 33, P35 = 35);

/// One view's storage of [`super::bundle_adjust`]: the view's correction (dZ_j mm, dE_j mA:
/// the block parameters of the errors-in-variables solve, zeros for the paper's estimator)
/// and the block solver's working state, for any layout of the model's numbers. Read the
/// correction with [`ViewCorrection::from`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewScratch(Blocks);

impl ViewScratch {
    /// Zeroed storage (sized by the bundle adjustment on entry).
    pub const ZERO: ViewScratch = ViewScratch(Blocks::P25(BlockScratch::ZERO));

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
