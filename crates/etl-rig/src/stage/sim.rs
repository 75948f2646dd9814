//! `sim`: the simulated rig's stage. Moves at once and exactly, within
//! [`SIM_TRAVEL_MM`]; poses the lens-off board itself (10 poses).

use super::Stage;
use crate::error::{Error, ErrorKind, Result};
pub use crate::sim::SIM_TRAVEL_MM;
use crate::sim::{SimWorld, SIM_OFFSTATE_POSES};

/// The simulated stage.
pub struct SimStage {
    world: SimWorld,
    /// Test double: the stage stops answering after this many more moves.
    silent_after: Option<usize>,
}

impl SimStage {
    /// The stage of `world`.
    pub fn new(world: SimWorld) -> SimStage {
        SimStage { world, silent_after: None }
    }

    /// Test double: after `moves` more moves, every call times out as a stage that has
    /// stopped answering.
    pub fn stop_answering_after(&mut self, moves: usize) {
        self.silent_after = Some(moves);
    }

    fn answering(&mut self) -> Result<()> {
        match self.silent_after {
            Some(0) => {
                Err(Error::device(self.name(), ErrorKind::Timeout, "no reply within 1 s (the stage stopped answering)"))
            }
            _ => Ok(()),
        }
    }
}

impl Stage for SimStage {
    fn name(&self) -> String {
        "stage sim".into()
    }

    fn move_mm(&mut self, z_mm: f64) -> Result<f64> {
        self.answering()?;
        if let Some(n) = self.silent_after.as_mut() {
            *n -= 1;
        }
        let [lo, hi] = SIM_TRAVEL_MM;
        if !(lo..=hi).contains(&z_mm) {
            let message = format!("position {z_mm} mm is outside the travel [{lo}, {hi}] mm");
            return Err(Error::device(self.name(), ErrorKind::Refused, message));
        }
        self.world.set_stage_z_mm(z_mm);
        Ok(z_mm)
    }

    fn position_mm(&mut self) -> Result<f64> {
        self.answering()?;
        Ok(self.world.stage_z_mm())
    }

    fn home(&mut self) -> Result<()> {
        self.answering()?;
        self.world.set_stage_z_mm(SIM_TRAVEL_MM[0]);
        Ok(())
    }

    fn limits_mm(&mut self) -> Result<[f64; 2]> {
        Ok(SIM_TRAVEL_MM)
    }

    fn present_offstate_pose(&mut self, k: usize, count: usize) -> Result<()> {
        self.answering()?;
        if count > SIM_OFFSTATE_POSES {
            let message = format!(
                "the simulated rig has {SIM_OFFSTATE_POSES} lens-off poses; the plan asks for {count} (offstate_views)"
            );
            return Err(Error::device(self.name(), ErrorKind::InvalidInput, message));
        }
        self.world.set_offstate_pose(k);
        Ok(())
    }
}
