//! The ray-traced rig (`etl_sim::optics`) against closed forms: the prescriptions' focal
//! lengths (y-nu trace, system matrix, a real ray near the axis), the ETL's power against
//! the lensmaker's equation, a centred rig's symmetry, ray aiming's convergence, the
//! entrance pupil (paraxial against traced chief rays) and its shift with the current
//! against the thin-lens formula; the fixtures in `fixtures/optics/`.

use std::path::PathBuf;

use etl_formats::optics::{
    system_matrix, trace_paraxial, BoardSpec, EtlSpec, OpticsFile, PrimeSpec, Procedure, SensorSpec, Tolerances,
};
use etl_sim::optics::aim::{aim, paraxial_start};
use etl_sim::optics::etl::{etl_lensmaker_power_dpt, thin_lens_pupil_mm};
use etl_sim::optics::paraxial::{back_focus_mm, entrance_pupil, focal_length_mm};
use etl_sim::optics::prime::{Prescription, COOKE_TRIPLET, DOUBLE_GAUSS};
use etl_sim::optics::ray::Ray;
use etl_sim::optics::rig::lens_frame;
use etl_sim::optics::trace::Apertures;
use etl_sim::optics::{OpticalRig, OpticsError};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics").join(name)
}

const CENTRED: Tolerances = Tolerances {
    etl_decentre_mm: [0.0; 2],
    etl_tilt_deg: [0.0; 2],
    sensor_decentre_mm: [0.0; 2],
    sensor_tilt_deg: [0.0; 2],
};

/// The fixtures' rigs: an EL-10-30-like ETL (P = 8.3 + 0.039 E dpt) in front of `prime`
/// scaled to `focal_mm` at `f_number`, the paper's 15 currents and board.
fn rig_file(
    name: &str,
    prime: &Prescription,
    focal_mm: f64,
    f_number: f64,
    sensor: SensorSpec,
    tol: Tolerances,
) -> OpticsFile {
    let surfaces = prime.scaled(focal_mm, f_number).unwrap();
    let mut f = OpticsFile {
        format: etl_formats::optics::FORMAT.into(),
        name: name.into(),
        source: prime.source.into(),
        etl: EtlSpec {
            power_law_dpt: [8.3, 0.039],
            liquid_index: 1.3,
            clear_semi_aperture_mm: 5.0,
            edge_thickness_mm: 1.0,
            window_thickness_mm: 0.5,
            window_index: 1.5168,
            gap_mm: 3.0,
        },
        prime: PrimeSpec { surfaces, stop: prime.stop },
        sensor,
        tolerances: tol,
        procedure: Procedure {
            e_com_ma: etl_sim::rig::PAPER_E_COM_MA.to_vec(),
            temperature_c: 27.0,
            board: BoardSpec { inner_corners: [14, 12], square_mm: 1.5 },
            stage_origin_mm: 0.0,
            stage_rotation_rodrigues: [0.004, -0.003, 0.002],
            lens_off_board: BoardSpec { inner_corners: [11, 8], square_mm: 4.0 },
            setting_views_per_current: 8,
            setting_tilt_deg: 15.0,
            fan_rings: 4,
            pixel_noise_px: 0.05,
        },
    };
    // Stage position 2 mm at the nearest focus, as the paper's.
    let near = f.paraxial_focus_distance_mm(225.0).unwrap();
    f.procedure.stage_origin_mm = (near - 2.0).floor();
    f
}

fn rigs() -> [OpticsFile; 2] {
    let tol = Tolerances {
        etl_decentre_mm: [0.03, -0.02],
        etl_tilt_deg: [0.1, -0.05],
        sensor_decentre_mm: [0.01, 0.005],
        sensor_tilt_deg: [0.05, 0.03],
    };
    [
        rig_file(
            "cooke-16mm-centred",
            &COOKE_TRIPLET,
            16.0,
            4.0,
            SensorSpec { pixel_pitch_mm: 0.0022, size_px: [1936, 1458] },
            CENTRED,
        ),
        rig_file(
            "double-gauss-25mm-toleranced",
            &DOUBLE_GAUSS,
            25.0,
            5.6,
            SensorSpec { pixel_pitch_mm: 0.00345, size_px: [1440, 1080] },
            tol,
        ),
    ]
}

/// The fixture named `name` (loaded and checked).
fn load(name: &str) -> OpticsFile {
    OpticsFile::load(&fixture(name)).unwrap()
}

fn centred(mut f: OpticsFile) -> OpticalRig {
    f.tolerances = CENTRED;
    OpticalRig::new(f).unwrap()
}

