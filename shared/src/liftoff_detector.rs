//! Lift-off detection during an estimation lift (docs/models.md#lift-off-detector): the pair's
//! thrust ramps slowly while the other robots hold their own weight; the IMU's attitude shows
//! when the payload starts to tilt, and the thrust at that moment is the measurement.
//!
//! The detector first holds the pair at its own weight while the attitude settles and takes
//! the resting attitude as reference. It then ramps at `ramp_rate` and watches the angle
//! between the body's z axis and the reference's. Crossing `tilt_threshold` is the lift-off.
//! Tilt shows up late: after equilibrium is lost the payload must turn far enough to cross the
//! threshold, slowly for a heavy axis, while the thrust ramps on. Past lift-off the unbalanced
//! torque grows with the ramp, `(T - lambda) ~ ramp_rate (t - t0)`, so the tilt grows as
//! `k (t - t0)^3`. The detector keeps the last second of (time, tilt vector); on
//! crossing the threshold at `t2` it projects that history onto the direction the payload tipped
//! (so the estimate's noise averages out instead of adding to a magnitude), smooths it over a
//! few samples, finds where it first rose above `onset_fraction` of the threshold, `t1`, and
//! solves the cubic through both for the onset `t0 = (t2 - r t1) / (1 - r)`,
//! `r = (tilt2 / tilt1)^(1/3)`. The reading is the ramp's thrust at `t0`, minus
//! `ramp_rate * detection_delay` for the sensor's own latency.
//! If the ramp reaches the robots' maximum and holds it for `settle_time` without a tilt, the
//! reading is "could not lift" (a censored measurement).
//!
//! A reading needs a payload at rest when the ramp starts: a payload still rocking (set down
//! from the last lift, or knocked) crosses the threshold at the ramp's first thrust, and that
//! thrust says nothing of the payload. So the settle window ends only when the body's down
//! axis moved less than `rest_tolerance` over it (the lift waits, window after window, up to
//! [`REST_TIMEOUT`], then gives up: [`LiftState::Restless`]); and a tilt that crosses the
//! threshold before the ramp has run `least_ramp_time` is the payload's own motion, not the
//! ramp's doing: the pair drops back to its own weight and the lift starts again (at most
//! [`MAX_REDOS`] times; a payload that tips that early after a steady window every time
//! really lifts there). Each wait and each restart is told ([`LiftDelay`]).

use crate::control::vector::{Quat, Vec3};
use crate::estimation::Measurement;
use crate::math;

/// Tuning of the detector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiftoffConfig {
    /// Thrust ramp of each robot of the pair, N/s.
    pub ramp_rate: f32,
    /// Tilt from the resting attitude that counts as lift-off, rad.
    pub tilt_threshold: f32,
    /// Latency of the attitude estimate behind the payload (the IMU's), compensated, s.
    pub detection_delay: f32,
    /// Share of the threshold below which the tilt counts as not yet started.
    pub onset_fraction: f32,
    /// Time held at the start (reference) and at maximum thrust (before giving up), s.
    pub settle_time: f32,
    /// Largest movement of the body's down axis over the settle window (peak to peak of any
    /// component, rad) for the payload to count as at rest.
    pub rest_tolerance: f32,
    /// Least time the ramp runs before a tilt can be its doing, s.
    pub least_ramp_time: f32,
}

impl LiftoffConfig {
    /// The defaults (the simulated vehicle's characterised detector).
    pub const DEFAULT: Self = Self {
        ramp_rate: 1.0,
        tilt_threshold: 0.01,
        detection_delay: 0.005,
        onset_fraction: 0.3,
        settle_time: 0.5,
        rest_tolerance: 0.005,
        least_ramp_time: 0.25,
    };
}

impl Default for LiftoffConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where a lift stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LiftState {
    /// Holding the pair at its own weight while the resting attitude is taken.
    Settling,
    /// Ramping the pair's thrust.
    Ramping,
    /// Holding maximum thrust, waiting for a tilt that has not come.
    HoldingMaximum,
    /// Done: the measurement for the estimator.
    Measured(Measurement),
    /// Done without a reading: the payload did not come to rest within [`REST_TIMEOUT`].
    Restless,
}

