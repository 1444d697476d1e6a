//! From the estimate to the landing: the formation decision (docs/system.md#formation-decision),
//! the rearrangement and the flight's build (docs/system.md#rearrangement), the flight itself
//! (docs/system.md#flight) and, in it, the adaptation to a load that shifts
//! (docs/system.md#in-flight-adaptation).

use super::{Mission, PendingJob};
use crate::control::navigator::NavState;
use crate::control::trajectory::FlightPhase;
use crate::control::vector::Vec3;
use crate::flight::{
    AdaptEvent, Adapter, CascadeSetpoints, FlightCommand, FlightEvent, FlightModel, FlightStack,
    FlightStop, LandingCause,
};
use crate::geometry::Vec2;
use crate::mission::jobs::{JobRequest, JobResult};
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::mission::supervision::Notice;
use crate::scenario::MAX_ROBOTS;

impl Mission {
    /// The formation chosen (the job's result): the robots move to it.
    pub(super) fn deciding_formation(&mut self) -> Result<Option<Transition>, AbortReason> {
        let Some(result) = self.take_result()? else {
            return Ok(None);
        };
        let JobResult::Formation(plan) = result else {
            return Err(AbortReason::JobOverrun);
        };
        let plan = plan?;
        self.formation = Some(plan.positions.clone());
        self.rail_move = Some((plan.rail_move, plan.positions));
        Ok(Some(self.enter(
            Phase::Rearranging,
            Reason::FormationChosen(plan.det),
        )))
    }

    /// The robots moved to the formation, then the flight built from the mixer and vehicle
    /// model (the job's result); arming begins in the next tick.
    pub(super) fn rearranging(
        &mut self,
        nav: &NavState,
    ) -> Result<Option<Transition>, AbortReason> {
        if self.flight_built {
            return Ok(Some(self.enter(Phase::Arming, Reason::FlightReady)));
        }
        if self.rail_move.is_some() {
            if self.follow_rail_move() {
                self.request(JobRequest::BuildFlight {
                    robots: self.robots.clone(),
                });
            }
            return Ok(None);
        }
        let Some(result) = self.take_result()? else {
            return Ok(None);
        };
        let JobResult::Flight(model) = result else {
            return Err(AbortReason::JobOverrun);
        };
        let model = model?;
        let start = nav.position.position;
        // A route's flight: built for the payload description's target (or, without one, a
        // hover above the take-off point), then its plan filled with the route in place.
        let target = match self.scenario.flight {
            Some(f) => f.target,
            None if !self.route.is_empty() => [start.x, start.y, 0.0],
            None => return Err(AbortReason::NoFlightTarget),
        };
        self.home = Some(start);
        let flight = self
            .flight
            .insert(FlightStack::new(self.config.flight, model, start, target));
        if !self.route.is_empty() {
            flight.follow_route(start, &self.route, usize::from(self.route_first));
        }
        self.adapter = self.estimate.map(|e| {
            let r = &self.scenario.robots;
            Adapter::new(
                self.config.adapt,
                Vec2::new(e.theta[0], e.theta[1]),
                e.theta[2],
                r.mass * r.count() as f32,
            )
        });
        self.flight_built = true;
        Ok(None)
    }

