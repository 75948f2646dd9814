//! The least-squares problem of a pair (module docs of [`super`]): shared numbers
//! x = (om, T, the left camera's free intrinsics, the right camera's), per pair the left
//! camera's board pose y_j = (om_j, t_j).

use etl_core::calib::jacobian::{rotate_point_jacobian, Projector};
use etl_core::lm::{BlockProblem, BlockRowSink};
use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix, Mat3};
use etl_core::model::DistortionModel;

use crate::zhang::{model_at, param_index, PlanarView, Shared};

/// One pair's points: each camera's board points and pixels (they may differ: a ChArUco
/// board seen in part).
#[derive(Debug, Clone)]
pub(super) struct PairPoints {
    pub left: PlanarView,
    pub right: PlanarView,
}

/// The problem: the pairs, the distortion family, each camera's shared numbers (the held
/// ones' values) and the indices into them of the free ones.
pub(super) struct StereoProblem<'a> {
    pub pairs: &'a [PairPoints],
    pub model: DistortionModel,
    pub left: Shared,
    pub right: Shared,
    pub left_free: &'a [usize],
    pub right_free: &'a [usize],
}

/// `a b` for 3 x 3 matrices.
fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

impl StereoProblem<'_> {
    /// The relative pose (om, T) and each camera's shared numbers at `x`.
    pub fn unpack<const N: usize>(&self, x: &[f64; N]) -> ([f64; 3], [f64; 3], Shared, Shared) {
        let (mut l, mut r) = (self.left, self.right);
        let nl = self.left_free.len();
        for (k, &i) in self.left_free.iter().enumerate() {
            l[i] = x.get(6 + k).copied().unwrap_or(l[i]);
        }
        for (k, &i) in self.right_free.iter().enumerate() {
            r[i] = x.get(6 + nl + k).copied().unwrap_or(r[i]);
        }
        ([x[0], x[1], x[2]], [x[3], x[4], x[5]], l, r)
    }

    /// Each camera's model at the identity pose (its world frame is its camera frame).
    pub fn projectors(&self, left: &Shared, right: &Shared) -> (Projector, Projector) {
        let (ml, mr) = (model_at(self.model, left, &[0.0; 6]), model_at(self.model, right, &[0.0; 6]));
        (Projector::new(&ml), Projector::new(&mr))
    }
}

/// Where a camera's residual rows put their intrinsics' derivatives: the first column in x
/// and the indices of the free numbers.
struct Columns<'a> {
    first: usize,
    free: &'a [usize],
}

/// Pushes the two rows of one point seen at `pixel` whose camera-frame position is `pc`:
/// `d_pc_x`, `d_pc_y` (3 x 6) map dq/dpc to the pose columns of x and of y.
fn push_point<const N: usize>(
    proj: &Projector,
    (pc, pixel): ([f64; 3], [f64; 2]),
    (d_pc_x, d_pc_y): (Option<&[[f64; 6]; 3]>, &[[f64; 6]; 3]),
    cols: &Columns<'_>,
    jacobian: bool,
    sink: &mut dyn BlockRowSink<N, 6>,
) -> etl_core::Result<()> {
    let p = proj.project(pc, 0.0, jacobian)?;
    let layout = proj.layout();
    let t = layout.translation();
    for row in 0..2 {
        let d = &p.d_params[row];
        let dq_dpc = [d[t.at(0)], d[t.at(1)], d[t.at(2)]];
        let (mut jx, mut jy) = ([0.0; N], [0.0; 6]);
        if jacobian {
            for k in 0..6 {
                jy[k] = (0..3).map(|i| dq_dpc[i] * d_pc_y[i][k]).sum();
                if let Some(m) = d_pc_x {
                    jx[k] = (0..3).map(|i| dq_dpc[i] * m[i][k]).sum();
                }
            }
            for (k, &f) in cols.free.iter().enumerate() {
                if let Some(slot) = jx.get_mut(cols.first + k) {
                    *slot = d.get(param_index(&layout, f)).copied().unwrap_or(0.0);
                }
            }
        }
        sink.push(p.pixel[row] - pixel[row], &jx, &jy);
    }
    Ok(())
}

