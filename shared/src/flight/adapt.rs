//! The formation adapts in flight to a load that shifts (beyond the paper, which names a load
//! that moves during flight as future work; docs/models.md#in-flight-adaptation).
//!
//! In a hover the trim ([`crate::flight::trim`]) measures where the payload's COM lies from
//! the wrench the rotors deliver. When that COM sits more than [`AdaptConfig::threshold`]
//! from the one the formation was solved for, and stays there for [`AdaptConfig::hold`]
//! seconds of confident estimates, the adapter asks for a new formation about it (a job, off
//! the tick, as on the ground). The robots then move to it along the rail, all together on
//! one time profile ([`RailMove`]: cyclic order and spacing hold at every instant) at the
//! in-flight speed [`AdaptConfig::rail`], and the mixer is rebuilt every tick from where the
//! robots are, so the allocation always matches the rotors' real positions. While it adapts
//! the hover is held (up to [`AdaptConfig::max_hold`] seconds) instead of landing an
//! unbalanced payload.
//!
//! The adapter is sans-IO: the mission feeds it each tick's delivered wrench and state, runs
//! the job it asks for and hands back the plan.

use crate::control::allocation::Wrench;
use crate::control::navigator::NavState;
use crate::geometry::{Rail, Vec2};
use crate::math;
use crate::numbers::Fixed;
use crate::rail::moves::{Positions, RailMove};
use crate::rail::stepper::MotionLimits;

use super::trim::{TrimConfig, TrimEstimator};

/// Tuning of the in-flight adaptation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptConfig {
    /// Adapt at all (`host-sim mission --no-adapt` switches it off).
    pub enabled: bool,
    /// Distance of the measured COM from the formation's COM that calls for a new formation,
    /// m. Above the estimation's own error on the paper's cases (a few centimetres), so a
    /// flight whose load did not move does not re-form.
    pub threshold: f32,
    /// Time the confident estimate must stay beyond the threshold before the robots move, s.
    pub hold: f32,
    /// Longest the hover is held for an adaptation, s; after it the plan goes on.
    pub max_hold: f32,
    /// Rail speed and acceleration in flight (slower than on the ground: the mixer follows).
    pub rail: MotionLimits,
    /// The trim estimator's window and hover criteria.
    pub trim: TrimConfig,
}

impl AdaptConfig {
    /// The defaults: a 6 cm threshold held for 1 s, 0.1 m/s on the rail, a 2 s trim window
    /// whose halves agree within 2 cm (the paper's disturbance, 0.3 N m at 0.37 and 0.53 Hz,
    /// moves a one-second average by up to about 7 mm on the paper's payloads).
    pub const DEFAULT: Self = Self {
        enabled: true,
        threshold: 0.06,
        hold: 1.0,
        max_hold: 30.0,
        rail: MotionLimits {
            max_speed: 0.1,
            max_acceleration: 0.2,
        },
        trim: TrimConfig {
            window: 2.0,
            max_speed: 0.15,
            max_tilt: 0.1,
            max_rate: 0.3,
            steadiness: 0.02,
        },
    };
}

impl Default for AdaptConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the adapter did this tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AdaptEvent {
    /// The COM has moved: a formation about this COM and mass is wanted.
    Shifted {
        /// The measured COM, body frame, m.
        com: Vec2,
        /// The measured mass, kg.
        mass: f32,
    },
    /// The robots started moving to the new formation; the move takes this long, s.
    Moving {
        /// Duration of the move, s.
        duration: f32,
    },
    /// The robots reached the new formation.
    Rebalanced,
    /// No new formation could be had (out of reach, or the job failed): the flight goes on
    /// with the one it has.
    GaveUp,
}