/// Why a lift did not start its ramp, or started it again (told once each time).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LiftDelay {
    /// The payload was still moving over the settle window: the lift waits for it.
    Waiting {
        /// How far the body's down axis moved over the window, rad.
        moved: f32,
    },
    /// The payload tipped before the ramp could have tipped it: the lift starts again.
    Redone {
        /// The restart's count in this lift, from 1.
        count: u8,
        /// How long the ramp had run, s.
        after: f32,
    },
}

/// Longest wait for the payload to come to rest before a ramp, s.
pub const REST_TIMEOUT: f32 = 10.0;
/// Restarts of one lift for a tilt too early to be the ramp's doing.
pub const MAX_REDOS: u8 = 2;

/// Samples of the tilt kept to find its onset (one second at 400 Hz).
pub const HISTORY: usize = 400;
/// Samples averaged when the history is projected (20 ms at 400 Hz).
const SMOOTHING: usize = 8;

/// Thrust of a linear ramp `back` seconds before it reached `thrust`.
fn ramp_back(thrust: f32, rate: f32, back: f32) -> f32 {
    thrust - rate * back
}

/// One lift.
#[derive(Clone, Debug, PartialEq)]
pub struct LiftoffDetector {
    config: LiftoffConfig,
    start_thrust: f32,
    max_thrust: f32,
    thrust: f32,
    timer: f32,
    reference_axis: Vec3,
    /// The down axis's componentwise least and greatest over the settle window.
    window_low: Vec3,
    window_high: Vec3,
    /// Time spent settling since the lift began or last restarted, s.
    waited: f32,
    redos: u8,
    waiting_told: bool,
    last_moved: f32,
    delay: Option<LiftDelay>,
    state: LiftState,
    /// (detector clock, tilt vector) of the last [`HISTORY`] ticks: the thrust at any of
    /// them follows from the ramp ([`ramp_back`]).
    history: heapless::Deque<(f32, Vec3), HISTORY>,
    clock: f32,
}

impl LiftoffDetector {
    /// A lift whose pair starts at `start_thrust` (the robots' own weight, N) and may go up
    /// to `max_thrust` (N, per robot).
    pub fn new(config: LiftoffConfig, start_thrust: f32, max_thrust: f32) -> Self {
        Self {
            config,
            start_thrust,
            max_thrust,
            thrust: start_thrust,
            timer: 0.0,
            reference_axis: Vec3::ZERO,
            window_low: Vec3::splat(f32::INFINITY),
            window_high: Vec3::splat(f32::NEG_INFINITY),
            waited: 0.0,
            redos: 0,
            waiting_told: false,
            last_moved: 0.0,
            delay: None,
            state: LiftState::Settling,
            history: heapless::Deque::new(),
            clock: 0.0,
        }
    }

    /// Where the lift stands.
    pub fn state(&self) -> LiftState {
        self.state
    }

    /// The body's down axis (world frame) at rest before the ramp, the reference of the tilt;
    /// zero while settling.
    pub fn resting_axis(&self) -> Vec3 {
        self.reference_axis
    }

    /// Thrust to command on each robot of the pair now, N.
    pub fn pair_thrust(&self) -> f32 {
        self.thrust
    }

    /// The last wait or restart not yet taken, if any (the mission tells it).
    pub fn take_delay(&mut self) -> Option<LiftDelay> {
        self.delay.take()
    }

    /// A new settle window: the reference and the window's extremes from nothing.
    fn open_window(&mut self) {
        self.reference_axis = Vec3::ZERO;
        self.window_low = Vec3::splat(f32::INFINITY);
        self.window_high = Vec3::splat(f32::NEG_INFINITY);
        self.timer = 0.0;
    }

    /// How far the down axis moved over the last whole settle window, rad (zero before one).
    pub fn window_moved(&self) -> f32 {
        self.last_moved
    }

    /// How far the down axis moved over the window: the largest peak-to-peak component, rad.
    fn window_movement(&self) -> f32 {
        let d = self.window_high - self.window_low;
        math::max(math::max(d.x, d.y), d.z)
    }

