//! The simulated rig's shared world: where the simulated stage holds the board, which
//! lens-off pose the board is in, and which boards there are. The sim camera
//! ([`crate::camera::sim`]) renders it; the sim stage ([`crate::stage::sim`]) moves it.
//!
//! The rig is the paper's ([`etl_core::model::CameraModel::paper_rig`], 1936 x 1458 px):
//! the ETL views' board on the stage at Z_W = the stage position, fronto-parallel, its
//! first inner corner where the paper's board has it; the lens-off views' board in the
//! 10 tilted poses of [`etl_sim::simulate::lens_off_poses`] (about 125 mm away).

use std::sync::{Arc, Mutex, MutexGuard};

use etl_formats::board::Board;

/// The simulated stage's travel, mm.
pub const SIM_TRAVEL_MM: [f64; 2] = [0.0, 150.0];

/// How many lens-off poses the simulated rig has.
pub const SIM_OFFSTATE_POSES: usize = 10;

#[derive(Debug)]
struct WorldState {
    stage_z_mm: f64,
    offstate_pose: Option<usize>,
    board: Board,
    offstate_board: Board,
}

/// The simulated rig's world (a handle: clones share it).
#[derive(Debug, Clone)]
pub struct SimWorld(Arc<Mutex<WorldState>>);

impl SimWorld {
    /// A world with `board` on the stage at 0 mm and `offstate_board` for the lens-off
    /// views.
    pub fn new(board: Board, offstate_board: Board) -> SimWorld {
        SimWorld(Arc::new(Mutex::new(WorldState { stage_z_mm: 0.0, offstate_pose: None, board, offstate_board })))
    }

    /// The simulated paper rig's boards ([`etl_sim::rig::PAPER_CHARUCO`] on the stage,
    /// [`etl_sim::rig::LENS_OFF_CHARUCO`] for the lens-off views).
    pub fn paper() -> etl_formats::Result<SimWorld> {
        Ok(SimWorld::new(etl_sim::rig::PAPER_CHARUCO.board()?, etl_sim::rig::LENS_OFF_CHARUCO.board()?))
    }

    fn lock(&self) -> MutexGuard<'_, WorldState> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Puts `board` on the stage and `offstate_board` in the lens-off poses.
    pub fn set_boards(&self, board: Board, offstate_board: Board) {
        let mut s = self.lock();
        s.board = board;
        s.offstate_board = offstate_board;
    }

    /// The stage position, mm.
    pub fn stage_z_mm(&self) -> f64 {
        self.lock().stage_z_mm
    }

    /// Moves the stage (and takes the board off any lens-off pose).
    pub fn set_stage_z_mm(&self, z_mm: f64) {
        let mut s = self.lock();
        s.stage_z_mm = z_mm;
        s.offstate_pose = None;
    }

    /// Puts the lens-off board in pose `k` (< [`SIM_OFFSTATE_POSES`]).
    pub fn set_offstate_pose(&self, k: usize) {
        self.lock().offstate_pose = Some(k);
    }

    /// What the camera sees: `Some((k, board))` in lens-off pose k, else `None` and the
    /// stage's board at the stage position.
    pub fn view(&self) -> (Option<(usize, Board)>, Board, f64) {
        let s = self.lock();
        (s.offstate_pose.map(|k| (k, s.offstate_board)), s.board, s.stage_z_mm)
    }
}
