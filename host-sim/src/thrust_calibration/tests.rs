use super::*;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// A map that is not the square law: a rotor whose speed starts at an offset (more thrust low
/// down), full thrust 14.2 N (the prototype's).
const MAP: [f64; 4] = [0.055, 0.19, 0.385, 0.66];
const FULL: f64 = 14.2;

/// Thrust at `command` of the map with interior fractions `map` and full thrust `full`.
fn thrust(map: [f64; 4], full: f64, command: f64) -> f64 {
    let knots = [0.0, map[0], map[1], map[2], map[3], 1.0].map(|p| p * full);
    piecewise(&knots, command)
}

/// Readings at commands 0, 0.05, .., `top`, `repeats` each, from `law` (command to N) plus
/// `noise(rng)`; lines from 2 (after a header), in sweep order.
fn sweep(
    top: f64,
    repeats: usize,
    law: impl Fn(f64) -> f64,
    mut noise: impl FnMut() -> f64,
) -> Vec<Reading> {
    let mut out = Vec::new();
    let steps = (top * 20.0).round() as usize;
    for i in 0..=steps {
        let command = i as f64 / 20.0;
        for _ in 0..repeats {
            out.push(Reading {
                line: out.len() + 2,
                command,
                thrust_n: law(command) + noise(),
            });
        }
    }
    out
}

fn exact(map: [f64; 4], full: f64) -> Vec<Reading> {
    sweep(1.0, 1, |c| thrust(map, full, c), || 0.0)
}

fn refused(readings: &[Reading]) -> String {
    calibrate(readings).unwrap_err().to_string()
}

fn close(got: [f64; 4], want: [f64; 4], tolerance: f64) {
    for k in 0..4 {
        assert!(
            (got[k] - want[k]).abs() <= tolerance,
            "{}: {} against {} ({got:?})",
            PARAMS[k],
            got[k],
            want[k]
        );
    }
}

#[test]
fn a_sweep_from_a_known_map_is_recovered() {
    let cal = calibrate(&exact(MAP, FULL)).unwrap();
    close(cal.params, MAP, 1e-4);
    assert!(
        (cal.full_thrust_n - FULL).abs() < 1e-9,
        "{}",
        cal.full_thrust_n
    );
    assert_eq!(cal.tare_n, 0.0);
    assert_eq!(cal.top_command, 1.0);
    assert_eq!(cal.readings, 21);
    assert_eq!(cal.points.len(), 21);
    // Only the rounding to four places is left.
    assert!(cal.max_error_fraction < 1e-4, "{}", cal.max_error_fraction);
    let want = ThrustMap::new(MAP.map(|p| p as f32)).unwrap();
    for i in 0..=100 {
        let c = i as f32 / 100.0;
        assert!((cal.map.thrust(c) - want.thrust(c)).abs() < 1e-4, "{c}");
    }
}

#[test]
fn the_square_law_is_recovered() {
    // Readings at the knots: the fit goes through them.
    let at_knots: Vec<Reading> = KNOTS
        .iter()
        .enumerate()
        .map(|(i, &c)| Reading {
            line: i + 2,
            command: c,
            thrust_n: FULL * c * c,
        })
        .collect();
    let cal = calibrate(&at_knots).unwrap();
    assert_eq!(cal.map, ThrustMap::SQUARE);
    close(cal.params, [0.04, 0.16, 0.36, 0.64], 1e-12);
    // A dense sweep of the curve itself: the straight pieces that fit a parabola best (least
    // squares) run below it at the knots, by about h^2 / 6 = 0.0067 for intervals h = 0.2 (a
    // little more at 20 %, next to the fixed zero), and stay closer to it in between than the
    // chords through the knots (h^2 / 4 = 0.01 at their middles).
    let dense = sweep(1.0, 1, |c| FULL * c * c, || 0.0);
    let cal = calibrate(&dense).unwrap();
    close(cal.params, [0.04, 0.16, 0.36, 0.64], 0.008);
    assert!(
        cal.params
            .iter()
            .zip([0.04, 0.16, 0.36, 0.64])
            .all(|(p, s)| *p < s)
    );
    assert!(cal.max_error_fraction < 0.008, "{}", cal.max_error_fraction);
    assert!(cal.max_error_fraction > 0.0);
}

