//! `etlcal.optics/1`: a physical ETL camera for the ray tracer of `etl_sim::optics`: an
//! electrically tunable lens in front of a prime lens of stated surfaces, its sensor, the
//! assembly tolerances and the calibration procedure traced through it.
//!
//! ```json
//! {"format": "etlcal.optics/1", "name": "cooke-16mm", "source": "W. J. Smith, ...",
//!  "etl": {"power_law_dpt": [8.3, 0.039], "liquid_index": 1.3, "clear_semi_aperture_mm": 5.0,
//!          "edge_thickness_mm": 1.0, "window_thickness_mm": 0.5, "window_index": 1.5168, "gap_mm": 1.5},
//!  "prime": {"surfaces": [{"radius_mm": 5.98, "thickness_mm": 0.94, "index": 1.61272, "semi_diameter_mm": 3.0},
//!                         ...], "stop": 4},
//!  "sensor": {"pixel_pitch_mm": 0.0022, "size_px": [1936, 1458]},
//!  "tolerances": {"etl_decentre_mm": [0, 0], "etl_tilt_deg": [0, 0],
//!                 "sensor_decentre_mm": [0, 0], "sensor_tilt_deg": [0, 0]},
//!  "procedure": {"e_com_ma": [80, 100, 125, 150, 175, 200, 225], "temperature_c": 27,
//!                "board": {"inner_corners": [14, 12], "square_mm": 1.5}, "stage_origin_mm": 50,
//!                "stage_rotation_rodrigues": [0.004, -0.003, 0.002],
//!                "lens_off_board": {"inner_corners": [11, 8], "square_mm": 4.0},
//!                "setting_views_per_current": 8, "setting_tilt_deg": 15, "fan_rings": 4,
//!                "pixel_noise_px": 0.05}}
//! ```
//!
//! Geometry (all lengths mm, along the optical axis z, light travelling towards +z; z = 0
//! is the ETL's rim plane, where its membrane is clamped):
//! - The ETL: a membrane sphere (air to a liquid of `liquid_index`) whose curvature follows
//!   the power law P(E) = p0 + p1 E (dioptres, E in mA; `power_law_dpt` = [p0, p1]):
//!   c(E) = P(E) / (1000 (n_liquid - 1)) per mm (a thin membrane in air bounding a
//!   plano-convex liquid lens: the lensmaker's equation with the plane side adding no
//!   power). The membrane is clamped at the rim of `clear_semi_aperture_mm` = a, so its
//!   vertex stands the sag s(E) = c a^2 / (1 + sqrt(1 - c^2 a^2)) in front of the rim
//!   plane, and the liquid's centre thickness is `edge_thickness_mm` + s(E) (the liquid the
//!   reservoir pushes in fills the cap). Then a plane window of `window_index` and
//!   `window_thickness_mm` from z = `edge_thickness_mm`, and `gap_mm` of air.
//! - The prime lens: `surfaces` in order, each a sphere of `radius_mm` (0 for a plane;
//!   positive: centre of curvature behind the vertex) followed by `thickness_mm` of a
//!   medium of refractive `index` up to the next surface; the last one's thickness is the
//!   distance to the sensor. `stop` is the index of the aperture stop, a plane surface in
//!   air whose `semi_diameter_mm` is the stop's radius.
//! - The sensor: `size_px` pixels of `pixel_pitch_mm`, centred on the axis (up to its
//!   tolerance), read out upright (the lens inverts the image).
//! - `tolerances`: the ETL decentred (x, y) and tilted (about x, then y, degrees) as one
//!   body about its rim plane's centre; the sensor likewise about its centre.
//! - `procedure` (the paper's, section 5.1.2): one view per current of `e_com_ma` with the
//!   board of `board` on the stage at the distance in focus at that current; the stage
//!   axis is the lens axis turned by `stage_rotation_rodrigues`; stage position 0 stands
//!   `stage_origin_mm` from the rim plane. Lens-off views (for A0) of `lens_off_board` at
//!   E = 0 mA (the ETL left in, at its zero-current power); `setting_views_per_current`
//!   tilted views (up to `setting_tilt_deg`) per current for a monofocal calibration at
//!   each current (0: none); `fan_rings` rings of rays over the stop per image point;
//!   `pixel_noise_px` of Gaussian noise on every observed pixel.
//!
//! [`OpticsFile::validate`] checks every value, and traces the centred system paraxially
//! at every current of the procedure and at 0 mA: an afocal (singular) system, a current
//! at which nothing in front of the lens is in focus, and a surface that the rays filling
//! the stop from anywhere in the field would miss are refused, naming the field.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{compact, read_json, write_json};
use crate::{check_image_size, check_range, Checkerboard, Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.optics/1";

/// The ETL: its power law and its body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EtlSpec {
    /// [p0, p1]: P(E) = p0 + p1 E, dioptres (E in mA).
    pub power_law_dpt: [f64; 2],
    /// Refractive index of the liquid.
    pub liquid_index: f64,
    /// Radius of the membrane's clamped rim (the clear aperture), mm.
    pub clear_semi_aperture_mm: f64,
    /// Liquid thickness at the rim, mm.
    pub edge_thickness_mm: f64,
    /// Thickness of the window, mm.
    pub window_thickness_mm: f64,
    /// Refractive index of the window.
    pub window_index: f64,
    /// Air from the window's rear face to the prime lens's first vertex, mm.
    pub gap_mm: f64,
}

