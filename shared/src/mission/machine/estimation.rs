//! The estimation loop's phases (docs/system.md#estimation-loop): the pre-flight checks, then
//! for each lift the pair chosen (a job), the robots moved, the pair's thrust ramped until the
//! payload lifts off, and the reading's Bayes update (a job) during the relaxation, until the
//! estimate has converged.

use super::Mission;
use crate::control::navigator::NavState;
use crate::control::vector::Vec3;
use crate::estimation::Status;
use crate::liftoff_detector::{LiftState, LiftoffDetector};
use crate::math;
use crate::mission::jobs::{JobRequest, JobResult};
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::mission::supervision::Notice;
use crate::scenario::{GRAVITY, MAX_ROBOTS};

/// Time over which the rotors' thrust falls to zero after a lift is read, s.
pub const SET_DOWN_TIME: f32 = 1.0;

/// Tilt from the lift's resting attitude that cuts the set-down, rad (6 degrees, ten times
/// the lift-off detector's threshold): the lifted edge still rising that far means the ramp
/// pushes past the lift-off, and on a light payload it rolled over (a campaign trial, 7
/// robots, 2.2 kg, tipped past 45 degrees in 0.6 s; cut, it delivers at 0.006 m). At 3
/// degrees a light payload in ground effect was cut where it would have come down by itself,
/// and its knock read as IMU noise.
pub const SET_DOWN_CUT_TILT: f32 = 0.105;

impl Mission {
    /// One robot's weight, N: the thrust that holds a robot that does not lift.
    fn own_weight(&self) -> f32 {
        self.scenario.robots.mass * GRAVITY
    }

    /// The set-down's length, s: [`SET_DOWN_TIME`], at most half the relax time.
    fn set_down_time(&self) -> f32 {
        math::min(SET_DOWN_TIME, 0.5 * self.config.relax_time)
    }

    /// Whether the rotors set the payload down after a lift (armed, their thrust ramping down).
    pub(super) fn setting_down(&self) -> bool {
        self.phase == Phase::Relaxing
            && self.phase_time < self.set_down_time()
            && self.set_down_axis.is_some()
    }

    /// The pre-flight checks: after `checks_time`, a valid position and the payload level
    /// start the estimation; not so by five times that, the mission stops.
    pub(super) fn checks(&mut self, nav: &NavState) -> Option<Transition> {
        if self.phase_time < self.config.checks_time {
            return None;
        }
        let level = nav.level_cosine() > math::cos(0.17);
        if nav.position.valid && level {
            self.request(JobRequest::SelectPair {
                robots: self.robots.clone(),
            });
            Some(self.enter(Phase::SelectingPair, Reason::ChecksPassed))
        } else if self.phase_time > 5.0 * self.config.checks_time {
            Some(self.abort(AbortReason::SensorsNotReady))
        } else {
            None
        }
    }

    /// The pair chosen (the job's result): the robots move to its lift positions.
    pub(super) fn selecting_pair(&mut self) -> Result<Option<Transition>, AbortReason> {
        let Some(result) = self.take_result()? else {
            return Ok(None);
        };
        let JobResult::Pair(plan) = result else {
            return Err(AbortReason::JobOverrun);
        };
        let plan = plan?;
        let reason = Reason::PairChosen {
            group: plan.group,
            information: plan.information,
        };
        self.rail_move = Some((plan.rail_move.clone(), plan.targets.clone()));
        self.lift_plan = Some(plan);
        Ok(Some(self.enter(Phase::MovingRobots, reason)))
    }

    /// The robots moved to the lift positions: the lift begins.
    pub(super) fn moving_to_lift(&mut self) -> Option<Transition> {
        if !self.follow_rail_move() {
            return None;
        }
        self.lift = Some(LiftoffDetector::new(
            self.config.liftoff,
            self.own_weight(),
            self.scenario.robots.max_thrust,
        ));
        Some(self.enter(Phase::Lifting, Reason::RobotsInPlace))
    }

