//! Prints, as one JSON line, the Rust results that the Python tests compare `etlcal` with
//! (to 1e-12): projections and undistortions of the paper rig at several currents, and
//! the thermal compensation on a grid. Run: `cargo run -p etl-core --example rust_reference`.

use etl_core::model::CameraModel;
use etl_core::thermal::ThermalSurface;

fn main() {
    let cam = CameraModel::paper_rig();
    let currents = [80.0, 140.0, 225.0];
    // The paper's board at three stage positions: 14 x 12 inner corners, 1.5 mm squares.
    let mut world = Vec::new();
    for &z in &[75.0, 48.0, 22.0] {
        for j in 0..12 {
            for i in 0..14 {
                world.push([1.5 * i as f64, 1.5 * j as f64, z]);
            }
        }
    }
    let mut project = Vec::new();
    let mut undistort = Vec::new();
    for &e in &currents {
        let mut px = vec![[0.0; 2]; world.len()];
        cam.project_many(&world, e, &mut px).expect("paper rig projects its board");
        let und: Vec<[f64; 2]> = px.iter().map(|p| cam.undistort(*p, e).expect("undistortion converges")).collect();
        project.push(serde_json::json!({ "e_com_ma": e, "pixels": px }));
        undistort.push(serde_json::json!({ "e_com_ma": e, "pixels": px, "undistorted": und }));
    }
    let s = ThermalSurface::PAPER;
    let mut thermal = Vec::new();
    for &t in &[20.0, 27.0, 31.5, 37.0] {
        for &e in &[0.0, 40.0, 133.3, 240.0] {
            thermal.push(serde_json::json!({
                "temperature_c": t, "e_in_ma": e,
                "e_t_ma": s.e_t_ma(e, t).expect("in domain"),
                "e_com_ma": s.e_com_ma(e, t).expect("in domain"),
            }));
        }
    }
    let out = serde_json::json!({ "world_mm": world, "project": project, "undistort": undistort, "thermal": thermal });
    println!("{out}");
}
