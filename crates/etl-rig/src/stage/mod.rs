//! The [`Stage`] trait and its backends: [`sim`] (the simulated rig's), [`manual`] (a hand
//! and a micrometer: prompts on stderr, reads stdin) and [`zaber`] (Zaber's ASCII protocol
//! over serial), with [`zaber_standin`], a Zaber device on a pseudo-terminal for tests.

pub mod manual;
pub mod sim;
pub mod zaber;
#[cfg(unix)]
pub mod zaber_standin;

use crate::error::Result;

/// A linear stage moving the board along the optical axis.
pub trait Stage {
    /// The device's name in errors: `stage SPEC`.
    fn name(&self) -> String;

    /// Moves to `z_mm` and waits until the move has ended; returns the position read back
    /// afterwards, mm (what the view records).
    fn move_mm(&mut self, z_mm: f64) -> Result<f64>;

    /// The position now, mm.
    fn position_mm(&mut self) -> Result<f64>;

    /// Homes the stage (finds its reference) and waits until it has.
    fn home(&mut self) -> Result<()>;

    /// The travel, `[lo, hi]` mm (infinite ends where the stage has none it knows of).
    fn limits_mm(&mut self) -> Result<[f64; 2]>;

    /// Puts the lens-off board in the `k`-th of `count` tilted poses (a hand does it for a
    /// real rig: the stage then prompts; the simulated rig poses the board itself).
    fn present_offstate_pose(&mut self, k: usize, count: usize) -> Result<()>;
}

impl<S: Stage + ?Sized> Stage for Box<S> {
    fn name(&self) -> String {
        (**self).name()
    }
    fn move_mm(&mut self, z_mm: f64) -> Result<f64> {
        (**self).move_mm(z_mm)
    }
    fn position_mm(&mut self) -> Result<f64> {
        (**self).position_mm()
    }
    fn home(&mut self) -> Result<()> {
        (**self).home()
    }
    fn limits_mm(&mut self) -> Result<[f64; 2]> {
        (**self).limits_mm()
    }
    fn present_offstate_pose(&mut self, k: usize, count: usize) -> Result<()> {
        (**self).present_offstate_pose(k, count)
    }
}
