//! Prints the rotor-fault tables of README.md (docs/failures.md#rotors-that-stop-in-flight):
//! every pair of rotors stopped at once on rect-ex1 and L-sim1 (holdable or not, dropped or
//! not, largest tilt, when both were named), from the vehicle's response alone and with the
//! ESCs' RPM; and every rotor fading over 4 s (when named, the tilt by then). Run by
//! `.ci/rotor-faults`; takes some three minutes.

use std::path::Path;

use anyhow::Result;
use host_sim::rotor_faults::{self, FADE_SECONDS, PairCase};

fn cell(c: &PairCase) -> String {
    let detection = c
        .detection_s()
        .map_or("-".to_string(), |s| format!("{:.0} ms", s * 1000.0));
    format!(
        "{:<7} {:>5.1} {:>7}",
        if c.outcome.dropped { "DROPPED" } else { "held" },
        c.outcome.max_tilt_deg,
        detection
    )
}

fn main() -> Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/scenarios");
    for name in ["rect-ex1", "L-sim1"] {
        let scenario = host_sim::scenario_file::load(&dir.join(format!("{name}.toml")))?.scenario;
        let n = scenario.robots.count();
        println!(
            "\n{name}: two rotors stopped at once, {} s after take-off began",
            rotor_faults::PAIR_STOP_AFTER
        );
        println!(
            "pair   holdable | response alone: outcome tilt(deg) named-in | with RPM: outcome tilt(deg) named-in"
        );
        let (mut dropped, mut held_dropped, mut rpm_dropped, mut rpm_held_dropped, mut holdable) =
            (0, 0, 0, 0, 0);
        for a in 1..=n {
            for b in a + 1..=n {
                let model = rotor_faults::pair(&scenario, a, b, false)?;
                let rpm = rotor_faults::pair(&scenario, a, b, true)?;
                holdable += usize::from(model.holdable);
                dropped += usize::from(model.outcome.dropped);
                held_dropped += usize::from(model.holdable && model.outcome.dropped);
                rpm_dropped += usize::from(rpm.outcome.dropped);
                rpm_held_dropped += usize::from(rpm.holdable && rpm.outcome.dropped);
                println!(
                    "{a}+{b}    {:<8} | {} | {}",
                    if model.holdable { "yes" } else { "no" },
                    cell(&model),
                    cell(&rpm)
                );
            }
        }
        println!(
            "{name}: {holdable} of {} pairs holdable; response alone: {dropped} dropped ({held_dropped} holdable); with RPM: {rpm_dropped} dropped ({rpm_held_dropped} holdable)",
            n * (n - 1) / 2
        );
        println!(
            "\n{name}: each rotor fading to nothing over {FADE_SECONDS} s, from {} s after take-off began",
            rotor_faults::FADE_AFTER
        );
        println!(
            "rotor | response alone: named after, tilt by then (deg), outcome | with RPM: named after, tilt (deg), outcome"
        );
        for robot in 1..=n {
            let row = |c: &rotor_faults::FadeCase| {
                format!(
                    "{:>7} {:>5} {}",
                    c.detection_s().map_or_else(
                        || match c.others_named().first() {
                            Some(other) => format!("never (rotor {other} named instead)"),
                            None => "never".to_string(),
                        },
                        |s| format!("{s:.2} s")
                    ),
                    c.tilt_when_named_deg()
                        .map_or("-".to_string(), |t| format!("{t:.1}")),
                    if c.outcome.dropped { "DROPPED" } else { "held" }
                )
            };
            let model = rotor_faults::fade(&scenario, robot, FADE_SECONDS, false)?;
            let rpm = rotor_faults::fade(&scenario, robot, FADE_SECONDS, true)?;
            println!("{robot:>5} | {} | {}", row(&model), row(&rpm));
        }
    }
    Ok(())
}
