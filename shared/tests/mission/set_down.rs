//! The set-down after a lift (docs/system.md#mission-phases): the rotors' thrust ramps down
//! over `SET_DOWN_TIME` unless the payload tips `SET_DOWN_CUT_TILT` past the attitude it
//! rested at, which cuts it at once.

use super::*;
use shared::mission::{SET_DOWN_CUT_TILT, SET_DOWN_TIME};

/// The first relax of a mission on `s`: from its third tick the payload rolls at `roll_rate`
/// rad/s (0: it rests; a lift that read high made the ramp roll a light payload over in a
/// campaign trial). Each tick of the set-down's ramp from then: the phase, the largest
/// thrust commanded and the payload's true tilt (rad).
fn first_relax(s: &Scenario, roll_rate: f32) -> Vec<(Phase, f32, f32)> {
    let mut world = World::new(s);
    let mut relax_from: Option<u64> = None;
    let mut seen = Vec::new();
    let ramp_ticks = (SET_DOWN_TIME * 1e6 / DT_US as f32) as u64;
    run_with(
        s,
        MissionConfig::default(),
        &mut world,
        Jobs::OnTime,
        &[(1, OperatorCommand::Start)],
        |tick, out, world| {
            if out.phase == Phase::Relaxing && relax_from.is_none() {
                relax_from = Some(tick);
            }
            let Some(from) = relax_from else { return };
            let k = tick - from;
            if k == 2 && roll_rate != 0.0 {
                world.forced_tilt_rate = Some(roll_rate);
            }
            if (3..ramp_ticks).contains(&k) {
                let largest = out.thrusts.iter().fold(0.0f32, |m, &t| m.max(t));
                seen.push((out.phase, largest, world.tilt));
            }
        },
        // Checks, the first lift and its set-down.
        20_000,
    );
    seen
}

#[test]
fn the_set_down_ramps_unless_the_payload_tips_six_degrees_which_cuts_it() {
    let s = straight_up_scenario(2.0);
    // At rest: the thrust falls along the ramp, the edge comes down.
    let level = first_relax(&s, 0.0);
    assert!(level.len() > 100, "{} ticks", level.len());
    assert!(
        level
            .iter()
            .all(|&(p, t, _)| p == Phase::Relaxing && t > 0.0)
    );
    assert!(level.windows(2).all(|w| w[1].1 <= w[0].1 + 1e-6), "falling");
    assert!(level.iter().all(|&(_, _, tilt)| tilt < SET_DOWN_CUT_TILT));
    // Rolling over at 1.3 rad/s (45 degrees in 0.6 s, as that trial): once it has tipped six
    // degrees every rotor is cut, and stays cut, before it tips much further.
    let pushed = first_relax(&s, 1.3);
    let cut = pushed
        .iter()
        .position(|&(_, t, _)| t == 0.0)
        .expect("cut in the set-down");
    assert!(cut > 0, "not cut before it tipped");
    let tilt_at_cut = pushed[cut].2;
    assert!(
        (SET_DOWN_CUT_TILT..2.0 * SET_DOWN_CUT_TILT).contains(&tilt_at_cut),
        "cut at {} deg",
        tilt_at_cut.to_degrees()
    );
    assert!(pushed[..cut].iter().all(|&(_, t, _)| t > 0.0));
    assert!(
        pushed[cut..]
            .iter()
            .all(|&(p, t, _)| p == Phase::Relaxing && t == 0.0)
    );
}
