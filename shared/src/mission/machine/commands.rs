//! The operator's commands to the mission (docs/ground-link.md#flight-modes,
//! docs/system.md#failsafes): start, resume, hold, land now, abort and kill, what each does in
//! the phase it comes in and why one is refused; and the route a ground station gives the
//! flight (docs/ground-link.md#missions). The bring-up commands are `bench`'s.

use super::Mission;
use crate::flight::Route;
use crate::manual::source::{InputMode, Manual, Source};
use crate::mission::interface::{CommandRefusal, CommandReply, OperatorCommand};
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::mission::supervision::GcsLossAction;

impl Mission {
    /// Flies `route` instead of the payload description's target from the next start (an
    /// empty route: the target again). Refused while the mission runs.
    pub fn set_route(&mut self, route: &Route) -> Result<(), CommandRefusal> {
        if !self.not_running() {
            return Err(CommandRefusal::AlreadyStarted);
        }
        self.route.clone_from(route);
        self.route_first = 0;
        Ok(())
    }

    /// The route flown (empty: the payload description's target).
    pub fn route(&self) -> &Route {
        &self.route
    }

    /// Flies the route from item `item` on: before the start, the flight begins there; in
    /// flight, the vehicle goes there now from where it is. Refused without a route, for an
    /// item it does not have, once landing, or (before the start) for an item the vehicle
    /// cannot take off to.
    pub fn set_route_item(&mut self, item: u8) -> Result<(), CommandRefusal> {
        let first = usize::from(item);
        if first >= self.route.len() {
            return Err(CommandRefusal::NoRouteItem);
        }
        match self.phase {
            Phase::Flying(_) => {
                let landing = self
                    .flight
                    .as_ref()
                    .is_none_or(|f| f.landing_cause().is_some() || f.stopped().is_some());
                if landing || self.abort.is_some() {
                    return Err(CommandRefusal::Landing);
                }
                self.jump = Some(item);
            }
            _ if self.not_running() || self.flight.is_none() => {
                Route::new(&self.route.items()[first..])
                    .map_err(|_| CommandRefusal::NoRouteItem)?;
                self.route_first = item;
            }
            _ => return Err(CommandRefusal::AlreadyStarted),
        }
        Ok(())
    }

    /// The route's progress in flight: the item flown (the first one before the flight) and
    /// the last one reached; `None` without a route.
    pub fn route_progress(&self) -> Option<(u8, Option<u8>)> {
        if self.route.is_empty() {
            return None;
        }
        Some(
            self.flight
                .as_ref()
                .map_or((self.route_first, None), |f| f.route_progress()),
        )
    }

    /// Whether the operator holds the vehicle where it is (and it is not landing).
    pub fn held(&self) -> bool {
        self.held && self.flight.as_ref().is_some_and(|f| f.holding())
    }

