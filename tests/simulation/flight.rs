//! The paper's flight comparison in the physics plant (docs/system.md#paper-cases,
//! flight): on rect-sim1, rect-sim2, L-sim1 and L-sim2, with the paper's mixer, the
//! optimised formation takes off and tracks the target with small attitude excursions; the
//! even formation does much worse (the paper saw it fail).

use std::path::Path;

use host_sim::harness::{self, FlightOutcome, FlightSetup, FormationChoice};
use host_sim::scenario_file;
use shared::control::allocation::MixerKind;
use shared::flight::FlightStop;

fn fly(name: &str, formation: FormationChoice, mixer: MixerKind) -> FlightOutcome {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/scenarios")
        .join(format!("{name}.toml"));
    let s = scenario_file::load(&path).expect("paper scenario").scenario;
    let truth = s.truth.expect("truth");
    let setup = FlightSetup {
        formation,
        mixer,
        believed_com: truth.com,
        believed_mass: truth.mass,
        seed: 7,
        map_error: 1.0,
        plant: scenario_file::PlantDepartures::MODEL,
    };
    harness::fly_formation(&s, &setup).expect("flight runs")
}

fn line(name: &str, label: &str, f: &FlightOutcome) -> String {
    format!(
        "{name} {label}: dropped {}, max tilt {:.1} deg, rms {:.3} m, final {:.3} m, max thrust {:.2}, max height {:.2} m, landed {}",
        f.dropped,
        f.max_tilt_deg,
        f.rms_tracking_error_m,
        f.final_position_error_m,
        f.max_thrust_fraction,
        f.max_height_m,
        f.landed
    )
}

#[test]
fn optimised_formation_delivers_and_even_formation_does_much_worse() {
    for name in ["rect-sim1", "rect-sim2", "L-sim1", "L-sim2"] {
        let opt = fly(name, FormationChoice::Optimized, MixerKind::EqualSplit);
        let even = fly(name, FormationChoice::Even, MixerKind::EqualSplit);
        eprintln!(
            "{}\n{}",
            line(name, "optimised", &opt),
            line(name, "even", &even)
        );

        // Optimised: takes off, tracks, delivers, with small attitude excursions and margin.
        assert!(!opt.dropped, "{name}");
        assert!(opt.max_height_m > 0.45, "{name}: reached the target height");
        assert!(opt.landed, "{name}: landed and disarmed at the target");
        assert!(opt.max_tilt_deg < 8.0, "{name}: {}", opt.max_tilt_deg);
        assert!(
            opt.rms_tracking_error_m < 0.1,
            "{name}: {}",
            opt.rms_tracking_error_m
        );
        assert!(
            opt.final_position_error_m < 0.1,
            "{name}: {}",
            opt.final_position_error_m
        );
        assert!(
            opt.max_thrust_fraction < 0.8,
            "{name}: {}",
            opt.max_thrust_fraction
        );

        // Even, same mixer: it cannot take off (it pivots on an edge) or it tilts at least
        // twice as far; either way it tracks far worse.
        let grounded = even.max_height_m < 0.1;
        assert!(
            grounded || even.max_tilt_deg > 2.0 * opt.max_tilt_deg,
            "{name}: even {} vs optimised {}",
            even.max_tilt_deg,
            opt.max_tilt_deg
        );
        assert!(
            even.rms_tracking_error_m > 2.5 * opt.rms_tracking_error_m,
            "{name}: even {} vs optimised {}",
            even.rms_tracking_error_m,
            opt.rms_tracking_error_m
        );
    }
}

#[test]
fn even_rectangle_cannot_take_off_with_the_papers_mixer() {
    // The paper's experiment: the even formation could not take off. With the COM 0.33 to
    // 0.4 m off the robots' centroid, the equal split lifts one end and the payload pivots.
    for name in ["rect-sim1", "rect-sim2"] {
        let even = fly(name, FormationChoice::Even, MixerKind::EqualSplit);
        assert!(
            even.max_height_m < 0.1,
            "{name}: {}",
            line(name, "even", &even)
        );
        assert!(!even.landed, "{name}: never flew, so never delivered");
        // The flight stack recognises it: the take-off failed and the rotors stopped.
        assert!(
            matches!(even.stop, Some(FlightStop::TakeoffFailed { .. })),
            "{name}: {:?}",
            even.stop
        );
    }
}

#[test]
fn allocation_mixer_trims_the_even_formation_at_a_thrust_cost() {
    // Each rotor's own trim lets the even formation fly, but it pays in thrust margin.
    let opt = fly(
        "rect-sim2",
        FormationChoice::Optimized,
        MixerKind::Allocation,
    );
    let even = fly("rect-sim2", FormationChoice::Even, MixerKind::Allocation);
    assert!(even.landed && opt.landed);
    assert!(
        even.max_thrust_fraction > opt.max_thrust_fraction + 0.2,
        "even {} vs optimised {}",
        even.max_thrust_fraction,
        opt.max_thrust_fraction
    );
}