#[test]
fn bench_noise_gives_a_small_error() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let noise = Normal::new(0.0, 0.05).unwrap();
    let readings = sweep(1.0, 3, |c| thrust(MAP, FULL, c), || noise.sample(&mut rng));
    let cal = calibrate(&readings).unwrap();
    // Some twelve readings of 0.05 N noise per knot, against 14.2 N: a few thousandths.
    close(cal.params, MAP, 0.005);
    assert!(
        (cal.full_thrust_n - FULL).abs() < 0.1,
        "{}",
        cal.full_thrust_n
    );
    assert!(
        cal.max_error_fraction > 0.0 && cal.max_error_fraction < 0.01,
        "{}",
        cal.max_error_fraction
    );
    assert_eq!(cal.readings, 63);
    assert_eq!(cal.points[1].lines, [5, 6, 7]);
}

#[test]
fn the_load_cells_zero_is_taken_off() {
    let offset = 0.3;
    let readings: Vec<Reading> = exact(MAP, FULL)
        .into_iter()
        .map(|r| Reading {
            thrust_n: r.thrust_n + offset,
            ..r
        })
        .collect();
    let cal = calibrate(&readings).unwrap();
    assert!((cal.tare_n - offset).abs() < 1e-12);
    close(cal.params, MAP, 1e-4);
    assert!((cal.full_thrust_n - FULL).abs() < 1e-9);
    assert_eq!(cal.points[0].measured_n, 0.0);
}

#[test]
fn full_thrust_is_extrapolated_from_a_sweep_to_ninety_percent() {
    let readings = sweep(0.9, 2, |c| thrust(MAP, FULL, c), || 0.0);
    let cal = calibrate(&readings).unwrap();
    assert_eq!(cal.top_command, 0.9);
    assert!((cal.full_thrust_n - FULL).abs() < 1e-9);
    close(cal.params, MAP, 1e-4);
}

#[test]
fn the_piecewise_map_agrees_with_the_firmwares() {
    let map = ThrustMap::new(MAP.map(|p| p as f32)).unwrap();
    for i in 0..=200 {
        let c = f64::from(i) / 200.0;
        let ours = thrust(MAP, 1.0, c);
        assert!((ours - f64::from(map.thrust(c as f32))).abs() < 1e-6, "{c}");
    }
}

#[test]
fn the_parameters_are_the_firmwares() {
    for name in PARAMS {
        assert!(
            shared::mission::params::find(name.as_bytes()).is_some(),
            "{name}"
        );
    }
}

#[test]
fn a_sweep_that_does_not_determine_the_map_is_refused_naming_what_is_missing() {
    assert_eq!(refused(&[]), "no readings below the header");
    let without_40_to_60: Vec<Reading> = exact(MAP, FULL)
        .into_iter()
        .filter(|r| !(r.command > 0.4 && r.command <= 0.6))
        .collect();
    assert_eq!(
        refused(&without_40_to_60),
        "no reading with a command in (0.4, 0.6]: the fit needs one in each fifth of the range, \
         (0, 0.2] to (0.8, 1], to set the map at 60 % command"
    );
    let short = sweep(0.85, 1, |c| thrust(MAP, FULL, c), || 0.0);
    assert_eq!(
        refused(&short),
        "line 19: the sweep stops at command 0.85, below 0.9: full thrust (at command 1) would \
         be extrapolated too far; sweep up to command 1"
    );
    // Every reading crowds its interval's left end: the knots above are barely seen.
    let crowded: Vec<Reading> = [0.2, 0.2 + 1e-13, 0.6, 0.8, 1.0]
        .iter()
        .enumerate()
        .map(|(i, &c)| Reading {
            line: i + 2,
            command: c,
            thrust_n: thrust(MAP, FULL, c),
        })
        .collect();
    assert_eq!(calibrate(&crowded), Err(CalibrationError::Undetermined));
}