/// The fixtures are the prescriptions scaled as documented (regenerate them from
/// `rigs()` when the prescriptions change).
#[test]
fn the_fixtures_are_the_published_prescriptions_scaled() {
    let [a, b] = rigs();
    assert_eq!(load("cooke-16mm-centred.json"), a);
    assert_eq!(load("double-gauss-25mm-toleranced.json"), b);
    for f in [&a, &b] {
        let prime = &f.centred_surfaces(0.0)[3..];
        let want = if f.name.starts_with("cooke") { 16.0 } else { 25.0 };
        assert!((focal_length_mm(prime).unwrap() - want).abs() < 1e-9, "{}", f.name);
        // The sensor in the prime's back focal plane.
        let last = prime.last().unwrap().z_mm;
        assert!((back_focus_mm(prime).unwrap() - (f.sensor_z_mm() - last)).abs() < 1e-9);
    }
}

/// The focal length three ways: the published figure (Smith's double Gauss: EFL 100.1,
/// BFL 56.42), the system matrix against a y-nu trace of a ray from infinity, and a real
/// ray 1 um off the axis (f = h / sin u', its back focus where it crosses the axis).
#[test]
fn the_focal_length_matches_the_prescription_and_the_paraxial_limit_of_real_rays() {
    let dg = DOUBLE_GAUSS.centred();
    assert!((focal_length_mm(&dg).unwrap() - 100.1).abs() < 0.05, "{}", focal_length_mm(&dg).unwrap());
    assert!((back_focus_mm(&dg).unwrap() - 56.42).abs() < 0.05, "{}", back_focus_mm(&dg).unwrap());
    for p in [&COOKE_TRIPLET, &DOUBLE_GAUSS] {
        let s = p.centred();
        let (z0, z1) = (s[0].z_mm, s.last().unwrap().z_mm);
        let f = focal_length_mm(&s).unwrap();
        let ynu = trace_paraxial(&s, [1.0, 0.0], z0 - 10.0, z1);
        assert!((-1.0 / ynu.last().unwrap()[1] - f).abs() < 1e-9 * f);
        let [[a, _], [c, _]] = system_matrix(&s, z0, z1);
        assert!((-a / c - back_focus_mm(&s).unwrap()).abs() < 1e-9);
        // A real ray from infinity at height h (surfaces in their own frames, as the
        // tracer builds them; a prescription is a centred rig).
        let file = rigs()[0].clone();
        let mut file =
            OpticsFile { prime: PrimeSpec { surfaces: p.scaled(100.0, 8.0).unwrap(), stop: p.stop }, ..file };
        file.tolerances = CENTRED;
        let sys = etl_sim::optics::tolerance::system_at(&file, 0.0);
        let prime =
            etl_sim::optics::trace::System { surfaces: sys.surfaces[3..].to_vec(), stop: p.stop, sensor: sys.sensor };
        let h = 1e-3;
        let (out, _) = prime
            .trace(
                &Ray { origin_mm: [0.0, h, 0.0], direction: [0.0, 0.0, 1.0] },
                prime.surfaces.len(),
                Apertures::Check,
            )
            .unwrap();
        let sin_u = -out.direction[1];
        assert!((h / sin_u - 100.0).abs() < 1e-5, "{} {}", p.source, h / sin_u);
    }
}

/// The ETL's paraxial power (its three surfaces' system matrix) is P(E) of the law and
/// the lensmaker's equation of its membrane radius and centre thickness.
#[test]
fn the_etl_power_is_the_lensmakers_equation() {
    let f = load("cooke-16mm-centred.json");
    for e in [0.0, 80.0, 150.0, 225.0, 290.0] {
        let s = f.centred_surfaces(e);
        let [_, [c, _]] = system_matrix(&s[..3], s[0].z_mm, s[2].z_mm);
        let p = -1000.0 * c;
        assert!((p - f.etl.power_dpt(e)).abs() < 1e-9, "{e}: {p}");
        assert!((p - etl_lensmaker_power_dpt(&f.etl, e)).abs() < 1e-9, "{e}: {p}");
        // The sag: the membrane's rim on the clear aperture, its vertex in front.
        let (cm, a) = (s[0].curvature_per_mm, f.etl.clear_semi_aperture_mm);
        let rim_z = s[0].z_mm + (1.0 - (1.0 - cm * cm * a * a).sqrt()) / cm;
        assert!(rim_z.abs() < 1e-12, "{e}: {rim_z}");
    }
}