    /// The operator's command; the transition it makes on the ground, if any (in flight the
    /// flight stack carries it out).
    pub(super) fn command(
        &mut self,
        command: OperatorCommand,
    ) -> (Option<CommandReply>, Option<Transition>) {
        // Mission mode asked for before the start: the start; Position mode too, the sticks
        // taking over after the take-off.
        let asked = command;
        let command = match command {
            OperatorCommand::Resume | OperatorCommand::Position if self.phase == Phase::Idle => {
                OperatorCommand::Start
            }
            other => other,
        };
        // Another mode than Position in the air: the sticks let go first.
        if matches!(
            command,
            OperatorCommand::Resume
                | OperatorCommand::Hold
                | OperatorCommand::LandNow
                | OperatorCommand::Abort
                | OperatorCommand::Kill
        ) && self.position
            && matches!(self.phase, Phase::Flying(_))
        {
            self.position = false;
            self.manual_hold = None;
            self.leave_steering();
            self.apply_hold();
            if command == OperatorCommand::Resume {
                return (
                    Some(CommandReply {
                        command,
                        outcome: Ok(()),
                    }),
                    None,
                );
            }
        }
        self.stop_motor_test_for(command);
        if command.is_bench() {
            let outcome = self.bench_command(command);
            return (Some(CommandReply { command, outcome }), None);
        }
        let finished = matches!(self.phase, Phase::Disarmed | Phase::Aborted);
        let flying = matches!(self.phase, Phase::Flying(_));
        let mut transition = None;
        let outcome = match command {
            OperatorCommand::Kill if finished => Ok(()),
            _ if finished => Err(CommandRefusal::Finished),
            OperatorCommand::Start if self.scenario.robots.count() == 0 => {
                Err(CommandRefusal::NoPayload)
            }
            // The pre-arm checks of the bench: the rails known, each robot on its mark,
            // nothing under way.
            OperatorCommand::Start if self.phase == Phase::Idle && self.rails_ready().is_err() => {
                Err(self
                    .rails_ready()
                    .err()
                    .unwrap_or(CommandRefusal::RailsUnconfirmed))
            }
            OperatorCommand::Start if self.phase == Phase::Idle && self.bench_busy() => {
                Err(CommandRefusal::BenchBusy)
            }
            // The pre-arm checks of manual control: the kill switch off, and an RC receiver
            // heard when `COM_RC_IN_MODE` takes RC alone.
            OperatorCommand::Start if self.phase == Phase::Idle && self.pilot.kill_on() => {
                Err(CommandRefusal::KillSwitchOn)
            }
            OperatorCommand::Start
                if self.phase == Phase::Idle
                    && self.config.manual.input_mode == InputMode::RcOnly
                    && !matches!(self.pilot.current(), Manual::Valid(Source::Rc, _)) =>
            {
                Err(CommandRefusal::NoManualControl { rc: true })
            }
            OperatorCommand::Start
                if self.phase == Phase::Idle
                    && self.config.supervision.gcs_action != GcsLossAction::Off
                    && !self.link.up() =>
            {
                Err(CommandRefusal::NoGroundLink)
            }
            OperatorCommand::Start
                if self.phase == Phase::Idle
                    && self.battery.volts().is_some_and(|v| {
                        let low = self.config.supervision.battery_low;
                        let critical = self.config.supervision.battery_critical;
                        (low > 0.0 && v < low) || (critical > 0.0 && v < critical)
                    }) =>
            {
                let volts = self.battery.volts().unwrap_or(0.0);
                Err(CommandRefusal::BatteryLow {
                    millivolts: (volts * 1000.0) as u32,
                })
            }
            OperatorCommand::Start if self.phase == Phase::Idle => {
                // A pack changed since a low reading is graded afresh.
                self.battery.regrade(&self.config.supervision);
                transition = Some(self.enter(Phase::PreflightChecks, Reason::Started));
                self.position = asked == OperatorCommand::Position;
                Ok(())
            }
            OperatorCommand::Position if flying => self.enter_position(),
            // Before the take-off: the sticks take over after it.
            OperatorCommand::Position => {
                self.position = true;
                Ok(())
            }
            OperatorCommand::Start | OperatorCommand::Resume if flying && self.held => {
                self.held = false;
                self.apply_hold();
                Ok(())
            }
            // A second start of the mission running (a ground station's beside the operator's,
            // as QGroundControl's Start Mission sends it), or mission mode asked for while the
            // mission runs: it is in it already. Taken, and nothing changes (PX4 accepts
            // MAV_CMD_MISSION_START in mission mode so).
            OperatorCommand::Start | OperatorCommand::Resume => Ok(()),
            OperatorCommand::Hold if !flying => Err(CommandRefusal::NotFlying),
            OperatorCommand::Hold => {
                let cruising = self.cruising();
                // A hold before the payload has left the ground would hold it there under
                // take-off thrust.
                let airborne = self.flight.as_ref().is_some_and(|f| f.airborne());
                if !airborne {
                    Err(CommandRefusal::NotFlying)
                } else if cruising {
                    self.held = true;
                    self.apply_hold();
                    Ok(())
                } else {
                    Err(CommandRefusal::Landing)
                }
            }
            OperatorCommand::LandNow if !flying => Err(CommandRefusal::NotFlying),
            OperatorCommand::Abort if flying => {
                self.abort = Some(AbortReason::OperatorAbort);
                Ok(())
            }
            OperatorCommand::Abort => {
                transition = Some(self.abort(AbortReason::OperatorAbort));
                Ok(())
            }
            OperatorCommand::Kill if !flying => {
                transition = Some(self.abort(AbortReason::Killed));
                Ok(())
            }
            OperatorCommand::Kill | OperatorCommand::LandNow => Ok(()),
            // Taken above.
            OperatorCommand::ConfirmRails
            | OperatorCommand::Jog { .. }
            | OperatorCommand::Calibrate(_)
            | OperatorCommand::MotorTest(_) => Ok(()),
        };
        (Some(CommandReply { command, outcome }), transition)
    }
}