#[test]
fn a_command_outside_the_range_is_refused_naming_its_line() {
    let mut readings = exact(MAP, FULL);
    readings[4].command = 20.0;
    assert_eq!(
        refused(&readings),
        "line 6: command 20 is outside 0..1 (commands are fractions of full command, not \
         percent)"
    );
    readings[4].command = -0.1;
    assert_eq!(
        refused(&readings),
        "line 6: command -0.1 is outside 0..1 (commands are fractions of full command, not \
         percent)"
    );
    readings[4].command = f64::NAN;
    assert!(refused(&readings).starts_with("line 6: command NaN"));
    let mut readings = exact(MAP, FULL);
    readings[3].thrust_n = f64::INFINITY;
    assert_eq!(
        refused(&readings),
        "line 5: thrust_n is not a finite number"
    );
}

#[test]
fn thrust_that_falls_is_refused_naming_the_lines_noise_is_not() {
    let mut readings = sweep(1.0, 3, |c| thrust(MAP, FULL, c), || 0.0);
    // Command 0.5 (lines 32 to 34) reads 0.5 N less than command 0.45 (lines 29 to 31).
    let fall = thrust(MAP, FULL, 0.5) - thrust(MAP, FULL, 0.45) + 0.5;
    for r in readings.iter_mut().filter(|r| r.command == 0.5) {
        r.thrust_n -= fall;
    }
    assert_eq!(
        refused(&readings),
        "lines 32, 33 and 34: thrust falls as the command rises: at command 0.5 the readings \
         average 2.890 N, 0.500 N below the 3.390 N at command 0.45 (lines 29, 30 and 31); \
         bench noise may lower it by 0.142 N at most (1 % of the largest mean)"
    );
    // A dead band read by a noisy load cell: thrust "falls" by a few hundredths of a newton.
    let mut readings = sweep(1.0, 1, |c| thrust(MAP, FULL, c), || 0.0);
    readings[1].thrust_n = 0.03;
    readings[2].thrust_n = 0.01;
    assert!(calibrate(&readings).is_ok());
    // A load cell mounted the other way.
    let negative: Vec<Reading> = exact(MAP, FULL)
        .into_iter()
        .map(|r| Reading {
            thrust_n: -r.thrust_n,
            ..r
        })
        .collect();
    assert_eq!(
        refused(&negative),
        "line 22: at the top command 1 the thrust averages -14.200 N above the tare, not \
         more: thrust must rise with the command (a load cell mounted the other way reads \
         negative: flip the sign)"
    );
}

#[test]
fn a_map_the_firmware_cannot_hold_is_refused_with_the_reason() {
    // An ESC whose dead band reaches 20 %: no thrust there.
    let dead = sweep(
        1.0,
        1,
        |c| thrust([0.0, 0.19, 0.385, 0.66], FULL, c),
        || 0.0,
    );
    let err = refused(&dead);
    assert!(
        err.starts_with("THR_MAP_20 would be 0, outside 0.001..0.999"),
        "{err}"
    );
    assert!(err.contains("at 20 % command"), "{err}");
    // Flat from 40 % to 60 % (within bench noise of it): the map must rise.
    let flat = sweep(1.0, 1, |c| thrust([0.06, 0.2, 0.2, 0.6], FULL, c), || 0.0);
    assert_eq!(
        refused(&flat),
        "THR_MAP_60 would be 0.2, not above THR_MAP_40 (0.2): the fitted map does not rise"
    );
}

#[test]
fn lines_are_listed_briefly() {
    assert_eq!(lines_of(&[7]), "line 7");
    assert_eq!(lines_of(&[7, 9]), "lines 7 and 9");
    assert_eq!(lines_of(&[7, 9, 12]), "lines 7, 9 and 12");
    assert_eq!(lines_of(&[7, 9, 12, 13, 20]), "lines 7, 9, 12 and 2 more");
}

#[test]
fn any_readings_give_a_map_or_a_reason_never_a_panic() {
    use rand::RngExt;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..500 {
        let count = rng.random_range(0..30);
        let readings: Vec<Reading> = (0..count)
            .map(|i| Reading {
                line: i + 2,
                // Whole twentieths, so that commands repeat.
                command: f64::from(rng.random_range(0..=20u8)) / 20.0,
                thrust_n: rng.random_range(-1.0..15.0),
            })
            .collect();
        if let Ok(cal) = calibrate(&readings) {
            assert!(cal.full_thrust_n > 0.0);
            assert!(cal.max_error_fraction.is_finite());
            assert_eq!(ThrustMap::new(cal.params.map(|p| p as f32)), Ok(cal.map));
        }
    }
}