impl EtlSpec {
    /// P(E), dioptres.
    pub fn power_dpt(&self, e_ma: f64) -> f64 {
        self.power_law_dpt[0] + self.power_law_dpt[1] * e_ma
    }

    /// The membrane's curvature at `e_ma`: c = P / (1000 (n_liquid - 1)), 1/mm.
    pub fn membrane_curvature_per_mm(&self, e_ma: f64) -> f64 {
        self.power_dpt(e_ma) / (1000.0 * (self.liquid_index - 1.0))
    }

    /// The membrane's sag over the clear aperture a: s = c a^2 / (1 + sqrt(1 - c^2 a^2)),
    /// mm (the form without cancellation near c = 0); NaN where c a > 1.
    pub fn sag_mm(&self, e_ma: f64) -> f64 {
        let (c, a) = (self.membrane_curvature_per_mm(e_ma), self.clear_semi_aperture_mm);
        c * a * a / (1.0 + (1.0 - c * c * a * a).sqrt())
    }
}

/// One surface of the prime lens.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSpec {
    /// Radius of curvature, mm (0: a plane; positive: centre of curvature behind).
    pub radius_mm: f64,
    /// Distance to the next surface (the last: to the sensor), mm.
    pub thickness_mm: f64,
    /// Refractive index of the medium after the surface.
    pub index: f64,
    /// Semi-diameter (clear aperture radius), mm.
    pub semi_diameter_mm: f64,
}

/// The prime lens.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrimeSpec {
    /// The surfaces in order.
    pub surfaces: Vec<SurfaceSpec>,
    /// Index in `surfaces` of the aperture stop (a plane in air).
    pub stop: usize,
}

/// The sensor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Pixel pitch, mm.
    pub pixel_pitch_mm: f64,
    /// Width and height, px.
    pub size_px: [u32; 2],
}

/// Assembly tolerances (all zero: a centred rig).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerances {
    /// The ETL's decentre (x, y), mm.
    pub etl_decentre_mm: [f64; 2],
    /// The ETL's tilt about x, then y, degrees.
    pub etl_tilt_deg: [f64; 2],
    /// The sensor's decentre (x, y), mm.
    pub sensor_decentre_mm: [f64; 2],
    /// The sensor's tilt about x, then y, degrees.
    pub sensor_tilt_deg: [f64; 2],
}

/// A checkerboard by its fields.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoardSpec {
    /// Inner corners, [cols, rows].
    pub inner_corners: [usize; 2],
    /// Side of a square, mm.
    pub square_mm: f64,
}

