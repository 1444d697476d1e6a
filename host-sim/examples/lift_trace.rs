//! Static check of the plant: hold the pair of group 11 on rect-ex1 at a constant thrust and
//! report the tilt after 3 s, for thrusts around the model's lift-off.
use host_sim::plant::{PHYSICS_DT, Plant, PlantConfig};
use shared::control::vector::Vec3;

fn main() -> anyhow::Result<()> {
    let s = host_sim::scenario_file::load(std::path::Path::new("tests/scenarios/rect-ex1.toml"))?
        .scenario;
    let truth = s.truth.unwrap();
    let rail = &s.payload.rail;
    let c = &s.payload.candidates;
    let targets =
        shared::rail::moves::lift_targets(rail, &s.robots.initial, &[c[11], c[0]], 0.25).unwrap();
    let pair: Vec<usize> = [c[11], c[0]]
        .iter()
        .map(|x| targets.iter().position(|t| (t - x).abs() < 1e-5).unwrap())
        .collect();
    for thrust in [6.6f32, 6.7, 6.8, 6.85, 6.9, 7.0, 7.1, 7.2] {
        let mut plant = Plant::new(PlantConfig {
            footprint: s.payload.footprint.to_vec(),
            com: truth.com,
            mass: truth.mass,
            robot_mass: 0.1,
            rotor_points: targets.iter().map(|&x| rail.point_at(x)).collect(),
            spin: s.robots.spin.to_vec(),
            torque_per_thrust: 0.016,
            max_thrust: 14.2,
            map_error: 1.0,
            disturbance_peak: 0.0,
            disturbance_phase: [0.0, 0.0],
        });
        let mut cmd = vec![0.980665f32; 8];
        for &i in &pair {
            cmd[i] = thrust;
        }
        for _ in 0..(3.0 / PHYSICS_DT) as usize {
            plant.step(&cmd);
        }
        let st = plant.state();
        let tilt = st.attitude.rotate(Vec3::DOWN).z.clamp(-1.0, 1.0).acos();
        println!(
            "thrust {thrust:.2}: tilt {tilt:.5} rad, z {:.5}",
            st.position.z
        );
    }
    Ok(())
}
