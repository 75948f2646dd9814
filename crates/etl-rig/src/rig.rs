//! A rig opened from its specs: a camera, and for a capture a lens and a stage. The
//! simulated pieces share one world: `--camera sim` renders what the virtual lens
//! (`--lens virtual`) and the simulated stage (`--stage sim`) make of it, so a sim camera
//! needs both (said in one line otherwise).

use etl_formats::board::Board;
use etl_hw::virtual_lens::{ThermalModel, VirtualDevice, VirtualLensConfig};

use crate::camera::files::FilesCamera;
use crate::camera::sim::SimCamera;
use crate::camera::Camera;
use crate::error::{Error, ErrorKind, Result};
use crate::lens::RigLens;
use crate::sim::SimWorld;
use crate::spec::{CameraSpec, LensSpec, StageSpec};
use crate::stage::manual::StdioManualStage;
use crate::stage::sim::SimStage;
use crate::stage::zaber::{ZaberOptions, ZaberStage};
use crate::stage::Stage;

/// What to open.
#[derive(Debug, Clone, PartialEq)]
pub struct RigSpec {
    /// The camera.
    pub camera: CameraSpec,
    /// The lens.
    pub lens: LensSpec,
    /// The stage.
    pub stage: StageSpec,
    /// Seed of the sim camera's noise.
    pub sim_seed: u64,
    /// The sim camera's region of interest `[x, y, width, height]`, px
    /// ([`SimCamera::set_roi`]); None: the whole sensor. Refused with another camera.
    pub sim_roi: Option<[u32; 4]>,
    /// The virtual lens's configuration (with `LensSpec::Virtual`).
    pub virtual_lens: VirtualLensConfig,
}

/// An open rig.
pub struct Rig {
    /// The camera.
    pub camera: Box<dyn Camera>,
    /// The lens.
    pub lens: RigLens,
    /// The stage.
    pub stage: Box<dyn Stage>,
    /// The simulated world, when the camera is `sim`.
    pub sim: Option<SimWorld>,
}

impl Rig {
    /// Opens every device of `spec` (the lens first: a sim camera needs it).
    ///
    /// Errors: a device that cannot be opened, or a sim camera without the virtual lens
    /// and the sim stage; each names the device.
    pub fn open(spec: &RigSpec) -> Result<Rig> {
        #[cfg(feature = "aravis")]
        if let (CameraSpec::Aravis(id), LensSpec::Genicam(g)) = (&spec.camera, &spec.lens) {
            if *id == g.id && spec.sim_roi.is_none() {
                return Rig::open_genicam_camera(spec, id, g);
            }
        }
        let lens = RigLens::open(&spec.lens, spec.virtual_lens.clone())?;
        let sim = matches!(spec.camera, CameraSpec::Sim).then(SimWorld::paper).transpose()?;
        let stage: Box<dyn Stage> = match (&spec.stage, &sim) {
            (StageSpec::Sim, Some(world)) => Box::new(SimStage::new(world.clone())),
            (StageSpec::Sim, None) => Box::new(SimStage::new(SimWorld::paper()?)),
            (_, Some(_)) => {
                let message = "the sim camera renders the simulated stage's board: use --stage sim";
                return Err(Error::device("camera sim", ErrorKind::InvalidInput, message));
            }
            (other, None) => open_stage(other)?,
        };
        let camera: Box<dyn Camera> = match (&spec.camera, &sim) {
            (CameraSpec::Sim, Some(world)) => {
                let device = lens.virtual_device().cloned().ok_or_else(|| {
                    let message = "the sim camera renders the virtual lens's state: use --lens virtual";
                    Error::device("camera sim", ErrorKind::InvalidInput, message)
                })?;
                let mut camera = SimCamera::new(world.clone(), device, spec.sim_seed);
                if let Some(roi) = spec.sim_roi {
                    camera.set_roi(roi)?;
                }
                Box::new(camera)
            }
            (other, _) if spec.sim_roi.is_some() => {
                let message =
                    "a region of interest (--sim-roi) is the sim camera's: set a real camera's in its own software";
                return Err(Error::device(format!("camera {other}"), ErrorKind::InvalidInput, message));
            }
            (other, _) => open_camera(other, spec.sim_seed)?,
        };
        Ok(Rig { camera, lens, stage, sim })
    }

