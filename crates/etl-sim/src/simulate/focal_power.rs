//! The paper rig run in the Lens Driver 4's focal-power mode: each view commands the focal
//! power that focuses its stage position, at one of several lens temperatures, and the
//! driver's firmware compensates the temperature with the virtual lens's residual
//! ([`FocalPowerCompensation`]).
//!
//! View j of the paper rig is at compensated current E_j. Its commanded power is the liquid
//! lens's there, P_j = 1000 / f_liq(E_j) (Eq. 5, [`LensPhysics::paper`]): the power that
//! focuses the stage position. At lens temperature T_j the firmware sets the E_in its model
//! says gives E_j, so the lens runs at E_in - E_T(T_j, E_in), off E_j by the residual
//! r (E_T(T_j, E_in) - E_T(T_ref, E_in)); the current noise of the noise model comes on top.
//! The views record `focal_power_dpt` = P_j and `temperature_c` = T_j, no current.
//!
//! The truth in dioptres: the camera at power P is the paper rig's at E(P), the current
//! where the liquid lens has power P ([`current_for_power_ma`]). That is not a polynomial in
//! P (f_liq is not linear in E), so a focal-power calibration of this rig is judged against
//! physics rather than against its own model.

use etl_core::model::CameraModel;
use etl_core::physics::LensPhysics;
use etl_core::thermal::ThermalSurface;
use etl_formats::observations::ViewObs;
use etl_hw::virtual_lens::FocalPowerCompensation;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::{gauss, lens_off_a0, lens_off_views_of, visible_stage_board, NoiseModel, RigDesign, Simulation};
use etl_formats::observations::{Observations, PointObs};

/// The lens temperatures the focal-power views cycle through, degC: the firmware's
/// compensation is exercised 5 degC either side of the middle.
pub const FOCAL_POWER_TEMPERATURES_C: [f64; 3] = [25.0, 30.0, 35.0];

/// The liquid lens's focal power at compensated current `e_com_ma`, dpt (Eq. 5).
pub fn power_dpt(e_com_ma: f64) -> f64 {
    LensPhysics::paper().power_dpt(e_com_ma)
}

/// The compensated current at which the liquid lens has power `dpt`, mA, within
/// 0..300 mA (NaN out of reach; [`LensPhysics::current_for_power_ma`]).
pub fn current_for_power_ma(dpt: f64) -> f64 {
    LensPhysics::paper().current_for_power_ma(dpt, [0.0, 300.0]).unwrap_or(f64::NAN)
}

/// The paper rig's views in focal-power mode under `noise`, seeded, the temperatures
/// cycling through `temperatures_c` and the firmware compensating with `compensation`
/// (module docs). `true_de_ma` holds each view's true focal-power error, dpt.
pub fn focal_power_rig(
    noise: &NoiseModel,
    seed: u64,
    temperatures_c: &[f64],
    compensation: &FocalPowerCompensation,
) -> Simulation {
    let design = RigDesign::paper();
    let truth: CameraModel = design.truth;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut obs = Observations::new(design.image_size);
    let (mut dzs, mut dps) = (vec![], vec![]);
    for (j, (&z, &e)) in design.z_w_mm.iter().zip(design.e_com_ma).enumerate() {
        let t = temperatures_c[j % temperatures_c.len()];
        let p = power_dpt(e);
        let surface = ThermalSurface::PAPER;
        let e_in = compensation.firmware_e_in_ma(&surface, e, t).unwrap_or(e);
        let e_true = e_in - surface.e_t_ma(e_in, t).unwrap_or(0.0) + gauss(noise.e_ma, &mut rng);
        let dz = gauss(noise.z_mm, &mut rng);
        let mut points = vec![];
        for (w, _) in visible_stage_board(&truth, &design.board, design.image_size, z, e) {
            let real = [w[0] + gauss(noise.xy_mm, &mut rng), w[1] + gauss(noise.xy_mm, &mut rng), z + dz];
            if let Ok(px) = truth.project(real, e_true) {
                let pixel = [px[0] + gauss(noise.px, &mut rng), px[1] + gauss(noise.px, &mut rng)];
                points.push(PointObs { world_mm: [w[0], w[1], z], pixel });
            }
        }
        obs.views.push(ViewObs {
            e_in_ma: f64::NAN,
            focal_power_dpt: Some(p),
            temperature_c: t,
            e_com_ma: None,
            points,
        });
        dzs.push(dz);
        dps.push(power_dpt(e_true) - p);
    }
    obs.offstate_views = lens_off_views_of(&truth, &design.lens_off, design.image_size, noise, &mut rng);
    let a0 = lens_off_a0(&truth, noise, &mut rng);
    Simulation { observations: obs, a0, truth, true_dz_mm: dzs, true_de_ma: dps }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_and_current_are_inverse() {
        for e in [0.0, 80.0, 150.0, 225.0] {
            assert!((current_for_power_ma(power_dpt(e)) - e).abs() < 1e-9, "{e}");
        }
        // Section 5.1.1: f_liq 120.5 mm at 0 mA.
        assert!((power_dpt(0.0) - 1000.0 / 120.5).abs() < 0.01);
        assert!(current_for_power_ma(1.0).is_nan());
    }
}