    /// The onset of the tilt (detector clock, s) from the history, the tilt now being
    /// `tilt_vector` (change of the body z axis since the reference).
    fn onset(&self, tilt_vector: Vec3) -> f32 {
        let direction = tilt_vector.normalized();
        // Walk back from the newest sample, projecting as it goes and smoothing with a
        // trailing moving average kept as a running sum over the window: only the samples
        // since the tilt rose are touched (this runs inside a control tick). The window is a
        // ring of SMOOTHING slots, its newest sample at `head`.
        let (front, back) = self.history.as_slices();
        let mut older = back
            .iter()
            .rev()
            .chain(front.iter().rev())
            .map(|&(t, v)| (t, v.dot(direction)));
        let mut window = [(0.0f32, 0.0f32); SMOOTHING];
        let (mut head, mut len) = (0usize, 0usize);
        let mut sum = 0.0f32;
        for sample in older.by_ref().take(SMOOTHING) {
            sum += sample.1;
            window[len] = sample;
            len += 1;
        }
        let floor = self.config.onset_fraction * self.config.tilt_threshold;
        let t2 = self.clock;
        let tilt2 = sum / math::max(len as f32, 1.0);
        let mut first = (t2, tilt2);
        while len > 0 {
            let (t_i, raw_i) = window[head];
            let smoothed = sum / len as f32;
            if smoothed <= floor {
                break;
            }
            first = (t_i, smoothed);
            head = (head + 1) % SMOOTHING;
            len -= 1;
            sum -= raw_i;
            if let Some(sample) = older.next() {
                sum += sample.1;
                window[(head + len) % SMOOTHING] = sample;
                len += 1;
            }
        }
        // Cubic growth through (t1, tilt1) and (t2, tilt2): the onset t0.
        let (t1, tilt1) = first;
        let r = libm::cbrtf(tilt2 / math::max(tilt1, 1e-9));
        if r > 1.0 + 1e-3 && t2 > t1 {
            math::min((t2 - r * t1) / (1.0 - r), t1)
        } else {
            t1
        }
    }

