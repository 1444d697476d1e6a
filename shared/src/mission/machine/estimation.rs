//! The estimation loop's phases (docs/system.md#estimation-loop): the pre-flight checks, then
//! for each lift the pair chosen (a job), the robots moved, the pair's thrust ramped until the
//! payload lifts off, and the reading's Bayes update (a job) during the relaxation, until the
//! estimate has converged.

use super::Mission;
use crate::control::navigator::NavState;
use crate::estimation::Status;
use crate::liftoff_detector::{LiftState, LiftoffDetector};
use crate::math;
use crate::mission::jobs::{JobRequest, JobResult};
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::scenario::{GRAVITY, MAX_ROBOTS};

impl Mission {
    /// One robot's weight, N: the thrust that holds a robot that does not lift.
    fn own_weight(&self) -> f32 {
        self.scenario.robots.mass * GRAVITY
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
    ) -> Option<Transition> {
        let n = self.scenario.robots.count();
        let own = self.own_weight();
        thrusts[..n].iter_mut().for_each(|t| *t = own);
        let lift = self.lift.as_mut()?;
        let state = lift.step(nav.attitude.attitude, dt);
        let plan = self.lift_plan.as_ref()?;
        for &i in &plan.lifting {
            thrusts[i] = lift.pair_thrust();
        }
        let LiftState::Measured(reading) = state else {
            return None;
        };
        let group = plan.group;
        self.lift = None;
        self.request(JobRequest::Update { group, reading });
        Some(self.enter(Phase::Relaxing, Reason::LiftRead(reading)))
    }

    /// The rotors off while the update runs: then the formation decision once the estimate
    /// has converged often enough in a row, or another lift.
    pub(super) fn relaxing(&mut self) -> Result<Option<Transition>, AbortReason> {
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