    /// The lift: the pair ramps its thrust, the others hold their own weight, until the
    /// lift-off is read; then the reading's update is asked for.
    pub(super) fn lifting(
        &mut self,
        nav: &NavState,
        dt: f32,
        thrusts: &mut [f32; MAX_ROBOTS],
    ) -> Result<Option<Transition>, AbortReason> {
        let n = self.scenario.robots.count();
        let own = self.own_weight();
        thrusts[..n].iter_mut().for_each(|t| *t = own);
        let Some(lift) = self.lift.as_mut() else {
            return Ok(None);
        };
        let state = lift.step(nav.attitude.attitude, dt);
        let delay = lift.take_delay();
        let moved = lift.window_moved();
        let Some(plan) = self.lift_plan.as_ref() else {
            return Ok(None);
        };
        for &i in &plan.lifting {
            thrusts[i] = lift.pair_thrust();
        }
        if let Some(delay) = delay {
            let group = plan.group;
            if self.notices.is_full() {
                self.notices.pop_front();
            }
            let _ = self.notices.push_back(Notice::LiftDelayed { group, delay });
        }
        if state == LiftState::Restless {
            return Err(AbortReason::PayloadRestless { moved });
        }
        let LiftState::Measured(reading) = state else {
            return Ok(None);
        };
        let group = plan.group;
        self.set_down_from = lift.pair_thrust();
        self.set_down_axis = Some(lift.resting_axis());
        self.lift = None;
        self.request(JobRequest::Update { group, reading });
        Ok(Some(self.enter(Phase::Relaxing, Reason::LiftRead(reading))))
    }

    /// The payload set down and the rotors off while the update runs: then the formation
    /// decision once the estimate has converged often enough in a row, or another lift.
    ///
    /// The set-down: every rotor's thrust falls from the lift's to zero along a ramp of
    /// [`SET_DOWN_TIME`] (at most half the relax time), so the lifted edge comes back down
    /// rather than dropping. Cut at once, a heavy edge fell its lift's height onto the ground;
    /// the knock rang through the IMU's anti-alias filter and notches as some 20 jumps in 32
    /// ticks, which the IMU monitor came close to calling noise, and on a real payload it is a
    /// blow to what it carries.
    pub(super) fn relaxing(
        &mut self,
        nav: &NavState,
        thrusts: &mut [f32; MAX_ROBOTS],
    ) -> Result<Option<Transition>, AbortReason> {
        if let Some(rest) = self.set_down_axis {
            let axis = nav.attitude.attitude.rotate(Vec3::DOWN).normalized();
            if rest.norm() > 0.0
                && math::acos(math::clamp(axis.dot(rest.normalized()), -1.0, 1.0))
                    > SET_DOWN_CUT_TILT
            {
                self.set_down_axis = None;
            }
        }
        let left = 1.0 - self.phase_time / self.set_down_time();
        if left > 0.0 && self.set_down_axis.is_some() {
            let n = self.scenario.robots.count();
            let own = self.own_weight();
            thrusts[..n].iter_mut().for_each(|t| *t = own * left);
            if let Some(plan) = self.lift_plan.as_ref() {
                for &i in &plan.lifting {
                    if let Some(t) = thrusts.get_mut(i) {
                        *t = self.set_down_from * left;
                    }
                }
            }
        }
        if let Some(result) = self.take_result()? {
            let JobResult::Updated(estimate) = result else {
                return Err(AbortReason::JobOverrun);
            };
            let estimate = estimate?;
            if let Status::OutsideGrid(why) = estimate.status {
                return Err(AbortReason::PayloadOutsideGrid(why));
            }
            self.converged_in_a_row = if estimate.status == Status::Converged {
                self.converged_in_a_row + 1
            } else {
                0
            };
            self.latest = Some(estimate);
        }
        if self.phase_time < self.config.relax_time || self.pending.is_some() {
            return Ok(None);
        }
        let Some(estimate) = self.latest else {
            return Ok(None);
        };
        let confirmed = self.converged_in_a_row >= self.config.confirmations;
        let transition = match estimate.status {
            Status::NotConverged => return Err(AbortReason::EstimationNotConverged),
            Status::OutsideGrid(why) => return Err(AbortReason::PayloadOutsideGrid(why)),
            Status::Converged if confirmed => {
                self.estimate = Some(estimate);
                self.request(JobRequest::DecideFormation {
                    robots: self.robots.clone(),
                });
                self.enter(Phase::DecidingFormation, Reason::Converged(estimate.theta))
            }
            Status::Settled => {
                self.estimate = Some(estimate);
                self.request(JobRequest::DecideFormation {
                    robots: self.robots.clone(),
                });
                self.enter(
                    Phase::DecidingFormation,
                    Reason::Settled {
                        theta: estimate.theta,
                        spread: estimate.spread,
                    },
                )
            }
            Status::Converged | Status::Measuring => {
                self.request(JobRequest::SelectPair {
                    robots: self.robots.clone(),
                });
                self.enter(Phase::SelectingPair, Reason::NeedMoreLifts)
            }
        };
        Ok(Some(transition))
    }
}
