//! The LM solvers on problems with known answers, and their bad inputs.

use etl_core::lm::{
    solve, solve_blocks, solve_blocks_scratch, Accumulation, BlockProblem, BlockRowSink, BlockScratch, Options,
    Problem, RowSink, StopReason,
};
use etl_core::Error;

/// Three circles sharing one radius; noisy points on each.
fn circle_points() -> (Vec<[f64; 2]>, Vec<Vec<[f64; 2]>>) {
    let centres = vec![[1.0, 2.0], [-3.0, 0.5], [4.0, -2.0]];
    let r = 2.5;
    let pts = centres
        .iter()
        .enumerate()
        .map(|(c, ctr)| {
            (0..12)
                .map(|i| {
                    let t = i as f64 * 0.5 + c as f64;
                    let noise = 0.01 * ((i * 7 + c * 3) as f64).sin();
                    [ctr[0] + (r + noise) * t.cos(), ctr[1] + (r + noise) * t.sin()]
                })
                .collect()
        })
        .collect();
    (centres, pts)
}

struct Circles<'a>(&'a [Vec<[f64; 2]>]);

impl BlockProblem<1, 2> for Circles<'_> {
    fn block_count(&self) -> usize {
        self.0.len()
    }
    fn eval_block(
        &mut self,
        b: usize,
        x: &[f64; 1],
        y: &[f64; 2],
        _jac: bool,
        sink: &mut dyn BlockRowSink<1, 2>,
    ) -> etl_core::Result<()> {
        for p in &self.0[b] {
            let (dx, dy) = (p[0] - y[0], p[1] - y[1]);
            let d = (dx * dx + dy * dy).sqrt();
            sink.push(d - x[0], &[-1.0], &[-dx / d, -dy / d]);
        }
        Ok(())
    }
}

/// The same problem stacked densely: [r, c1x, c1y, c2x, c2y, c3x, c3y].
struct Stacked<'a>(&'a [Vec<[f64; 2]>]);

impl Problem<7> for Stacked<'_> {
    fn eval(&mut self, x: &[f64; 7], _jac: bool, sink: &mut dyn RowSink<7>) -> etl_core::Result<()> {
        for (b, pts) in self.0.iter().enumerate() {
            for p in pts {
                let (dx, dy) = (p[0] - x[1 + 2 * b], p[1] - x[2 + 2 * b]);
                let d = (dx * dx + dy * dy).sqrt();
                let mut j = [0.0; 7];
                j[0] = -1.0;
                j[1 + 2 * b] = -dx / d;
                j[2 + 2 * b] = -dy / d;
                sink.push(d - x[0], &j);
            }
        }
        Ok(())
    }
}

#[test]
fn block_solver_agrees_with_the_dense_solver() {
    let (centres, pts) = circle_points();
    let mut scratch = vec![BlockScratch::<1, 2>::ZERO; solve_blocks_scratch::<1, 2>(3)];
    for (s, c) in scratch.iter_mut().zip(&centres) {
        s.set_y([c[0] + 0.3, c[1] - 0.2]);
    }
    let rb = solve_blocks(&mut Circles(&pts), [2.0], &Options::default(), &mut scratch).unwrap();
    let y: Vec<[f64; 2]> = scratch.iter().map(|s| *s.y()).collect();
    let x0 = [
        2.0,
        centres[0][0] + 0.3,
        centres[0][1] - 0.2,
        centres[1][0] + 0.3,
        centres[1][1] - 0.2,
        centres[2][0] + 0.3,
        centres[2][1] - 0.2,
    ];
    let rd = solve(&mut Stacked(&pts), x0, &Options::default()).unwrap();
    assert!(rb.stop.converged() && rd.stop.converged(), "{:?} {:?}", rb.stop, rd.stop);
    assert!((rb.x[0] - rd.x[0]).abs() < 1e-10, "{} vs {}", rb.x[0], rd.x[0]);
    for b in 0..3 {
        assert!((y[b][0] - rd.x[1 + 2 * b]).abs() < 1e-10 && (y[b][1] - rd.x[2 + 2 * b]).abs() < 1e-10);
    }
    assert!((rb.cost - rd.cost).abs() <= 1e-10 * rd.cost);
    // The marginal variance of the shared radius equals the dense covariance's entry.
    assert!((rb.covariance[0][0] - rd.covariance[0][0]).abs() < 1e-6 * rd.covariance[0][0]);
    assert!((rb.x[0] - 2.5).abs() < 0.01);
}

