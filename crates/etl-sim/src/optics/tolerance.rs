//! The toleranced system: the centred surfaces of an optics file placed with the ETL
//! decentred and tilted as one body (about its rim plane's centre) and the sensor
//! decentred and tilted about its centre.

use etl_formats::optics::{OpticsFile, Tolerances};

use super::ray::{add, mul, tilt, IDENTITY};
use super::surface::{Placement, Surface};
use super::trace::System;

/// The ETL's surfaces: the first three of [`OpticsFile::centred_surfaces`].
pub const ETL_SURFACES: usize = 3;

/// `file`'s system at current `e_ma` with its tolerances.
pub fn system_at(file: &OpticsFile, e_ma: f64) -> System {
    toleranced(file, e_ma, &file.tolerances)
}

/// `file`'s system at `e_ma` with tolerances `tol` (a test varies them).
pub fn toleranced(file: &OpticsFile, e_ma: f64, tol: &Tolerances) -> System {
    let r_etl = tilt(tol.etl_tilt_deg[0].to_radians(), tol.etl_tilt_deg[1].to_radians());
    let [dx, dy] = tol.etl_decentre_mm;
    let surfaces = file
        .centred_surfaces(e_ma)
        .into_iter()
        .enumerate()
        .map(|(k, s)| {
            let placement = if k < ETL_SURFACES {
                // The body turns about the rim plane's centre, then shifts.
                Placement { origin_mm: add([dx, dy, 0.0], mul(&r_etl, [0.0, 0.0, s.z_mm])), rotation: r_etl }
            } else {
                Placement { origin_mm: [0.0, 0.0, s.z_mm], rotation: IDENTITY }
            };
            Surface {
                name: s.name,
                curvature_per_mm: s.curvature_per_mm,
                index_after: s.index_after,
                semi_diameter_mm: s.semi_diameter_mm,
                placement,
            }
        })
        .collect();
    let [sx, sy] = tol.sensor_decentre_mm;
    let sensor = Placement {
        origin_mm: [sx, sy, file.sensor_z_mm()],
        rotation: tilt(tol.sensor_tilt_deg[0].to_radians(), tol.sensor_tilt_deg[1].to_radians()),
    };
    System { surfaces, stop: file.stop_surface(), sensor }
}
