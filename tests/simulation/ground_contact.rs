//! The plant's ground contact against the lift-off model (docs/models.md#lift-off-thrust): a
//! payload rests on, and tips about, the edges of its footprint's convex hull, so each lift the
//! plant flies reads the model's lift-off thrust within the lift's own noise. Flown on the
//! L-shape and on random payloads whose hulls have 5 to 9 corners (the physics library keeps
//! four corners of a resting face, so such hulls are where a contact that drops corners
//! shows: a lift then tips about a chord inside the hull and reads light), for every
//! reachable lifting group, in the model plant (no departures).

use crate::common::scenario_path;

use host_sim::campaign::payload;
use host_sim::harness::run_lift;
use host_sim::scenario_file;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use shared::estimation::Measurement;
use shared::estimation::groups::{group_count, lift_group};
use shared::geometry::ConvexHull;
use shared::scenario::Scenario;

/// How far a reading may lie from the model, N: the vehicle's lift noise (`noise_sigma` 0.5 N
/// on the prototype's detector) at about 1.5 sigma. With corners dropped, half the lifts
/// about them read more than 1.5 N light.
const TOLERANCE: f32 = 0.75;

/// Lifts whose model lies this close to the robots' maximum may read either way, N.
const CENSOR_BAND: f32 = 1.0;

/// Every reachable group's lift on `scenario`: (group, read, model) for each lift that read a
/// thrust; a censored lift must be one the model says cannot lift.
fn lifts(scenario: &Scenario) -> Vec<(usize, f32, f32)> {
    let max = scenario.robots.max_thrust;
    let mut read = Vec::new();
    for group in 0..group_count(scenario) {
        if !lift_group(scenario, group).is_some_and(|g| g.reachable) {
            continue;
        }
        let Ok(lift) = run_lift(scenario, group, 7, 1.0) else {
            continue; // not reachable from the initial formation
        };
        match lift.measured {
            Measurement::Lifted { thrust } => read.push((group, thrust, lift.model)),
            Measurement::CouldNotLift => assert!(
                lift.model > max - CENSOR_BAND,
                "group {group} could not lift, the model says {} N of {max} N",
                lift.model
            ),
        }
    }
    read
}

#[test]
fn every_lift_on_hulls_of_five_to_nine_corners_reads_the_lift_off_model() {
    let mut payloads: Vec<(String, Scenario)> = Vec::new();
    let l = scenario_file::load(&scenario_path("L-sim1")).expect("the L-shape");
    payloads.push(("L-sim1".into(), l.scenario));
    // One random payload for each hull size from 5 to 9 corners.
    let mut rng = ChaCha8Rng::seed_from_u64(56);
    for corners in 5..=9 {
        let drawn = (0..400)
            .filter_map(|i| payload::draw(&format!("contact-{i}"), &mut rng).ok())
            .find(|p| {
                let s = &p.loaded.scenario;
                s.robots.count() <= 8
                    && ConvexHull::of(&s.payload.footprint)
                        .is_some_and(|h| h.vertices().len() == corners)
            })
            .unwrap_or_else(|| panic!("no payload of {corners} hull corners in 400 draws"));
        payloads.push((format!("{corners} corners"), drawn.loaded.scenario));
    }
    let mut worst = Vec::new();
    for (name, scenario) in &payloads {
        let read = lifts(scenario);
        assert!(read.len() >= 3, "{name}: only {} lifts read", read.len());
        let (group, got, model) = read
            .iter()
            .copied()
            .max_by(|a, b| (a.1 - a.2).abs().total_cmp(&(b.1 - b.2).abs()))
            .expect("lifts");
        eprintln!(
            "{name}: {} lifts; the farthest from the model: group {group} read {got:.2} N, model {model:.2} N",
            read.len()
        );
        worst.push((name.clone(), group, got, model));
    }
    for (name, group, got, model) in worst {
        assert!(
            (got - model).abs() <= TOLERANCE,
            "{name}, group {group}: read {got:.2} N, the model says {model:.2} N"
        );
    }
}
