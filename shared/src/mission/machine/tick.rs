//! One tick of the mission at 400 Hz (docs/system.md#mission-phases): the IMU sample checked
//! and the navigation updated, the ground link and the battery supervised, the operator's
//! command and the faults the board reports taken, the phase stepped, the rotors watched in
//! flight and the bench's work done, all in this order; and the dispatch to the phase's step.

use super::Mission;
use crate::control::navigator::NavState;
use crate::control::trajectory::FlightPhase;
use crate::flight::{CascadeSetpoints, FlightCommand};
use crate::manual::PilotMode;
use crate::mission::interface::{
    CommandReply, ImuDetection, OperatorCommand, TickInput, TickOutput,
};
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::mission::supervision::Notice;
use crate::scenario::MAX_ROBOTS;

impl Mission {
    /// One tick.
    pub fn step(&mut self, input: &TickInput) -> TickOutput {
        self.tick += 1;
        let dt = self.clock.step(input.time_us);
        self.phase_time += dt;
        // The calibrated offsets off the sample before anything reads it.
        let imu = self.config.sensors.correct(&input.imu);
        // Set down (the plan done, the weight on the ground while the landing is confirmed)
        // counts as on the ground: the rotors spinning down shake the frame as on a lift.
        let airborne = matches!(self.phase, Phase::Flying(p) if p != FlightPhase::Done);
        let imu_failure = self.imu_monitor.check(&imu, airborne);
        let started = !matches!(self.phase, Phase::Idle | Phase::Disarmed | Phase::Aborted);
        if let Some(failure) = imu_failure
            && started
            && self.imu_detection.is_none()
        {
            self.imu_detection = Some(ImuDetection {
                failure,
                time_us: input.time_us,
            });
        }
        if (imu_failure.is_some() || input.faults.imu) && matches!(self.phase, Phase::Flying(_)) {
            // From this sample on the IMU is not to be trusted: land on motion capture.
            self.navigator.drop_imu();
        }
        self.navigator.update(&imu, dt, input.time_us);
        // The fix after the sample: a fix is never newer than the tick it arrives in.
        if let Some(fix) = &input.mocap {
            self.navigator.motion_capture(fix);
        }
        let nav = self.navigator.state();
        let mut thrusts = [0.0f32; MAX_ROBOTS];
        let mut cascade = None;
        // The supervision first: a heartbeat in the start's own tick counts for it.
        let sup = self.config.supervision;
        let link_change = self.link.update(
            input.time_us,
            input.supervision.gcs_heartbeat,
            sup.gcs_timeout,
        );
        let battery_change = self
            .battery
            .update(input.supervision.battery_volts, dt, &sup);
        let mut notice = self.notices.pop_front();
        let pilot = self.pilot_step(input, dt);
        let mut transition = pilot.transition;
        let reply = match input.command {
            Some(c) => {
                let (reply, t) = self.command(c);
                transition = transition.or(t);
                reply
            }
            None => None,
        };
        if transition.is_none()
            && input.command.is_none()
            && let Some(switched) = pilot.command
        {
            let (answer, t) = self.command(switched);
            transition = t;
            if let Some(CommandReply {
                outcome: Err(why), ..
            }) = answer
                && let Some(mode) = PilotMode::from_command(switched)
            {
                self.tell(&mut notice, Notice::SwitchRefused { mode, why });
            }
        }
        if let Some(n) = pilot.notice {
            self.tell(&mut notice, n);
        }
        let mut supervision_landing = false;
        if transition.is_none() {
            let (t, landing, said) = self.supervise(link_change, battery_change, input.time_us, dt);
            transition = t;
            if let Some(why) = landing
                && self.abort.is_none()
            {
                self.abort = Some(why);
                supervision_landing = true;
            }
            for n in said.into_iter().flatten() {
                self.tell(&mut notice, n);
            }
            let (fenced, said) = self.watch_fence(&nav);
            if let Some(why) = fenced
                && self.abort.is_none()
            {
                self.abort = Some(why);
                supervision_landing = true;
            }
            if let Some(n) = said {
                self.tell(&mut notice, n);
            }
        }
        let mut fault_landing = false;
        let fault = input
            .faults
            .reason(self.scenario.robots.count())
            .or(imu_failure.map(AbortReason::from));
        if transition.is_none()
            && let Some(why) = fault
        {
            match self.phase {
                Phase::Idle | Phase::Disarmed | Phase::Aborted => {}
                // In flight: land where it is, once (the reason is kept for the landing).
                Phase::Flying(_) => {
                    if self.abort.is_none() {
                        self.abort = Some(why);
                        fault_landing = true;
                    }
                }
                _ => transition = Some(self.abort(why)),
            }
        }
        if transition.is_none() {
            let flight_command = match input.command.or(pilot.command) {
                Some(OperatorCommand::Kill) => Some(FlightCommand::Kill),
                _ if pilot.flight == Some(FlightCommand::Kill) => Some(FlightCommand::Kill),
                Some(OperatorCommand::LandNow | OperatorCommand::Abort) => {
                    Some(FlightCommand::LandNow)
                }
                _ if fault_landing || supervision_landing => Some(FlightCommand::LandNow),
                _ => pilot.flight,
            };
            if matches!(self.phase, Phase::Flying(_)) {
                self.steer_flight(&nav);
            }
            transition = self.advance(&nav, dt, flight_command, &mut thrusts, &mut cascade);
        }
        if matches!(self.phase, Phase::Flying(_)) {
            self.watch_rotors(input, &nav, &thrusts, dt);
        }
        let setting_down = self.setting_down();
        let mut armed = setting_down
            || matches!(
                self.phase,
                Phase::Lifting | Phase::Arming | Phase::Flying(_)
            );
        if !setting_down && !matches!(self.phase, Phase::Lifting | Phase::Flying(_)) {
            thrusts = [0.0; MAX_ROBOTS];
        }
        let stalled = input.faults.stalled_robots != 0;
        let mut calibrated = None;
        let mut motor_test = false;
        // Nothing on the bench in flight: one look.
        if stalled || self.bench_busy() {
            (motor_test, calibrated) = self.bench_step(&input.imu, dt, stalled, &mut thrusts);
            armed |= motor_test;
        }
        if !matches!(self.phase, Phase::Flying(_)) {
            cascade = None;
        }
        if !motor_test {
            self.compensate_voltage(&mut thrusts, dt);
        }
        if pilot.rotors_off {
            // The kill switch: every rotor at zero from the tick that sees it, whatever the
            // phase or the bench does.
            thrusts = [0.0; MAX_ROBOTS];
        }
        TickOutput {
            thrusts,
            robots: self.robots.clone(),
            armed,
            motor_test,
            phase: self.phase,
            transition,
            adaptation: self.adaptation.take(),
            job: self.outgoing.take(),
            reply,
            notice,
            calibrated,
            nav,
            cascade,
            killed: pilot.rotors_off,
        }
    }

