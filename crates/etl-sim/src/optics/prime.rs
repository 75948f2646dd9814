//! Prime lenses from published prescriptions, scaled to a focal length and stopped down.
//!
//! - [`COOKE_TRIPLET`]: the Cooke triplet of W. J. Smith, *Modern Optical Engineering*,
//!   4th ed. (McGraw-Hill, 2008), chapter 6 (its worked example of a triplet: glasses SK4,
//!   n_d = 1.61272, and SF2, n_d = 1.64769; focal length about 100 mm), the stop 2.00 mm
//!   behind the negative element.
//! - [`DOUBLE_GAUSS`]: the F/1.25 double-Gauss of W. J. Smith, *Modern Lens Design*
//!   (McGraw-Hill, 1992), p. 304, from US patent 2,771,006 (Werfel): EFL 100.1 mm, BFL
//!   56.42 mm, n_d as listed there; semi-diameters as listed.
//!
//! Radii 0 are planes. Each prescription's last thickness is replaced, when scaled, by its
//! paraxial back focus (the sensor in the back focal plane: the prime alone focused at
//! infinity, the ETL's power bringing nearer planes into focus).

use etl_formats::optics::{CentredSurface, SurfaceSpec};

use super::paraxial::{back_focus_mm, entrance_pupil, focal_length_mm};
use super::OpticsError;

/// A published prescription: (radius, thickness, index after, semi-diameter) per surface,
/// mm, and the stop's index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prescription {
    /// Name and source, for the optics file.
    pub source: &'static str,
    /// (radius_mm, thickness_mm, index, semi_diameter_mm) per surface.
    pub surfaces: &'static [(f64, f64, f64, f64)],
    /// Index of the stop.
    pub stop: usize,
    /// The published focal length, mm (None where the source states none).
    pub published_focal_mm: Option<f64>,
    /// The published back focal length, mm.
    pub published_back_focus_mm: Option<f64>,
}

/// See the module docs. The semi-diameters are this project's (the example gives none):
/// generous for the F-numbers it is used at.
pub const COOKE_TRIPLET: Prescription = Prescription {
    source: "Cooke triplet: W. J. Smith, Modern Optical Engineering, 4th ed. (McGraw-Hill, 2008), ch. 6 worked example (SK4 n_d 1.61272, SF2 n_d 1.64769), scaled",
    surfaces: &[
        (37.40, 5.90, 1.61272, 20.0),
        (-341.48, 12.93, 1.0, 20.0),
        (-42.65, 2.50, 1.64769, 14.0),
        (36.40, 2.00, 1.0, 14.0),
        (0.0, 9.85, 1.0, 10.0),
        (204.52, 5.90, 1.61272, 18.0),
        // The last thickness is replaced by the back focus when scaled.
        (-37.05, 80.0, 1.0, 18.0),
    ],
    stop: 4,
    published_focal_mm: None,
    published_back_focus_mm: None,
};

/// See the module docs.
pub const DOUBLE_GAUSS: Prescription = Prescription {
    source: "Double Gauss F/1.25: W. J. Smith, Modern Lens Design (McGraw-Hill, 1992), p. 304, after US 2,771,006 (Werfel), scaled",
    surfaces: &[
        (93.320, 11.320, 1.717, 40.0),
        (358.290, 0.400, 1.0, 40.0),
        (46.320, 20.000, 1.643, 36.0),
        (0.0, 2.000, 1.589, 36.0),
        (28.680, 14.000, 1.0, 24.5),
        (0.0, 10.000, 1.0, 24.3),
        (-41.320, 6.000, 1.762, 24.0),
        (60.800, 22.000, 1.744, 30.0),
        (-55.000, 13.000, 1.0, 30.0),
        (90.200, 16.000, 1.717, 28.0),
        (-212.580, 56.424, 1.0, 28.0),
    ],
    stop: 5,
    published_focal_mm: Some(100.1),
    published_back_focus_mm: Some(56.42),
};

impl Prescription {
    /// The centred surfaces as published, first vertex at z = 0.
    pub fn centred(&self) -> Vec<CentredSurface> {
        let mut z = 0.0;
        self.surfaces
            .iter()
            .enumerate()
            .map(|(k, &(r, t, n, semi))| {
                let s = CentredSurface {
                    name: format!("prime.surfaces[{k}]"),
                    z_mm: z,
                    curvature_per_mm: if r == 0.0 { 0.0 } else { 1.0 / r },
                    index_after: n,
                    semi_diameter_mm: semi,
                };
                z += t;
                s
            })
            .collect()
    }

    /// The prescription scaled by f / f_published (f from the paraxial trace), the last
    /// thickness its back focus, the stop's radius set so the prime alone works at
    /// F-number `f_number` (entrance pupil diameter f / N). Errors: an afocal prescription.
    pub fn scaled(&self, focal_mm: f64, f_number: f64) -> Result<Vec<SurfaceSpec>, OpticsError> {
        let centred = self.centred();
        let k = focal_mm / focal_length_mm(&centred)?;
        let bfl = k * back_focus_mm(&centred)?;
        let ep = entrance_pupil(&centred, self.stop)?;
        // The pupil's magnification of the stop does not change with the scale.
        let stop_semi = self.surfaces[self.stop].3 * (focal_mm / (2.0 * f_number)) / ep.radius_mm;
        let last = self.surfaces.len() - 1;
        Ok(self
            .surfaces
            .iter()
            .enumerate()
            .map(|(i, &(r, t, n, semi))| SurfaceSpec {
                radius_mm: k * r,
                thickness_mm: if i == last { bfl } else { k * t },
                index: n,
                semi_diameter_mm: if i == self.stop { stop_semi } else { k * semi },
            })
            .collect())
    }
}
