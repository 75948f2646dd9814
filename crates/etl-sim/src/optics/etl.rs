//! The ETL's closed forms, against which the traced lens is tested, and the paraxial
//! pupil shift an ETL in front of a prime lens causes (docs/METHOD.md, "Physical optics").
//!
//! The ETL (its geometry: [`etl_formats::optics`]) is a membrane sphere of curvature
//! c(E) = P(E) / (1000 (n_l - 1)) bounding a liquid of index n_l, behind it plane
//! surfaces only. Its power is the lensmaker's equation of a thick lens with R2 = inf,
//! P = (n_l - 1) (1/R1 - 1/R2 + (n_l - 1) t / (n_l R1 R2)) = (n_l - 1) / R1 whatever its
//! thickness t: the power law exactly.

use etl_formats::optics::EtlSpec;

/// The lensmaker's equation for a thick lens of index `n` in air with radii `r1_mm`,
/// `r2_mm` (infinite for a plane) and centre thickness `t_mm`: power, dioptres.
pub fn lensmaker_power_dpt(n: f64, r1_mm: f64, r2_mm: f64, t_mm: f64) -> f64 {
    let (c1, c2) = (1.0 / r1_mm, 1.0 / r2_mm);
    1000.0 * (n - 1.0) * (c1 - c2 + (n - 1.0) * t_mm * c1 * c2 / n)
}

/// The ETL's power at `e_ma` by the lensmaker's equation of its liquid lens
/// (membrane radius from the law, plane rear), dioptres.
pub fn etl_lensmaker_power_dpt(etl: &EtlSpec, e_ma: f64) -> f64 {
    let r1 = 1.0 / etl.membrane_curvature_per_mm(e_ma);
    lensmaker_power_dpt(etl.liquid_index, r1, f64::INFINITY, etl.edge_thickness_mm + etl.sag_mm(e_ma))
}

/// Where a thin lens of power `p_dpt` images a point `a_mm` behind it (the prime lens's
/// own entrance pupil) into object space, mm behind the lens: the Gaussian equation
/// 1/a - 1/s = P (light left to right, both distances behind the lens) gives
/// s = a / (1 - a P). So the entrance pupil moves back by ds/dP = s^2 (about a^2 per
/// dioptre, in mm with P in 1/mm) as the ETL's power grows.
pub fn thin_lens_pupil_mm(a_mm: f64, p_dpt: f64) -> f64 {
    a_mm / (1.0 - a_mm * p_dpt / 1000.0)
}