/// A centred rig: a point on the axis images on the axis (chief ray and centroid), and
/// points mirrored in x or y image mirrored.
#[test]
fn a_centred_rig_images_symmetrically() {
    for name in ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"] {
        let rig = centred(load(name));
        for e in [80.0, 225.0] {
            let at = rig.at(e).unwrap();
            let d = rig.focus_distance_mm(e).unwrap();
            let axis = at.spot([0.0, 0.0, d]).unwrap();
            for v in [axis.chief_mm, axis.centroid_mm] {
                assert!(v[0].abs() < 1e-12 && v[1].abs() < 1e-12, "{name} {e}: {v:?}");
            }
            let s = |x: f64, y: f64| at.spot([x, y, d]).unwrap();
            let (p, mx, my) = (s(4.0, 2.5), s(-4.0, 2.5), s(4.0, -2.5));
            for (a, b, sx, sy) in [(p, mx, -1.0, 1.0), (p, my, 1.0, -1.0)] {
                for (u, v) in [(a.chief_mm, b.chief_mm), (a.centroid_mm, b.centroid_mm)] {
                    assert!(
                        (u[0] - sx * v[0]).abs() < 1e-10 && (u[1] - sy * v[1]).abs() < 1e-10,
                        "{name} {e}: {u:?} {v:?}"
                    );
                }
                assert!((a.rms_mm - b.rms_mm).abs() < 1e-10);
            }
            // The image is inverted (mm on the sensor) and upright in pixels.
            assert!(p.chief_mm[0] < 0.0);
            let px = at.pixel([4.0, 2.5, d]).unwrap();
            let [w, h] = rig.file.sensor.size_px;
            assert!(px[0] > (w as f64 - 1.0) / 2.0 && px[1] > (h as f64 - 1.0) / 2.0, "{px:?}");
        }
    }
}

/// Ray aiming brings the chief ray through the stop's centre to 1e-9 mm in a few Newton
/// steps, over the field, at every current, with tolerances too.
#[test]
fn ray_aiming_converges_through_the_stop() {
    for name in ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"] {
        let rig = OpticalRig::new(load(name)).unwrap();
        for e in [0.0, 80.0, 150.0, 225.0] {
            let at = rig.at(e).unwrap();
            let d = rig.focus_distance_mm(e).unwrap();
            for (x, y) in [(0.0, 0.0), (6.0, 0.0), (-5.0, 4.0), (3.0, -6.0)] {
                let object = lens_frame([x, y, d]);
                let stop_r = at.system.surfaces[at.system.stop].semi_diameter_mm;
                for target in [[0.0, 0.0], [0.7 * stop_r, -0.5 * stop_r]] {
                    let start = paraxial_start(object, target, &at.pupil, stop_r);
                    let a = aim(&at.system, object, target, start, None).unwrap();
                    let hit = at.system.to_stop(&a.ray, Apertures::Check).unwrap();
                    let miss = (hit[0] - target[0]).hypot(hit[1] - target[1]);
                    assert!(miss < 1e-9 && a.steps <= 8, "{name} {e} ({x}, {y}): {miss:e} mm in {} steps", a.steps);
                }
            }
        }
    }
}

/// The paraxial entrance pupil is where traced chief rays cross the axis in object
/// space, in the limit of small fields (pupil aberration grows as the field squared).
#[test]
fn the_entrance_pupil_is_where_chief_rays_cross_the_axis() {
    for name in ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"] {
        let rig = centred(load(name));
        for e in [80.0, 225.0] {
            let at = rig.at(e).unwrap();
            let d = rig.focus_distance_mm(e).unwrap();
            let crossing = |x: f64| {
                let c = at.spot([x, 0.0, d]).unwrap().chief.ray;
                c.origin_mm[2] - c.origin_mm[0] * c.direction[2] / c.direction[0]
            };
            let (small, large) = (crossing(0.01) - at.pupil.z_mm, crossing(1.0) - at.pupil.z_mm);
            assert!(small.abs() < 1e-5, "{name} {e}: {small:e}");
            // Quadratic in the field: 100 x the field, about 10^4 x the departure.
            assert!(small.abs() < 1e-3 * large.abs().max(1e-9), "{name} {e}: {small:e} {large:e}");
        }
    }
}