/// [R_a | I] laid out as a 3 x 6 block (rotation columns `ra`, then the identity), or
/// `m` times it.
fn pose_block(m: Option<&Mat3>, ra: &Mat3) -> [[f64; 6]; 3] {
    let id: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let (left, right) = match m {
        Some(m) => (mat_mul(m, ra), *m),
        None => (*ra, id),
    };
    core::array::from_fn(|i| core::array::from_fn(|k| if k < 3 { left[i][k] } else { right[i][k - 3] }))
}

impl<const N: usize> BlockProblem<N, 6> for StereoProblem<'_> {
    fn block_count(&self) -> usize {
        self.pairs.len()
    }

    fn eval_block(
        &mut self,
        b: usize,
        x: &[f64; N],
        y: &[f64; 6],
        jacobian: bool,
        sink: &mut dyn BlockRowSink<N, 6>,
    ) -> etl_core::Result<()> {
        let pair = self.pairs.get(b).ok_or(etl_core::Error::InvalidArgument { what: "pair index" })?;
        let (om, t, zl, zr) = self.unpack(x);
        let (pl, pr) = self.projectors(&zl, &zr);
        let (omj, tj) = ([y[0], y[1], y[2]], [y[3], y[4], y[5]]);
        let (r, rj) = (rodrigues_to_matrix(om), rodrigues_to_matrix(omj));
        let left_cols = Columns { first: 6, free: self.left_free };
        let right_cols = Columns { first: 6 + self.left_free.len(), free: self.right_free };
        let in_left = |w: &[f64; 2]| {
            let q = mat_vec(&rj, [w[0], w[1], 0.0]);
            let d_rot = if jacobian { rotate_point_jacobian(&rj, omj, [w[0], w[1], 0.0]) } else { [[0.0; 3]; 3] };
            ([q[0] + tj[0], q[1] + tj[1], q[2] + tj[2]], d_rot)
        };
        for (w, px) in pair.left.board_mm.iter().zip(&pair.left.pixels) {
            let (xl, d_rot) = in_left(w);
            let dy = pose_block(None, &d_rot);
            push_point(&pl, (xl, *px), (None, &dy), &left_cols, jacobian, sink)?;
        }
        for (w, px) in pair.right.board_mm.iter().zip(&pair.right.pixels) {
            let (xl, d_rot) = in_left(w);
            let q = mat_vec(&r, xl);
            let xr = [q[0] + t[0], q[1] + t[1], q[2] + t[2]];
            let d_om = if jacobian { rotate_point_jacobian(&r, om, xl) } else { [[0.0; 3]; 3] };
            let (dx, dy) = (pose_block(None, &d_om), pose_block(Some(&r), &d_rot));
            push_point(&pr, (xr, *px), (Some(&dx), &dy), &right_cols, jacobian, sink)?;
        }
        Ok(())
    }
}