    /// A GenICam camera that grabs the frames and drives the lens over one connection.
    #[cfg(feature = "aravis")]
    fn open_genicam_camera(spec: &RigSpec, id: &str, lens: &crate::spec::GenicamLensSpec) -> Result<Rig> {
        let camera = crate::camera::aravis::AravisCamera::open(id)?;
        let lens = RigLens::genicam(crate::lens::genicam::GenicamLens::on_camera(camera.arv_camera(), lens)?)?;
        let stage = open_stage(&spec.stage)?;
        Ok(Rig { camera: Box::new(camera), lens, stage, sim: None })
    }

    /// Shows `board` on the simulated stage and `offstate_board` in the lens-off poses
    /// (nothing for a real rig: its boards are what they are).
    pub fn show_boards(&self, board: Board, offstate_board: Board) {
        if let Some(world) = &self.sim {
            world.set_boards(board, offstate_board);
        }
    }
}

/// Opens a stage alone (`etlcal stage`, a rig whose camera is not `sim`); `sim` is a
/// simulated stage of its own.
pub fn open_stage(spec: &StageSpec) -> Result<Box<dyn Stage>> {
    Ok(match spec {
        StageSpec::Sim => Box::new(SimStage::new(SimWorld::paper()?)),
        StageSpec::Manual => Box::new(StdioManualStage::stdio()),
        StageSpec::Zaber(z) => Box::new(ZaberStage::open(z, ZaberOptions::default())?),
    })
}

/// The virtual lens of the simulated rig: the paper's physics and thermal surface at the
/// paper's lens temperature, 27 degC ambient (as `etlcal lens --virtual`), real time, no
/// dynamics.
pub fn paper_virtual_lens() -> VirtualLensConfig {
    VirtualLensConfig { thermal: ThermalModel { ambient_c: 27.0, ..Default::default() }, ..Default::default() }
}

/// Opens a camera alone (`etlcal camera grab`): `sim` is the simulated rig at rest (a
/// virtual lens at 0 mA, the stage at 0 mm).
pub fn open_camera(spec: &CameraSpec, sim_seed: u64) -> Result<Box<dyn Camera>> {
    let name = format!("camera {spec}");
    match spec {
        CameraSpec::Sim => {
            let device = VirtualDevice::new(paper_virtual_lens()).map_err(|e| Error::lens("lens virtual", e))?;
            Ok(Box::new(SimCamera::new(SimWorld::paper()?, device, sim_seed)))
        }
        CameraSpec::Files(dir) => Ok(Box::new(FilesCamera::open(dir)?)),
        CameraSpec::Aravis(id) => open_aravis(id, &name),
        CameraSpec::V4l2(path) => open_v4l2(path, &name),
    }
}

#[cfg(all(feature = "v4l2", target_os = "linux"))]
fn open_v4l2(path: &std::path::Path, _name: &str) -> Result<Box<dyn Camera>> {
    Ok(Box::new(crate::camera::v4l2::V4l2Camera::open(path)?))
}

#[cfg(not(all(feature = "v4l2", target_os = "linux")))]
fn open_v4l2(_path: &std::path::Path, name: &str) -> Result<Box<dyn Camera>> {
    Err(Error::device(
        name,
        ErrorKind::InvalidInput,
        "this etlcal was built without the v4l2 feature (Linux: cargo install --path crates/etlcal --features v4l2)",
    ))
}

#[cfg(feature = "aravis")]
fn open_aravis(id: &str, _name: &str) -> Result<Box<dyn Camera>> {
    Ok(Box::new(crate::camera::aravis::AravisCamera::open(id)?))
}

#[cfg(not(feature = "aravis"))]
fn open_aravis(_id: &str, name: &str) -> Result<Box<dyn Camera>> {
    Err(Error::device(
        name,
        ErrorKind::InvalidInput,
        "this etlcal was built without the aravis feature (cargo install --path crates/etlcal --features aravis)",
    ))
}

/// The cameras this build can list: aravis's devices with the `aravis` feature; `sim`
/// always.
pub fn list_cameras() -> Result<Vec<String>> {
    let sim = vec!["sim".to_owned()];
    #[cfg(feature = "aravis")]
    let sim =
        sim.into_iter().chain(crate::camera::aravis::list()?.into_iter().map(|id| format!("aravis:{id}"))).collect();
    Ok(sim)
}
