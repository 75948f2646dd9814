//! [`JointSystem`]: the joint normal equations of a rig at given models, and one step
//! through either path of [`LinearSolver`]: what the benchmark measures and the tests
//! compare.

use etl_core::calib::{ParamMask, Point};
use etl_core::model::CameraModel;
use etl_formats::rig_dataset::RigDataset;
use etl_formats::{Error, Result};

use super::cameras::{CameraView, JointCamera};
use super::covariance::{extrinsics_covariance, joint_covariance};
use super::normal::{JointProblem, Normal};
use super::options::LinearSolver;
use super::reduced::{dense_step, sparse_step, SparsePattern};
use super::result::pose_of;
use nalgebra::DMatrix;

/// The errors-in-variables normal equations of a rig's points at given models (each
/// camera's views at their recorded E_com), with every point kept.
pub struct JointSystem {
    cameras: Vec<JointCamera>,
    views: usize,
    sigma_z_mm: f64,
    present: Vec<Vec<(usize, usize)>>,
    sizes: Vec<usize>,
    normal: Normal,
    /// The sparse path's symbolic factorisation, computed by the first sparse step (as the
    /// calibration's loop does: its later steps reuse it).
    pattern: SparsePattern,
}

impl JointSystem {
    /// The system of `dataset`'s points at `models` (one per camera), pixel noise
    /// `sigma_px`, priors `sigma_z_mm` (stage) and `sigma_e_ma` (every camera's current).
    /// Errors: a model count other than the cameras', a view without `e_com_ma`, a point
    /// that does not project.
    pub fn new(
        dataset: &RigDataset,
        models: &[CameraModel],
        sigma_px: f64,
        (sigma_z_mm, sigma_e_ma): (f64, f64),
    ) -> Result<Self> {
        if models.len() != dataset.cameras.len() {
            let message = format!("models: {} for {} cameras", models.len(), dataset.cameras.len());
            return Err(Error::invalid("models", message));
        }
        let mut cameras = vec![];
        for (k, m) in models.iter().enumerate() {
            let mut views = vec![];
            for (j, v) in dataset.views.iter().enumerate() {
                let Some(s) = v.cameras.iter().find(|s| s.camera == k) else { continue };
                let e = s
                    .e_com_ma
                    .ok_or_else(|| Error::invalid(format!("views[{j}]"), format!("views[{j}]: no e_com_ma")))?;
                let points =
                    s.points.iter().flatten().map(|p| Point { world_mm: [p[2], p[3], v.z_w_mm], pixel: [p[0], p[1]] });
                views.push(CameraView { view: j, e, points: points.collect() });
            }
            cameras.push(JointCamera {
                views,
                start: *m,
                layout: m.layout(),
                sigma_px,
                sigma_e: sigma_e_ma,
                hold: ParamMask::NONE,
            });
        }
        let problem = JointProblem::new(&cameras, dataset.views.len(), vec![], Some(sigma_z_mm));
        let normal = problem.normal(&problem.start())?;
        let (present, sizes) = (problem.present.clone(), problem.sizes());
        Ok(JointSystem {
            cameras,
            views: dataset.views.len(),
            sigma_z_mm,
            present,
            sizes,
            normal,
            pattern: SparsePattern::new(),
        })
    }

    /// The inverse of the Fisher information of every camera's numbers (the model's
    /// parameters, cameras stacked, each in its layout's order) with the corrections
    /// marginalised out: at the true models and the simulation's noise, the Cramer-Rao
    /// bound of the joint problem (module docs of [`super`] and of `covariance.rs`).
    pub fn covariance(&self) -> Result<DMatrix<f64>> {
        let problem = JointProblem::new(&self.cameras, self.views, vec![], Some(self.sigma_z_mm));
        joint_covariance(&problem, &problem.start(), None)
    }

    /// Where each camera's numbers start in [`Self::covariance`].
    pub fn offsets(&self) -> Vec<usize> {
        self.sizes.iter().scan(0, |a, p| Some(std::mem::replace(a, *a + p))).collect()
    }

    /// The 6 x 6 covariance of camera k's extrinsics (rad, mm) from a covariance `c` of
    /// the system's numbers ([`Self::covariance`]), at the system's models.
    pub fn extrinsics_covariance(&self, k: usize, c: &DMatrix<f64>) -> [[f64; 6]; 6] {
        let off = self.offsets();
        let (p0, i0) = pose_of(&self.cameras[0].start);
        let (pk, ik) = pose_of(&self.cameras[k].start);
        extrinsics_covariance(c, (&i0.map(|i| i + off[0]), &ik.map(|i| i + off[k])), (p0, pk))
    }

    /// The number of cameras.
    pub fn camera_count(&self) -> usize {
        self.cameras.len()
    }

    /// The size of the reduced system of `solver`'s path: sum p_k (dense), plus one stage
    /// correction per view (sparse).
    pub fn reduced_size(&self, solver: LinearSolver) -> usize {
        let p: usize = self.sizes.iter().sum();
        if solver.sparse_for(self.cameras.len()) {
            p + self.present.len()
        } else {
            p
        }
    }

    /// One step with damping `lambda` by `solver`'s path: every camera's internal numbers'
    /// change (stacked), then each view's corrections (dZ_j, dE_kj...).
    pub fn step(&self, solver: LinearSolver, lambda: f64) -> Result<Vec<f64>> {
        let (dx, dy) = if solver.sparse_for(self.cameras.len()) {
            sparse_step(&self.normal, &self.sizes, &self.present, lambda, &self.pattern)?
        } else {
            dense_step(&self.normal, &self.sizes, &self.present, lambda)?
        };
        Ok(dx.iter().chain(dy.iter().flat_map(|d| d.iter())).copied().collect())
    }
}
