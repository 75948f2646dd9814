use etl_sim::multi_camera::{simulate_multi_camera, MultiCameraDesign};
use etl_sim::simulate::NoiseModel;
fn main() {
    for (n, b) in [(2, 60.0), (3, 150.0)] {
        let design = MultiCameraDesign { cameras: n, baseline_mm: b, views: 15, moving_centre: false };
        let sim = simulate_multi_camera(&design, &NoiseModel::NONE, 1).unwrap();
        for v in &sim.dataset.views {
            let s: Vec<String> = v
                .cameras
                .iter()
                .map(|c| format!("c{} E{:.0} n{}", c.camera, c.e_com_ma.unwrap(), c.points.as_ref().unwrap().len()))
                .collect();
            println!("z {:.1}: {}", v.z_w_mm, s.join(", "));
        }
        for (k, m) in sim.truths.iter().enumerate() {
            for z in [2.0, 38.5, 75.0] {
                print!("cam{k} z{z}: depth {:.1}  ", m.world_to_camera([0.0, 0.0, z])[2]);
            }
            println!();
        }
    }
}