struct Line {
    dependent: bool,
}

impl Problem<2> for Line {
    fn eval(&mut self, x: &[f64; 2], _jac: bool, sink: &mut dyn RowSink<2>) -> etl_core::Result<()> {
        for i in 0..10 {
            let t = i as f64;
            if self.dependent {
                // y = (a + b) t: only a + b is determined.
                sink.push((x[0] + x[1]) * t - 3.0 * t, &[t, t]);
            } else {
                sink.push(x[0] + x[1] * t - (1.0 + 2.0 * t), &[1.0, t]);
            }
        }
        Ok(())
    }
}

#[test]
fn linear_problem_is_solved_exactly() {
    let r = solve(&mut Line { dependent: false }, [0.0, 0.0], &Options::default()).unwrap();
    assert!((r.x[0] - 1.0).abs() < 1e-12 && (r.x[1] - 2.0).abs() < 1e-12, "{:?}", r.x);
    assert!(r.iterations <= 10 && r.stop.converged(), "{:?} after {}", r.stop, r.iterations);
}

#[test]
fn rank_deficiency_is_reported() {
    let r = solve(&mut Line { dependent: true }, [0.0, 0.0], &Options::default()).unwrap();
    assert_eq!(r.stop, StopReason::RankDeficient);
    assert_eq!(r.rank, 1);
    assert!((r.x[0] + r.x[1] - 3.0).abs() < 1e-10);
}

struct Failing;

impl Problem<1> for Failing {
    fn eval(&mut self, _x: &[f64; 1], _jac: bool, _sink: &mut dyn RowSink<1>) -> etl_core::Result<()> {
        Err(Error::BehindCamera)
    }
}

struct Nothing;

impl Problem<1> for Nothing {
    fn eval(&mut self, _x: &[f64; 1], _jac: bool, _sink: &mut dyn RowSink<1>) -> etl_core::Result<()> {
        Ok(())
    }
}

#[test]
fn bad_inputs_are_typed_errors() {
    let e = solve(&mut Line { dependent: false }, [f64::NAN, 0.0], &Options::default()).unwrap_err();
    assert!(matches!(e, Error::NotFinite { .. }), "{e}");
    assert_eq!(solve(&mut Failing, [1.0], &Options::default()).unwrap_err(), Error::BehindCamera);
    assert!(matches!(solve(&mut Nothing, [1.0], &Options::default()).unwrap_err(), Error::TooFew { .. }));
    let (_, pts) = circle_points();
    let mut small = vec![BlockScratch::<1, 2>::ZERO; 2];
    let e = solve_blocks(&mut Circles(&pts), [2.0], &Options::default(), &mut small).unwrap_err();
    assert!(matches!(e, Error::BufferTooSmall { needed: 3, got: 2, .. }), "{e}");
    let mut scratch = vec![BlockScratch::<1, 2>::starting_at([0.0, f64::NAN]); 3];
    let e = solve_blocks(&mut Circles(&pts), [2.0], &Options::default(), &mut scratch).unwrap_err();
    assert!(matches!(e, Error::NotFinite { .. }), "{e}");
}

#[test]
fn normal_equations_accumulation_agrees_with_qr() {
    let (centres, pts) = circle_points();
    let x0 = [
        2.0,
        centres[0][0] + 0.3,
        centres[0][1] - 0.2,
        centres[1][0] + 0.3,
        centres[1][1] - 0.2,
        centres[2][0] + 0.3,
        centres[2][1] - 0.2,
    ];
    let qr = solve(&mut Stacked(&pts), x0, &Options::default()).unwrap();
    let ne =
        solve(&mut Stacked(&pts), x0, &Options { accumulation: Accumulation::NormalEquations, ..Options::default() })
            .unwrap();
    for i in 0..7 {
        assert!((qr.x[i] - ne.x[i]).abs() < 1e-10, "{i}: {} vs {}", qr.x[i], ne.x[i]);
        assert!((qr.covariance[i][i] - ne.covariance[i][i]).abs() < 1e-8 * qr.covariance[i][i]);
    }
    // Rank deficiency is still reported through the semidefinite Cholesky.
    let r = solve(
        &mut Line { dependent: true },
        [0.0, 0.0],
        &Options { accumulation: Accumulation::NormalEquations, ..Options::default() },
    )
    .unwrap();
    assert_eq!(r.stop, StopReason::RankDeficient);
}