    /// The flight's step: the rotors' thrusts and the cascade's setpoints, the navigation told
    /// the rotors' command when it flies without the IMU, the adaptation, and the phase the
    /// flight's event moves to.
    pub(super) fn fly(
        &mut self,
        nav: &NavState,
        dt: f32,
        command: Option<FlightCommand>,
        thrusts: &mut [f32; MAX_ROBOTS],
        cascade: &mut Option<CascadeSetpoints>,
    ) -> Option<Transition> {
        self.fly_full_mixer();
        let flight = self.flight.as_mut()?;
        if let Some(item) = self.jump.take() {
            flight.follow_route(nav.position.position, &self.route, usize::from(item));
        }
        let out = flight.step(nav, command, dt);
        *cascade = out.cascade;
        let n = self.scenario.robots.count();
        thrusts[..n].copy_from_slice(&out.thrusts[..n]);
        if self.navigator.imu_dropped() {
            // Without the IMU the navigation predicts from what the rotors were told.
            let wrench = flight.mixer().wrench_of(&out.thrusts[..n]);
            let vehicle = flight.vehicle();
            let per = |torque: f32, inertia: f32| {
                if inertia > 0.0 { torque / inertia } else { 0.0 }
            };
            let i = vehicle.inertia;
            let alpha = Vec3::new(
                per(wrench.torque.x, i.x),
                per(wrench.torque.y, i.y),
                per(wrench.torque.z, i.z),
            );
            let force = Vec3::new(0.0, 0.0, -per(wrench.thrust, vehicle.mass));
            self.navigator.rotor_command(alpha, force);
        }
        self.adapt(nav, &out.thrusts[..n], dt);
        let event = out.event?;
        let (to, reason) = match event {
            FlightEvent::Advanced(phase) => (Phase::Flying(phase), Reason::PlanAdvanced),
            FlightEvent::Landing(cause) => {
                let reason = match cause {
                    LandingCause::PositionLost => Reason::Abort(AbortReason::PositionLost),
                    LandingCause::TrackingLost => Reason::Abort(AbortReason::TrackingLost),
                    LandingCause::RotorOut { robot } => {
                        Reason::Abort(AbortReason::RotorOut { robot })
                    }
                    LandingCause::Operator => match self.abort {
                        Some(
                            why @ (AbortReason::OperatorAbort
                            | AbortReason::ImuFault
                            | AbortReason::ImuStuck
                            | AbortReason::ImuNoisy
                            | AbortReason::RobotStalled { .. }
                            | AbortReason::GcsLost
                            | AbortReason::GeofenceBreached { .. }
                            | AbortReason::ManualLost
                            | AbortReason::BatteryCritical { .. }),
                        ) => Reason::Abort(why),
                        _ => Reason::LandNow,
                    },
                };
                (Phase::Flying(FlightPhase::Land), reason)
            }
            FlightEvent::Stopped(FlightStop::Landed) => (Phase::Disarmed, Reason::Landed),
            FlightEvent::Stopped(FlightStop::TakeoffFailed { height }) => (
                Phase::Aborted,
                Reason::Abort(AbortReason::TakeoffFailed { height }),
            ),
            FlightEvent::Stopped(FlightStop::NoPosition) => {
                (Phase::Aborted, Reason::Abort(AbortReason::PositionLost))
            }
            // Landing asked for before the payload left the ground: the reason it was asked for.
            FlightEvent::Stopped(FlightStop::OperatorGrounded) => (
                Phase::Aborted,
                Reason::Abort(self.abort.unwrap_or(AbortReason::OperatorAbort)),
            ),
            FlightEvent::Stopped(FlightStop::Killed) => {
                (Phase::Aborted, Reason::Abort(AbortReason::Killed))
            }
        };
        Some(self.enter(to, reason))
    }

    /// After rotors were found stopped: takes the full mixer without them at its job's tick
    /// (the step flew the interim one until then), says what was found and whether the rotors
    /// left hold the hover, and asks again while the flight still wants a mixer (a result
    /// missing or built for an earlier layout).
    fn fly_full_mixer(&mut self) {
        let Some(flight) = self.flight.as_mut() else {
            return;
        };
        if self
            .pending
            .as_ref()
            .is_some_and(|p| p.mixer && self.tick >= p.due)
        {
            // Read where it lies: a job's result is up to the flight model's 2.8 KB, and a
            // copy of it costs the control step over 1,000 instructions.
            let held = match self.pending.as_ref().and_then(|p| p.result.as_ref()) {
                Some(JobResult::MixerWithout(Ok(left))) => {
                    flight.take_mixer(&left.mixer).then_some(left.holds_level)
                }
                // The rotors left cannot make thrust, roll and pitch: fly on with the interim
                // mixer and land; nothing is held level.
                Some(JobResult::MixerWithout(Err(_))) => {
                    flight.keep_interim_mixer();
                    Some(false)
                }
                _ => None,
            };
            self.pending = None;
            if let Some(held) = held
                && let Some(mut notice) = self.rotors_notice.take()
            {
                if let Notice::RotorsOut { holdable, .. } = &mut notice {
                    *holdable = held;
                }
                // Out with the next tick's (this one's notice was taken at its start).
                self.queue_notice(notice);
            }
        }
        self.ask_for_mixer();
    }