/// The calibration procedure traced through the optics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Procedure {
    /// The ETL views' currents, mA (one view each, the board in focus).
    pub e_com_ma: Vec<f64>,
    /// The lens temperature recorded with every view, degC.
    pub temperature_c: f64,
    /// The board on the stage.
    pub board: BoardSpec,
    /// Distance from the ETL's rim plane to the board at stage position 0, mm.
    pub stage_origin_mm: f64,
    /// The stage axis's rotation from the optical axis (Rodrigues, radians).
    pub stage_rotation_rodrigues: [f64; 3],
    /// The lens-off views' board (at E = 0 mA).
    pub lens_off_board: BoardSpec,
    /// Tilted views per current for a monofocal calibration at each current (0: none).
    pub setting_views_per_current: usize,
    /// Largest tilt of those views, degrees.
    pub setting_tilt_deg: f64,
    /// Rings of rays over the stop per image point (ring k has 6 k rays).
    pub fan_rings: usize,
    /// Gaussian noise of every observed pixel, px (seeded).
    pub pixel_noise_px: f64,
}

/// An `etlcal.optics/1` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpticsFile {
    /// `"etlcal.optics/1"`.
    pub format: String,
    /// The rig's name.
    pub name: String,
    /// Where the prime lens's prescription comes from.
    pub source: String,
    /// The ETL.
    pub etl: EtlSpec,
    /// The prime lens.
    pub prime: PrimeSpec,
    /// The sensor.
    pub sensor: SensorSpec,
    /// Assembly tolerances.
    pub tolerances: Tolerances,
    /// The procedure.
    pub procedure: Procedure,
}

/// A surface of the centred system: its vertex on the axis, its curvature, the medium after
/// it, its clear radius, and the file's name for it (for messages).
#[derive(Debug, Clone, PartialEq)]
pub struct CentredSurface {
    /// The file's name for the surface (`etl.membrane`, `prime.surfaces[3]`).
    pub name: String,
    /// Vertex position on the axis, mm.
    pub z_mm: f64,
    /// Curvature 1/R, 1/mm (0: a plane).
    pub curvature_per_mm: f64,
    /// Refractive index after the surface.
    pub index_after: f64,
    /// Clear radius, mm.
    pub semi_diameter_mm: f64,
}

/// A paraxial ray (y-nu form): height y, mm, and reduced slope nu = n u at a plane.
pub type YNu = [f64; 2];

/// Traces `ray` (at plane `z_from_mm`, in air) through `surfaces` (centred, in order) to
/// the plane `z_to_mm` behind the last: refraction nu' = nu - y c (n' - n), transfer
/// y' = y + d nu / n. Returns the ray at every surface and at `z_to_mm` (last).
pub fn trace_paraxial(surfaces: &[CentredSurface], ray: YNu, z_from_mm: f64, z_to_mm: f64) -> Vec<YNu> {
    let ([mut y, mut nu], mut z, mut n) = (ray, z_from_mm, 1.0);
    let mut out = Vec::with_capacity(surfaces.len() + 1);
    for s in surfaces {
        y += (s.z_mm - z) * nu / n;
        nu -= y * s.curvature_per_mm * (s.index_after - n);
        out.push([y, nu]);
        (z, n) = (s.z_mm, s.index_after);
    }
    out.push([y + (z_to_mm - z) * nu / n, nu]);
    out
}

/// The system matrix [[A, B], [C, D]] mapping (y, nu) at `z_from_mm` to (y, nu) at
/// `z_to_mm` (two paraxial rays: [`trace_paraxial`] is linear).
pub fn system_matrix(surfaces: &[CentredSurface], z_from_mm: f64, z_to_mm: f64) -> [[f64; 2]; 2] {
    let last = |ray| trace_paraxial(surfaces, ray, z_from_mm, z_to_mm).last().copied().unwrap_or(ray);
    let ([a, c], [b, d]) = (last([1.0, 0.0]), last([0.0, 1.0]));
    [[a, b], [c, d]]
}

/// Smallest |C| (1/mm) of a system that is not afocal: a focal length below 1e9 mm.
pub const MIN_POWER_PER_MM: f64 = 1e-9;
/// The most surfaces of a prime lens.
pub const MAX_SURFACES: usize = 64;
/// The most rings of a fan (1 + 3 R (R + 1) rays).
pub const MAX_FAN_RINGS: usize = 32;

