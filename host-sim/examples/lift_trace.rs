//! Static check of the plant (`MOVE_FIRST=1`: the robots first glide from the initial formation): hold the pair of group 11 of a scenario (default rect-ex1) at a
//! constant thrust and report the tilt after 3 s, for thrusts around the model's lift-off.
use host_sim::plant::{PHYSICS_DT, Plant, PlantConfig};
use shared::control::vector::Vec3;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .map_or("tests/scenarios/rect-ex1.toml", String::as_str);
    let s = host_sim::scenario_file::load(std::path::Path::new(path))?.scenario;
    let truth = s.truth.unwrap();
    let rail = &s.payload.rail;
    let c = &s.payload.candidates;
    let targets =
        shared::rail::moves::lift_targets(rail, &s.robots.initial, &[c[11], c[0]], 0.25).unwrap();
    let pair: Vec<usize> = [c[11], c[0]]
        .iter()
        .map(|x| targets.iter().position(|t| (t - x).abs() < 1e-5).unwrap())
        .collect();
    for thrust in [6.4f32, 6.5, 6.6, 6.7, 6.8, 6.9, 7.0, 7.1, 7.2, 7.3] {
        let mut plant = Plant::new(PlantConfig {
            footprint: s.payload.footprint.to_vec(),
            com: truth.com,
            mass: truth.mass,
            robot_mass: 0.1,
            rotor_points: if std::env::var("MOVE_FIRST").is_ok() {
                s.robots.initial.iter().map(|&x| rail.point_at(x)).collect()
            } else {
                targets.iter().map(|&x| rail.point_at(x)).collect()
            },
            spin: s.robots.spin.to_vec(),
            torque_per_thrust: 0.016,
            max_thrust: 14.2,
            map_error: 1.0,
            disturbance_peak: 0.0,
            disturbance_phase: [0.0, 0.0],
            ..PlantConfig::MODEL
        });
        if std::env::var("MOVE_FIRST").is_ok() {
            let mv = shared::rail::moves::RailMove::plan(
                rail,
                &s.robots.initial,
                &targets,
                0.25,
                shared::rail::stepper::MotionLimits::default(),
            )
            .unwrap();
            let steps = (mv.duration() / PHYSICS_DT) as usize + 1;
            for k in 0..steps {
                let at = mv.positions_at(rail, k as f32 * PHYSICS_DT);
                let pts: Vec<_> = at.iter().map(|&x| rail.point_at(x)).collect();
                plant.set_rotor_points(&pts);
                plant.step(&[0.0; 8]);
            }
        }
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