    /// Asks the job side for the full mixer without the rotors out while the flight flies
    /// the interim one and no job is pending; whether it asked.
    pub(super) fn ask_for_mixer(&mut self) -> bool {
        let Some(flight) = self.flight.as_ref() else {
            return false;
        };
        let Some(out) = flight.mixer_wanted().filter(|_| self.pending.is_none()) else {
            return false;
        };
        let job = JobRequest::MixerWithout {
            robots: self.robots.clone(),
            com: flight.com(),
            out,
            weight: flight.hover_thrust(),
        };
        self.request(job);
        true
    }

    /// The in-flight adaptation after this tick's flight step: measure in the hover, ask for a
    /// new formation when the load has shifted, take it at its deadline, move the robots and
    /// fly every tick with the mixer of where they are.
    fn adapt(&mut self, nav: &NavState, thrusts: &[f32], dt: f32) {
        let (Some(flight), Some(adapter)) = (self.flight.as_mut(), self.adapter.as_mut()) else {
            return;
        };
        let rail = &self.scenario.payload.rail;
        let mut event = None;
        if let Some((positions, arrived)) = adapter.move_step(rail, dt) {
            self.robots = positions;
            event = arrived;
            let (com, mass) = adapter.belief();
            // A layout the mixer cannot fly (it cannot happen between two balanced formations
            // of the same rail, but never on trust): keep the last mixer and stop adapting.
            match FlightModel::build(&self.scenario, &self.robots, com, mass, self.config.mixer) {
                Ok(model) => flight.set_model(model),
                Err(_) => {
                    adapter.give_up();
                    event = Some(AdaptEvent::GaveUp);
                }
            }
        } else if self.pending.as_ref().is_some_and(|p| !p.mixer) {
            let taken = match &mut self.pending {
                Some(p) if self.tick >= p.due => {
                    let result = p.result.take();
                    self.pending = None;
                    Some(result)
                }
                _ => None,
            };
            if let Some(result) = taken {
                let solved = match result {
                    Some(JobResult::Reformed(Ok((positions, _det)))) => Some(positions),
                    _ => None,
                };
                event = Some(adapter.formation(
                    solved.as_ref(),
                    rail,
                    &self.robots,
                    self.scenario.robots.min_spacing,
                ));
            }
        } else if self.pending.is_none() && flight.airborne() && flight.landing_cause().is_none() {
            let phase = flight.phase();
            let cruising = matches!(phase, FlightPhase::Transit | FlightPhase::Hover);
            if cruising {
                let delivered = flight.mixer().wrench_of(thrusts);
                let hovering = phase == FlightPhase::Hover;
                if let Some(shifted) = adapter.observe(&delivered, nav, hovering, dt) {
                    if let AdaptEvent::Shifted { com, .. } = shifted {
                        let job = JobRequest::Reform {
                            robots: self.robots.clone(),
                            com,
                        };
                        self.pending = Some(PendingJob {
                            due: self.tick + u64::from(job.deadline_ticks()),
                            result: None,
                            mixer: false,
                        });
                        self.outgoing = Some(job);
                    }
                    event = Some(shifted);
                }
            }
        }
        let holding = flight.landing_cause().is_none() && adapter.holds_hover();
        flight.hold_hover(holding);
        self.adaptation = event;
    }
}