impl OpticsFile {
    /// Reads and checks a file ([`Self::validate`]).
    pub fn load(path: &Path) -> Result<Self> {
        let f: OpticsFile = read_json(path, FORMAT)?;
        f.validate().map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })?;
        Ok(f)
    }

    /// Checks and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate().map_err(|e| e.within(path.display(), None))?;
        write_json(path, self)
    }

    /// The centred system at current `e_ma` (no tolerances): the ETL's membrane, window
    /// front and rear, then the prime lens's surfaces; z = 0 at the rim plane.
    pub fn centred_surfaces(&self, e_ma: f64) -> Vec<CentredSurface> {
        let etl = &self.etl;
        let a = etl.clear_semi_aperture_mm;
        let surface = |name: &str, z_mm, c, n, semi| CentredSurface {
            name: name.to_owned(),
            z_mm,
            curvature_per_mm: c,
            index_after: n,
            semi_diameter_mm: semi,
        };
        let (front, rear) = (etl.edge_thickness_mm, etl.edge_thickness_mm + etl.window_thickness_mm);
        let mut out = vec![
            surface("etl.membrane", -etl.sag_mm(e_ma), etl.membrane_curvature_per_mm(e_ma), etl.liquid_index, a),
            surface("etl.window front", front, 0.0, etl.window_index, a),
            surface("etl.window rear", rear, 0.0, 1.0, a),
        ];
        let mut z = rear + etl.gap_mm;
        for (k, s) in self.prime.surfaces.iter().enumerate() {
            let c = if s.radius_mm == 0.0 { 0.0 } else { 1.0 / s.radius_mm };
            out.push(surface(&format!("prime.surfaces[{k}]"), z, c, s.index, s.semi_diameter_mm));
            z += s.thickness_mm;
        }
        out
    }

    /// The sensor plane's position on the axis, mm (the last surface plus its thickness).
    pub fn sensor_z_mm(&self) -> f64 {
        let etl = &self.etl;
        let lens: f64 = self.prime.surfaces.iter().map(|s| s.thickness_mm).sum();
        etl.edge_thickness_mm + etl.window_thickness_mm + etl.gap_mm + lens
    }

    /// Index in [`Self::centred_surfaces`] of the stop.
    pub fn stop_surface(&self) -> usize {
        3 + self.prime.stop
    }

    /// Paraxial distance (mm, in front of the rim plane) of the object plane in focus on
    /// the sensor at `e_ma`: with the system matrix M from the rim plane to the sensor, an
    /// object s in front images on the sensor where A s + B = 0, s = -B / A. Errors: an
    /// afocal system (singular), or no real object plane in focus (A = 0 or s <= 0).
    pub fn paraxial_focus_distance_mm(&self, e_ma: f64) -> Result<f64> {
        let surfaces = self.centred_surfaces(e_ma);
        let [[_, _], [c, _]] = system_matrix(&surfaces, 0.0, surfaces.last().map_or(0.0, |s| s.z_mm));
        if !(c.abs() >= MIN_POWER_PER_MM) {
            let message = format!(
                "prime.surfaces: the optics are afocal at {} mA (power {} dpt): singular",
                compact(e_ma),
                compact(0.0 - 1000.0 * c)
            );
            return Err(Error::invalid_value("prime.surfaces", compact(e_ma), message));
        }
        let [[a, b], _] = system_matrix(&surfaces, 0.0, self.sensor_z_mm());
        let s = -b / a;
        if !(s.is_finite() && s > 0.0) {
            // The sensor's distance decides it: the last surface's thickness.
            let k = self.prime.surfaces.len() - 1;
            let key = format!("prime.surfaces[{k}].thickness_mm");
            let message = format!(
                "{key}: at {} mA no object in front of the lens is in focus on the sensor {} mm behind the last surface",
                compact(e_ma),
                compact(self.prime.surfaces[k].thickness_mm)
            );
            return Err(Error::invalid_value(key, self.prime.surfaces[k].thickness_mm, message));
        }
        Ok(s)
    }

    /// See the module docs.
    pub fn validate(&self) -> Result<()> {
        if self.format != FORMAT {
            return Err(Error::invalid_value("format", self.format.as_str(), format!("format must be \"{FORMAT}\"")));
        }
        if self.name.trim().is_empty() || self.source.trim().is_empty() {
            let key = if self.name.trim().is_empty() { "name" } else { "source" };
            return Err(Error::invalid(key, format!("{key} must not be empty")));
        }
        self.validate_etl()?;
        self.validate_prime()?;
        check_image_size(self.sensor.size_px, "sensor.size_px")?;
        check_range("sensor.pixel_pitch_mm", self.sensor.pixel_pitch_mm, [1e-4, 0.1], "mm")?;
        let t = &self.tolerances;
        for (key, v, hi, unit) in [
            ("tolerances.etl_decentre_mm", t.etl_decentre_mm, 1.0, "mm"),
            ("tolerances.etl_tilt_deg", t.etl_tilt_deg, 5.0, "deg"),
            ("tolerances.sensor_decentre_mm", t.sensor_decentre_mm, 1.0, "mm"),
            ("tolerances.sensor_tilt_deg", t.sensor_tilt_deg, 5.0, "deg"),
        ] {
            for x in v {
                check_range(key, x, [-hi, hi], unit)?;
            }
        }
        self.validate_procedure()?;
        for e in std::iter::once(0.0).chain(self.procedure.e_com_ma.iter().copied()) {
            self.check_rays_pass(e)?;
        }
        Ok(())
    }

    fn validate_etl(&self) -> Result<()> {
        let etl = &self.etl;
        for (k, p) in etl.power_law_dpt.into_iter().enumerate() {
            check_range(&format!("etl.power_law_dpt[{k}]"), p, [-1e3, 1e3], "dpt")?;
        }
        check_range("etl.liquid_index", etl.liquid_index, [1.01, 3.0], "")?;
        check_range("etl.window_index", etl.window_index, [1.0, 3.0], "")?;
        check_range("etl.clear_semi_aperture_mm", etl.clear_semi_aperture_mm, [0.1, 50.0], "mm")?;
        check_range("etl.edge_thickness_mm", etl.edge_thickness_mm, [0.0, 50.0], "mm")?;
        check_range("etl.window_thickness_mm", etl.window_thickness_mm, [0.0, 50.0], "mm")?;
        check_range("etl.gap_mm", etl.gap_mm, [0.0, 1000.0], "mm")?;
        Ok(())
    }

    fn validate_prime(&self) -> Result<()> {
        let p = &self.prime;
        if p.surfaces.is_empty() || p.surfaces.len() > MAX_SURFACES {
            let message = format!("prime.surfaces: 1 to {MAX_SURFACES} surfaces, got {}", p.surfaces.len());
            return Err(Error::invalid_value("prime.surfaces", p.surfaces.len(), message));
        }
        for (k, s) in p.surfaces.iter().enumerate() {
            let key = |f: &str| format!("prime.surfaces[{k}].{f}");
            if !s.radius_mm.is_finite() || (s.radius_mm != 0.0 && s.radius_mm.abs() < 0.1) {
                let message = format!(
                    "{}: a radius of {} mm (0 for a plane, else at least 0.1 mm)",
                    key("radius_mm"),
                    compact(s.radius_mm)
                );
                return Err(Error::invalid_value(key("radius_mm"), s.radius_mm, message));
            }
            check_range(&key("thickness_mm"), s.thickness_mm, [0.0, 1000.0], "mm")?;
            check_range(&key("index"), s.index, [1.0, 3.0], "")?;
            check_range(&key("semi_diameter_mm"), s.semi_diameter_mm, [0.01, 100.0], "mm")?;
        }
        let before = |k: usize| if k == 0 { 1.0 } else { p.surfaces[k - 1].index };
        match p.surfaces.get(p.stop) {
            Some(s) if s.radius_mm == 0.0 && s.index == 1.0 && before(p.stop) == 1.0 => Ok(()),
            Some(_) => Err(Error::invalid_value(
                "prime.stop",
                p.stop,
                format!("prime.stop: surface {} is not a plane in air (radius_mm 0, air on both sides)", p.stop),
            )),
            None => Err(Error::invalid_value(
                "prime.stop",
                p.stop,
                format!("prime.stop {} is not one of the {} surfaces", p.stop, p.surfaces.len()),
            )),
        }
    }

    fn validate_procedure(&self) -> Result<()> {
        let p = &self.procedure;
        if p.e_com_ma.len() < 3 || p.e_com_ma.len() > 1000 {
            let message = format!("procedure.e_com_ma: 3 to 1000 currents, got {}", p.e_com_ma.len());
            return Err(Error::invalid_value("procedure.e_com_ma", p.e_com_ma.len(), message));
        }
        for e in &p.e_com_ma {
            check_range("procedure.e_com_ma", *e, etl_core::thermal::E_IN_DOMAIN_MA, "mA")?;
        }
        check_range("procedure.temperature_c", p.temperature_c, [-40.0, 120.0], "degC")?;
        for (key, b) in [("procedure.board", p.board), ("procedure.lens_off_board", p.lens_off_board)] {
            Checkerboard { inner_corners: b.inner_corners, square_mm: b.square_mm }
                .validate()
                .map_err(|e| e.within(key, None))?;
        }
        check_range("procedure.stage_origin_mm", p.stage_origin_mm, [0.0, 1e4], "mm")?;
        for x in p.stage_rotation_rodrigues {
            check_range("procedure.stage_rotation_rodrigues", x, [-0.2, 0.2], "rad")?;
        }
        if p.setting_views_per_current > 1000 {
            let message = format!("procedure.setting_views_per_current {}: at most 1000", p.setting_views_per_current);
            return Err(Error::invalid_value(
                "procedure.setting_views_per_current",
                p.setting_views_per_current,
                message,
            ));
        }
        check_range("procedure.pixel_noise_px", p.pixel_noise_px, [0.0, 100.0], "px")?;
        check_range("procedure.setting_tilt_deg", p.setting_tilt_deg, [0.0, 60.0], "deg")?;
        if !(1..=MAX_FAN_RINGS).contains(&p.fan_rings) {
            let message = format!("procedure.fan_rings {}: 1 to {MAX_FAN_RINGS} rings", p.fan_rings);
            return Err(Error::invalid_value("procedure.fan_rings", p.fan_rings, message));
        }
        Ok(())
    }

    /// At `e_ma`, the paraxial rays from the in-focus object plane that fill the stop,
    /// from the axis to the sensor's corner, pass every surface: at each, the marginal
    /// ray's height plus the chief ray's is within its semi-diameter.
    fn check_rays_pass(&self, e_ma: f64) -> Result<()> {
        let s_obj = self.paraxial_focus_distance_mm(e_ma)?;
        let surfaces = self.centred_surfaces(e_ma);
        let stop = self.stop_surface();
        let (z0, z_sensor) = (-s_obj, self.sensor_z_mm());
        // Marginal: from the axial object point (y = 0) with the slope that reaches the
        // stop's edge; chief: through the stop's centre to the sensor's corner.
        let at_stop = |ray: YNu| trace_paraxial(&surfaces, ray, z0, z_sensor)[stop][0];
        let semi_stop = surfaces[stop].semi_diameter_mm;
        let marginal = [0.0, semi_stop / at_stop([0.0, 1.0])];
        let (ya, yb) = (at_stop([1.0, 0.0]), at_stop([0.0, 1.0]));
        // Chief ray (h, u) with ya h + yb u = 0: (h, u) = t (yb, -ya), scaled to the corner.
        let unit = trace_paraxial(&surfaces, [yb, -ya], z0, z_sensor);
        let [w, h] = self.sensor.size_px.map(|n| 0.5 * n as f64 * self.sensor.pixel_pitch_mm);
        let t = w.hypot(h) / unit.last().map_or(f64::NAN, |r| r[0]).abs();
        let m = trace_paraxial(&surfaces, marginal, z0, z_sensor);
        for (k, s) in surfaces.iter().enumerate() {
            let height = m[k][0].abs() + t * unit[k][0].abs();
            if k != stop && !(height <= s.semi_diameter_mm) {
                let key = if k < 3 {
                    "etl.clear_semi_aperture_mm".to_owned()
                } else {
                    format!("{}.semi_diameter_mm", s.name)
                };
                let message = format!(
                    "{key}: at {} mA the rays that fill the stop miss {} (they reach {} mm, its semi-diameter is {} mm)",
                    compact(e_ma),
                    s.name,
                    compact((height * 1e4).round() / 1e4),
                    compact(s.semi_diameter_mm)
                );
                return Err(Error::invalid_value(key, s.semi_diameter_mm, message));
            }
        }
        Ok(())
    }
}