/// Every point's reprojection distance, px, per pair and camera ([left, right]) at the
/// shared numbers `x` and the poses `poses` (infinite where a point does not project).
pub(super) fn distances<const N: usize>(
    problem: &StereoProblem<'_>,
    x: &[f64; N],
    poses: &[[f64; 6]],
) -> Vec<[Vec<f64>; 2]> {
    let (om, t, zl, zr) = problem.unpack(x);
    let (pl, pr) = problem.projectors(&zl, &zr);
    let r = rodrigues_to_matrix(om);
    let one = |proj: &Projector, pc: [f64; 3], px: &[f64; 2]| match proj.project(pc, 0.0, false) {
        Ok(q) => (q.pixel[0] - px[0]).hypot(q.pixel[1] - px[1]),
        Err(_) => f64::INFINITY,
    };
    problem
        .pairs
        .iter()
        .zip(poses)
        .map(|(pair, y)| {
            let rj = rodrigues_to_matrix([y[0], y[1], y[2]]);
            let in_left = |w: &[f64; 2]| {
                let q = mat_vec(&rj, [w[0], w[1], 0.0]);
                [q[0] + y[3], q[1] + y[4], q[2] + y[5]]
            };
            let left = pair.left.board_mm.iter().zip(&pair.left.pixels).map(|(w, px)| one(&pl, in_left(w), px));
            let right = pair.right.board_mm.iter().zip(&pair.right.pixels).map(|(w, px)| {
                let q = mat_vec(&r, in_left(w));
                one(&pr, [q[0] + t[0], q[1] + t[1], q[2] + t[2]], px)
            });
            [left.collect(), right.collect()]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One row: residual, d/dx, d/dy.
    type Row<const N: usize> = (f64, [f64; N], [f64; 6]);

    /// Collects every row.
    struct Rows<const N: usize>(Vec<Row<N>>);

    impl<const N: usize> BlockRowSink<N, 6> for Rows<N> {
        fn push(&mut self, r: f64, jx: &[f64; N], jy: &[f64; 6]) {
            self.0.push((r, *jx, *jy));
        }
    }

    fn rows<const N: usize>(p: &mut StereoProblem<'_>, x: &[f64; N], y: &[f64; 6], jac: bool) -> Rows<N> {
        let mut sink = Rows(vec![]);
        p.eval_block(0, x, y, jac, &mut sink).unwrap();
        sink
    }

    /// The analytic Jacobian of both cameras' rows, with respect to R, T, every intrinsic
    /// of both cameras (OpenCV's family, all free) and the pair's pose, agrees with central
    /// differences to 1e-6 relative (absolute below 1).
    #[test]
    fn jacobian_matches_central_differences() {
        let board: Vec<[f64; 2]> = (0..12).map(|k| [30.0 * (k % 4) as f64, 40.0 * (k / 4) as f64]).collect();
        let view = PlanarView { board_mm: board.clone(), pixels: vec![[600.0, 450.0]; board.len()] };
        let pairs = [PairPoints { left: view.clone(), right: view }];
        let free: Vec<usize> = (0..9).collect();
        let left = [1000.0, 990.0, 640.0, 480.0, -0.2, 0.08, 1e-3, -2e-3, -0.02];
        let right = [980.0, 985.0, 630.0, 470.0, -0.15, 0.05, -1e-3, 5e-4, 0.01];
        let mut p = StereoProblem {
            pairs: &pairs,
            model: DistortionModel::OpenCv,
            left,
            right,
            left_free: &free,
            right_free: &free,
        };
        let mut x = [0.0; 24];
        x[..6].copy_from_slice(&[0.02, -0.15, 0.01, -120.0, 2.0, 5.0]);
        x[6..15].copy_from_slice(&left);
        x[15..].copy_from_slice(&right);
        let y = [0.3, -0.2, 0.1, -40.0, -30.0, 600.0];
        let analytic = rows(&mut p, &x, &y, true);
        assert_eq!(analytic.0.len(), 48);
        let check = |k: usize, numeric: Vec<f64>, pick: &dyn Fn(&Row<24>) -> f64| {
            for (row, n) in analytic.0.iter().zip(numeric) {
                let a = pick(row);
                assert!((a - n).abs() <= 1e-6 * a.abs().max(1.0), "column {k}: analytic {a}, numeric {n}");
            }
        };
        for k in 0..24 {
            let h = 1e-6 * x[k].abs().max(1.0);
            let (mut xp, mut xm) = (x, x);
            xp[k] += h;
            xm[k] -= h;
            let (rp, rm) = (rows(&mut p, &xp, &y, false), rows(&mut p, &xm, &y, false));
            let numeric = rp.0.iter().zip(&rm.0).map(|(a, b)| (a.0 - b.0) / (2.0 * h)).collect();
            check(k, numeric, &|r| r.1[k]);
        }
        for k in 0..6 {
            let h = 1e-6 * y[k].abs().max(1.0);
            let (mut yp, mut ym) = (y, y);
            yp[k] += h;
            ym[k] -= h;
            let (rp, rm) = (rows(&mut p, &x, &yp, false), rows(&mut p, &x, &ym, false));
            let numeric = rp.0.iter().zip(&rm.0).map(|(a, b)| (a.0 - b.0) / (2.0 * h)).collect();
            check(24 + k, numeric, &|r| r.2[k]);
        }
    }
}