    /// `n` goes out this tick if nothing else does, else in a later one: room for every tick's
    /// notices while one goes out per tick (the oldest is dropped only if ticks of several
    /// came faster than one a tick).
    fn tell(
        &mut self,
        notice: &mut Option<crate::mission::supervision::Notice>,
        n: crate::mission::supervision::Notice,
    ) {
        if notice.is_none() {
            *notice = Some(n);
        } else {
            self.queue_notice(n);
        }
    }

    /// `n` goes out in a later tick, after those already waiting (the oldest is dropped when
    /// the queue is full).
    pub(super) fn queue_notice(&mut self, n: crate::mission::supervision::Notice) {
        if self.notices.is_full() {
            self.notices.pop_front();
        }
        let _ = self.notices.push_back(n);
    }

    /// The phase's step of this tick; an abort when it fails.
    pub(super) fn advance(
        &mut self,
        nav: &NavState,
        dt: f32,
        command: Option<FlightCommand>,
        thrusts: &mut [f32; MAX_ROBOTS],
        cascade: &mut Option<CascadeSetpoints>,
    ) -> Option<Transition> {
        let step = match self.phase {
            Phase::Idle | Phase::Disarmed | Phase::Aborted => Ok(None),
            Phase::PreflightChecks => Ok(self.checks(nav)),
            Phase::SelectingPair => self.selecting_pair(),
            Phase::MovingRobots => Ok(self.moving_to_lift()),
            Phase::Lifting => self.lifting(nav, dt, thrusts),
            Phase::Relaxing => self.relaxing(nav, thrusts),
            Phase::DecidingFormation => self.deciding_formation(),
            Phase::Rearranging => self.rearranging(nav),
            Phase::Arming => Ok((self.phase_time >= self.config.arm_time)
                .then(|| self.enter(Phase::Flying(FlightPhase::Takeoff), Reason::Armed))),
            Phase::Flying(_) => Ok(self.fly(nav, dt, command, thrusts, cascade)),
        };
        step.unwrap_or_else(|why| Some(self.abort(why)))
    }
}