    /// One step with the current attitude estimate, `dt` seconds after the previous one.
    /// Returns the state after the step.
    pub fn step(&mut self, attitude: Quat, dt: f32) -> LiftState {
        let axis = attitude.rotate(Vec3::DOWN);
        match self.state {
            LiftState::Settling => {
                self.reference_axis += axis;
                self.window_low = self.window_low.min(axis);
                self.window_high = self.window_high.max(axis);
                self.timer += dt;
                self.waited += dt;
                if self.timer >= self.config.settle_time {
                    let moved = self.window_movement();
                    self.last_moved = moved;
                    if moved <= self.config.rest_tolerance {
                        self.reference_axis = self.reference_axis.normalized();
                        self.timer = 0.0;
                        self.clock = 0.0;
                        self.history.clear();
                        self.state = LiftState::Ramping;
                    } else if self.waited >= REST_TIMEOUT {
                        self.state = LiftState::Restless;
                    } else {
                        if !self.waiting_told {
                            self.waiting_told = true;
                            self.delay = Some(LiftDelay::Waiting { moved });
                        }
                        self.open_window();
                    }
                }
            }
            LiftState::Ramping | LiftState::HoldingMaximum => {
                let cos = math::clamp(axis.normalized().dot(self.reference_axis), -1.0, 1.0);
                let tilt = crate::math::acos(cos);
                self.clock += dt;
                if self.history.is_full() {
                    self.history.pop_front();
                }
                let tilt_vector = axis.normalized() - self.reference_axis;
                let _ = self.history.push_back((self.clock, tilt_vector));
                if tilt > self.config.tilt_threshold
                    && self.clock < self.config.least_ramp_time
                    && self.redos < MAX_REDOS
                {
                    self.redos += 1;
                    self.delay = Some(LiftDelay::Redone {
                        count: self.redos,
                        after: self.clock,
                    });
                    self.thrust = self.start_thrust;
                    self.waited = 0.0;
                    self.waiting_told = false;
                    self.open_window();
                    self.state = LiftState::Settling;
                } else if tilt > self.config.tilt_threshold {
                    let onset = self.onset(tilt_vector);
                    let at_onset =
                        ramp_back(self.thrust, self.config.ramp_rate, self.clock - onset);
                    let compensated =
                        at_onset - self.config.ramp_rate * self.config.detection_delay;
                    let thrust = crate::math::max(compensated, self.start_thrust);
                    self.state = LiftState::Measured(Measurement::Lifted { thrust });
                } else if self.state == LiftState::Ramping {
                    self.thrust =
                        crate::math::min(self.thrust + self.config.ramp_rate * dt, self.max_thrust);
                    if self.thrust >= self.max_thrust {
                        self.state = LiftState::HoldingMaximum;
                    }
                } else {
                    self.timer += dt;
                    if self.timer >= self.config.settle_time {
                        self.state = LiftState::Measured(Measurement::CouldNotLift);
                    }
                }
            }
            LiftState::Measured(_) | LiftState::Restless => {}
        }
        self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// What a simulated lift gave: the reading (none when the detector gave up), when it
    /// ended, and every wait and restart it told.
    struct Lift {
        reading: Option<Measurement>,
        ended: f32,
        delays: Vec<LiftDelay>,
    }

    /// A payload that starts tilting `lag` seconds after the pair passes `lift_at`, its roll
    /// disturbed by `rocking(t)` (rad) besides.
    fn lift(lift_at: f32, lag: f32, max: f32, rocking: impl Fn(f32) -> f32) -> Lift {
        lift_growing(lift_at, lag, max, rocking, |s| 0.2 * s.powi(3))
    }

    /// As [`lift`], the tilt growing as `growth(time since the lift-off)` once it goes.
    fn lift_growing(
        lift_at: f32,
        lag: f32,
        max: f32,
        rocking: impl Fn(f32) -> f32,
        growth: impl Fn(f32) -> f32,
    ) -> Lift {
        let config = LiftoffConfig {
            detection_delay: lag,
            ..LiftoffConfig::default()
        };
        let mut d = LiftoffDetector::new(config, 0.98, max);
        let dt = 0.0025;
        let mut tilt_start: Option<f32> = None;
        let mut t = 0.0;
        let mut delays = Vec::new();
        loop {
            let thrust = d.pair_thrust();
            if thrust >= lift_at && tilt_start.is_none() {
                tilt_start = Some(t + lag);
            } else if thrust < lift_at {
                // Dropped back below the lift-off (a restart): the payload rests again.
                tilt_start = None;
            }
            // Once it goes the tilt grows as the cube of time (the torque grows with the ramp).
            let tilt = tilt_start.map_or(0.0, |s| growth((t - s).max(0.0)));
            let q = Quat::from_euler(0.02 + tilt + rocking(t), -0.01, 0.3); // resting off level
            let state = d.step(q, dt);
            delays.extend(d.take_delay());
            match state {
                LiftState::Measured(m) => {
                    return Lift {
                        reading: Some(m),
                        ended: t,
                        delays,
                    };
                }
                LiftState::Restless => {
                    return Lift {
                        reading: None,
                        ended: t,
                        delays,
                    };
                }
                _ => {}
            }
            t += dt;
            assert!(t < 60.0, "the lift must end");
        }
    }

    fn run(lift_at: f32, lag: f32, max: f32) -> (Measurement, f32) {
        let l = lift(lift_at, lag, max, |_| 0.0);
        assert!(l.delays.is_empty(), "a payload at rest: {:?}", l.delays);
        (l.reading.expect("a reading"), l.ended)
    }

    fn lifted(m: Option<Measurement>) -> f32 {
        match m {
            Some(Measurement::Lifted { thrust }) => thrust,
            other => panic!("not a lifted reading: {other:?}"),
        }
    }

    /// A decaying rock of `amplitude` rad at 3 Hz, decaying with `tau` s, from time `from`.
    fn rock(amplitude: f32, tau: f32, from: f32) -> impl Fn(f32) -> f32 {
        move |t| {
            if t < from {
                0.0
            } else {
                let s = t - from;
                amplitude * (-s / tau).exp() * (std::f32::consts::TAU * 3.0 * s).sin()
            }
        }
    }

    #[test]
    fn reads_the_lift_off_thrust_with_the_delay_compensated() {
        let (m, _) = run(6.0, 0.005, 14.2);
        let Measurement::Lifted { thrust } = m else {
            panic!("{m:?}");
        };
        // The threshold is crossed at 6 + (0.01 / 0.2)^(1/3) = 6.37 N; the cubic fit through
        // the onset floor finds the lift-off itself.
        assert!((thrust - 6.0).abs() < 0.03, "{thrust}");
    }

    #[test]
    fn a_pair_that_cannot_lift_is_a_censored_reading() {
        let (m, t) = run(20.0, 0.005, 14.2);
        assert_eq!(m, Measurement::CouldNotLift);
        assert!(t > (14.2 - 0.98) / 1.0, "ramped all the way first: {t}");
    }

    #[test]
    fn a_payload_still_rocking_is_waited_for_and_then_read() {
        // Set down from the last lift: rocking 3 degrees, dying out over 0.4 s.
        let l = lift(6.0, 0.005, 14.2, rock(0.05, 0.4, 0.0));
        assert!(
            matches!(l.delays.as_slice(), [LiftDelay::Waiting { moved }] if *moved > 0.005),
            "told once that it waits: {:?}",
            l.delays
        );
        let thrust = lifted(l.reading);
        assert!((thrust - 6.0).abs() < 0.03, "{thrust}");
    }

    #[test]
    fn a_payload_that_never_rests_is_no_reading() {
        let l = lift(6.0, 0.005, 14.2, |t| {
            0.02 * (std::f32::consts::TAU * 2.0 * t).sin()
        });
        assert_eq!(l.reading, None);
        assert!(
            l.ended >= REST_TIMEOUT - 0.01,
            "waited its time: {}",
            l.ended
        );
        assert_eq!(l.delays.len(), 1, "told once: {:?}", l.delays);
    }

    #[test]
    fn a_knock_as_the_ramp_begins_restarts_the_lift_and_is_not_read() {
        // The ramp starts after the 0.5 s settle window; a knock 0.1 s into it rocks the
        // payload 3 degrees. Read as a lift it would be the ramp's first thrust, 1.08 N.
        let l = lift(6.0, 0.005, 14.2, rock(0.05, 0.15, 0.6));
        assert!(
            matches!(l.delays.first(), Some(LiftDelay::Redone { count: 1, after }) if *after < 0.25),
            "{:?}",
            l.delays
        );
        let thrust = lifted(l.reading);
        assert!(
            (thrust - 6.0).abs() < 0.03,
            "the lift's own reading: {thrust}"
        );
    }

    #[test]
    fn a_lift_off_at_the_ramps_first_thrust_that_tips_as_a_lift_does_is_read_at_once() {
        // A COM by the hull's edge: the lift-off 0.01 N above the robots' own weight. The tilt
        // grows as a lift's does (slowly at first), so it crosses the threshold 0.38 s into
        // the ramp.
        let l = lift(0.99, 0.005, 14.2, |_| 0.0);
        assert!(l.delays.is_empty(), "{:?}", l.delays);
        let thrust = lifted(l.reading);
        assert!((thrust - 0.99).abs() < 0.03, "{thrust}");
    }

    #[test]
    fn a_payload_that_tips_at_the_ramps_start_every_time_is_read_there() {
        // A lift-off just above the robots' own weight on a payload that tips fast: every ramp
        // crosses the threshold within 0.1 s. Two restarts, then the reading.
        let l = lift_growing(1.0, 0.005, 14.2, |_| 0.0, |s| 0.5 * s);
        let redone = l
            .delays
            .iter()
            .filter(|d| matches!(d, LiftDelay::Redone { .. }))
            .count();
        assert_eq!(redone, usize::from(MAX_REDOS), "{:?}", l.delays);
        let thrust = lifted(l.reading);
        assert!((thrust - 1.0).abs() < 0.05, "{thrust}");
    }
}