impl core::fmt::Display for AdaptEvent {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Shifted { com, mass } => write!(
                f,
                "the load shifted: COM ({}, {}) m, mass {} kg",
                Fixed(com.x, 3),
                Fixed(com.y, 3),
                Fixed(mass, 2)
            ),
            Self::Moving { duration } => {
                write!(
                    f,
                    "robots moving to the new formation ({} s)",
                    Fixed(duration, 1)
                )
            }
            Self::Rebalanced => write!(f, "rebalanced: the robots are in the new formation"),
            Self::GaveUp => write!(f, "no new formation: flying on with the one it has"),
        }
    }
}

/// Where the adaptation stands.
// Without an allocator the move cannot be boxed; the adapter lives once, in the mission.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
enum Stage {
    /// Measuring.
    Watching,
    /// A formation about the new COM was asked for.
    Solving,
    /// The robots move: the plan, where to, time into it.
    Moving(RailMove, Positions, f32),
}

/// The in-flight adapter.
#[derive(Clone, Debug, PartialEq)]
pub struct Adapter {
    config: AdaptConfig,
    trim: TrimEstimator,
    /// The COM and mass the formation and the mixer are built for.
    com: Vec2,
    mass: f32,
    /// Time the confident estimate has been beyond the threshold, s.
    beyond: f32,
    /// The last estimate (even unconfident) was beyond the threshold.
    off_balance: bool,
    /// Time the hover has been held, s.
    held: f32,
    stage: Stage,
    /// The COM and mass asked for, while solving and moving.
    wanted: (Vec2, f32),
}

impl Adapter {
    /// An adapter for a formation solved about `com` for a payload of `mass`, carried by
    /// robots of `robots_mass` in all.
    pub fn new(config: AdaptConfig, com: Vec2, mass: f32, robots_mass: f32) -> Self {
        Self {
            config,
            trim: TrimEstimator::new(config.trim, mass, robots_mass),
            com,
            mass,
            beyond: 0.0,
            off_balance: false,
            held: 0.0,
            stage: Stage::Watching,
            wanted: (com, mass),
        }
    }

    /// The COM and mass the mixer is built for now: the formation's, and while the robots
    /// move, carried from the old COM to the new one as they go (a reference point that
    /// jumped would hand the controller the whole shift's torque at once).
    pub fn belief(&self) -> (Vec2, f32) {
        match &self.stage {
            Stage::Moving(mv, _, t) => {
                let d = mv.duration();
                let x = if d > 0.0 { math::min(*t / d, 1.0) } else { 1.0 };
                // Smooth at both ends, as the robots' own profile.
                let lambda = x * x * (3.0 - 2.0 * x);
                let (from, to) = (self.com, self.wanted.0);
                let mass = self.mass + lambda * (self.wanted.1 - self.mass);
                (from + (to - from) * lambda, mass)
            }
            _ => (self.com, self.mass),
        }
    }

    /// Whether the plan's hover should be held: the payload is off balance, a formation is
    /// being solved or the robots are moving (never beyond [`AdaptConfig::max_hold`]).
    pub fn holds_hover(&self) -> bool {
        self.config.enabled
            && self.held < self.config.max_hold
            && (self.off_balance || !matches!(self.stage, Stage::Watching))
    }

    /// One tick in a hover or transit: the wrench the rotors delivered about the believed COM
    /// and the state; `hovering` says whether the plan is in its hover; `dt` seconds since
    /// the last tick. Returns [`AdaptEvent::Shifted`] when a new formation is wanted.
    pub fn observe(
        &mut self,
        delivered: &Wrench,
        nav: &NavState,
        hovering: bool,
        dt: f32,
    ) -> Option<AdaptEvent> {
        if !self.config.enabled {
            return None;
        }
        if self.holds_hover() && hovering {
            self.held += dt;
        }
        if !matches!(self.stage, Stage::Watching) {
            return None;
        }
        // Saturation is judged by the state: the delivered wrench is what held the payload.
        self.trim.update(delivered, nav, false, dt);
        let Some(estimate) = self.trim.estimate() else {
            self.beyond = 0.0;
            return None;
        };
        let far = estimate.com_offset.norm() > self.config.threshold;
        self.off_balance = far;
        if !(far && estimate.confident) {
            self.beyond = 0.0;
            return None;
        }
        self.beyond += dt;
        if self.beyond < self.config.hold || !hovering {
            return None;
        }
        let com = self.com + estimate.com_offset;
        let mass = if estimate.mass.is_finite() && estimate.mass > 0.0 {
            estimate.mass
        } else {
            self.mass
        };
        self.stage = Stage::Solving;
        self.wanted = (com, mass);
        Some(AdaptEvent::Shifted { com, mass })
    }