/// The entrance pupil of ETL + prime is the ETL's image of the prime's own pupil: with
/// the ETL's principal planes H (its membrane vertex: the rear is plane) and H' (its rear
/// face less the reduced thickness t_l / n_l + t_w / n_w), a = H' to the prime's pupil,
/// s = a / (1 - a P) from H. It matches the whole system's paraxial pupil at every
/// current, and the traced one's shift over 80-225 mA.
#[test]
fn the_entrance_pupil_moves_with_the_current_as_the_thin_lens_formula_says() {
    for name in ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"] {
        let f = load(name);
        let mut z_ep = vec![];
        for e in [80.0, 150.0, 225.0] {
            let s = f.centred_surfaces(e);
            let whole = entrance_pupil(&s, f.stop_surface()).unwrap();
            let prime = entrance_pupil(&s[3..], f.prime.stop).unwrap();
            let etl = &f.etl;
            let tau =
                (etl.edge_thickness_mm + etl.sag_mm(e)) / etl.liquid_index + etl.window_thickness_mm / etl.window_index;
            let h_rear = s[2].z_mm - tau;
            let predicted = s[0].z_mm + thin_lens_pupil_mm(prime.z_mm - h_rear, etl.power_dpt(e));
            assert!((whole.z_mm - predicted).abs() < 1e-9, "{name} {e}: {} {predicted}", whole.z_mm);
            z_ep.push(whole.z_mm);
        }
        let shift = z_ep[2] - z_ep[0];
        println!("{name}: entrance pupil {:.3} mm at 80 mA, {:.3} mm at 225 mA: shift {shift:.3} mm", z_ep[0], z_ep[2]);
        assert!(shift > 0.3, "{name}: {shift}");
    }
}

/// A point whose rays cannot reach the stop (far outside the field) is refused with an
/// error naming the surface that stops them.
#[test]
fn rays_that_cannot_reach_the_stop_are_refused_naming_the_surface() {
    let rig = OpticalRig::new(load("cooke-16mm-centred.json")).unwrap();
    let at = rig.at(150.0).unwrap();
    let e = at.spot([60.0, 0.0, 70.0]).unwrap_err();
    let named = match &e {
        OpticsError::Missed { surface }
        | OpticsError::Blocked { surface, .. }
        | OpticsError::StopMissed { surface, .. }
        | OpticsError::TotalInternalReflection { surface } => surface.clone(),
        other => panic!("{other:?}"),
    };
    assert!(named.starts_with("etl.") || named.starts_with("prime.surfaces["), "{e}");
    assert!(e.to_string().contains(&named) && !e.to_string().contains('\n'), "{e}");
}

/// The distance in focus minimises the spot: nearer and farther planes blur more.
#[test]
fn the_distance_in_focus_minimises_the_spot() {
    let rig = OpticalRig::new(load("double-gauss-25mm-toleranced.json")).unwrap();
    for e in [80.0, 225.0] {
        let at = rig.at(e).unwrap();
        let d = rig.focus_distance_mm(e).unwrap();
        let rms = |d: f64| at.spot([0.0, 0.0, d]).unwrap().rms_mm;
        assert!(rms(d) < rms(d - 0.5) && rms(d) < rms(d + 0.5), "{e}");
        let s = rig.file.paraxial_focus_distance_mm(e).unwrap();
        assert!((d / s - 1.0).abs() < 0.05, "{e}: {d} {s}");
    }
}

/// The procedure: 15 ETL views with the board in focus, 10 lens-off views, tilted views
/// per current; seeded noise on the traced centroids.
#[test]
fn the_procedure_traces_the_papers_views() {
    let mut file = load("cooke-16mm-centred.json");
    file.procedure.setting_views_per_current = 1;
    let rig = OpticalRig::new(file).unwrap();
    let clean = etl_sim::optics::procedure::traced(&rig).unwrap();
    let obs = etl_sim::optics::procedure::with_pixel_noise(&clean, 0.05, 3);
    obs.validate().unwrap();
    assert_eq!((obs.views.len(), obs.offstate_views.len(), obs.setting_views.len()), (15, 10, 15));
    assert!(
        obs.views.iter().all(|v| v.points.len() >= 40),
        "{:?}",
        obs.views.iter().map(|v| v.points.len()).collect::<Vec<_>>()
    );
    assert!(obs.offstate_views.iter().all(|v| v.points.len() >= 20));
    assert_eq!(obs, etl_sim::optics::procedure::with_pixel_noise(&clean, 0.05, 3));
    // The noise: 0.05 px about the traced centroids.
    let d: Vec<f64> = clean
        .views
        .iter()
        .zip(&obs.views)
        .flat_map(|(a, b)| a.points.iter().zip(&b.points).map(|(p, q)| q.pixel[0] - p.pixel[0]))
        .collect();
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    assert!((rms / 0.05 - 1.0).abs() < 0.1, "{rms}");
    // A view's first point is the traced centroid of its world point, in focus.
    let v = &clean.views[7];
    let at = rig.at(v.e_com_ma.unwrap()).unwrap();
    let p = &v.points[0];
    assert_eq!(at.pixel(rig.world_to_camera(p.world_mm)).unwrap(), p.pixel);
    let z = rig.stage_z_mm(v.e_com_ma.unwrap()).unwrap();
    assert_eq!(p.world_mm[2], z);
}