    /// The new formation for the COM asked for, or `None` if none could be had; the robots
    /// are at `robots` on `rail` with `min_spacing`.
    pub fn formation(
        &mut self,
        solved: Option<&Positions>,
        rail: &Rail,
        robots: &[f32],
        min_spacing: f32,
    ) -> AdaptEvent {
        let planned = solved.and_then(|to| {
            RailMove::plan(rail, robots, to, min_spacing, self.config.rail)
                .ok()
                .map(|mv| (mv, to.clone()))
        });
        match planned {
            Some((mv, to)) => {
                let duration = mv.duration();
                self.stage = Stage::Moving(mv, to, 0.0);
                AdaptEvent::Moving { duration }
            }
            None => {
                self.give_up();
                AdaptEvent::GaveUp
            }
        }
    }

    /// Gives up the adaptation under way: the flight goes on with what it has, and the
    /// adapter watches no more.
    pub fn give_up(&mut self) {
        self.stage = Stage::Watching;
        self.off_balance = false;
        self.config.enabled = false;
    }

    /// While the robots move: where they are after `dt` more seconds, and whether they have
    /// arrived ([`AdaptEvent::Rebalanced`], after which the trim measures afresh).
    pub fn move_step(&mut self, rail: &Rail, dt: f32) -> Option<(Positions, Option<AdaptEvent>)> {
        let Stage::Moving(mv, to, t) = &mut self.stage else {
            return None;
        };
        *t += dt;
        if *t < mv.duration() {
            return Some((mv.positions_at(rail, *t), None));
        }
        let arrived = to.clone();
        (self.com, self.mass) = self.wanted;
        self.stage = Stage::Watching;
        self.off_balance = false;
        self.beyond = 0.0;
        self.held = 0.0;
        self.trim.restart(self.mass);
        Some((arrived, Some(AdaptEvent::Rebalanced)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::attitude_estimator::AttitudeState;
    use crate::control::position_estimator::PositionState;
    use crate::control::vector::{Quat, Vec3};
    use crate::scenario::GRAVITY;

    fn hover() -> NavState {
        NavState {
            attitude: AttitudeState {
                attitude: Quat::IDENTITY,
                rate: Vec3::ZERO,
                gyro_bias: Vec3::ZERO,
            },
            position: PositionState {
                position: Vec3::new(0.0, 0.0, -0.5),
                velocity: Vec3::ZERO,
                valid: true,
            },
        }
    }

    /// The wrench that holds `mass` with its COM `delta` from the believed one, under the
    /// paper's disturbance.
    fn held(mass: f32, delta: Vec2, t: f32) -> Wrench {
        let w = mass * GRAVITY;
        let d = 0.3 * libm::sinf(2.0 * core::f32::consts::PI * 0.37 * t);
        Wrench {
            thrust: (mass + 0.8) * GRAVITY,
            torque: Vec3::new(-delta.y * w + d, delta.x * w - d, 0.0),
        }
    }

    fn run(adapter: &mut Adapter, delta: Vec2, seconds: f32) -> Option<AdaptEvent> {
        let dt = 0.0025;
        let mut t = 0.0;
        let mut event = None;
        while t < seconds {
            if let Some(e) = adapter.observe(&held(3.3, delta, t), &hover(), true, dt) {
                event = Some(e);
            }
            t += dt;
        }
        event
    }

    #[test]
    fn a_balanced_hover_never_asks_for_a_new_formation() {
        let mut a = Adapter::new(AdaptConfig::DEFAULT, Vec2::new(0.2, 0.0), 3.3, 0.8);
        assert_eq!(run(&mut a, Vec2::new(0.02, -0.01), 30.0), None);
        assert!(!a.holds_hover());
    }

    #[test]
    fn a_shifted_load_asks_for_a_formation_about_the_new_com() {
        let mut a = Adapter::new(AdaptConfig::DEFAULT, Vec2::new(0.2, 0.0), 3.3, 0.8);
        let event = run(&mut a, Vec2::new(0.15, 0.0), 4.0).expect("a shift is seen");
        let AdaptEvent::Shifted { com, mass } = event else {
            panic!("{event:?}");
        };
        assert!((com - Vec2::new(0.35, 0.0)).norm() < 0.01, "{com:?}");
        assert!((mass - 3.3).abs() < 0.05, "{mass}");
        assert!(a.holds_hover(), "the hover waits for the new formation");
    }

    #[test]
    fn switched_off_it_does_nothing() {
        let config = AdaptConfig {
            enabled: false,
            ..AdaptConfig::DEFAULT
        };
        let mut a = Adapter::new(config, Vec2::new(0.2, 0.0), 3.3, 0.8);
        assert_eq!(run(&mut a, Vec2::new(0.15, 0.0), 10.0), None);
        assert!(!a.holds_hover());
    }

    /// A 1 m square rail: perimeter 4 m.
    fn square() -> Rail {
        Rail::new(&[
            Vec2::new(-0.5, -0.5),
            Vec2::new(0.5, -0.5),
            Vec2::new(0.5, 0.5),
            Vec2::new(-0.5, 0.5),
        ])
        .expect("a square")
    }

    #[test]
    fn the_robots_move_to_the_new_formation_keeping_order_and_spacing() {
        let rail = square();
        let from: Positions = [0.0, 1.0, 2.0, 3.0].into_iter().collect();
        let to: Positions = [0.2, 1.1, 2.3, 3.1].into_iter().collect();
        let mut a = Adapter::new(AdaptConfig::DEFAULT, Vec2::new(0.2, 0.0), 3.3, 0.8);
        run(&mut a, Vec2::new(0.15, 0.0), 4.0).expect("a shift is seen");
        let AdaptEvent::Moving { duration } = a.formation(Some(&to), &rail, &from, 0.25) else {
            panic!("a move");
        };
        assert!(duration > 0.0);
        assert!(
            (a.belief().0 - Vec2::new(0.2, 0.0)).norm() < 1e-6,
            "from the old COM"
        );
        let mut last = None;
        for _ in 0..((duration / 0.0025) as usize + 2) {
            let (p, event) = a.move_step(&rail, 0.0025).expect("moving");
            assert!(
                crate::formation::search::order_and_spacing_hold(&rail, &p, 0.25 - 1e-4),
                "{p:?}"
            );
            if event.is_some() {
                last = Some((p, event));
                break;
            }
        }
        let (p, event) = last.expect("arrived");
        assert_eq!(event, Some(AdaptEvent::Rebalanced));
        assert_eq!(p, to);
        assert!(
            (a.belief().0 - Vec2::new(0.35, 0.0)).norm() < 0.01,
            "to the new one"
        );
        assert!(!a.holds_hover());
    }

    #[test]
    fn no_formation_gives_up_and_the_flight_goes_on() {
        let rail = square();
        let from: Positions = [0.0, 1.0, 2.0, 3.0].into_iter().collect();
        let mut a = Adapter::new(AdaptConfig::DEFAULT, Vec2::new(0.2, 0.0), 3.3, 0.8);
        run(&mut a, Vec2::new(0.15, 0.0), 4.0).expect("a shift is seen");
        assert_eq!(a.formation(None, &rail, &from, 0.25), AdaptEvent::GaveUp);
        assert!(!a.holds_hover());
        assert_eq!(run(&mut a, Vec2::new(0.15, 0.0), 4.0), None);
    }
}
