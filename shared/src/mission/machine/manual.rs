//! What a person's sticks and switches mean to the mission (docs/manual-control.md): the kill
//! switch's rotors off then disarm, whatever the phase; the mode switch in flight (Mission,
//! Hold, Land, Position); Position mode's steering; and manual control lost, which in Position
//! mode holds, then takes `NAV_RCL_ACT`'s action, and in Mission mode lets the mission go on.

use super::Mission;
use crate::control::navigator::NavState;
use crate::control::trajectory::FlightPhase;
use crate::flight::{FlightCommand, ManualVelocity};
use crate::manual::kill::KillAction;
use crate::manual::source::Manual;
use crate::manual::{ManualLossAction, PilotMode};
use crate::mission::interface::{CommandRefusal, OperatorCommand, TickInput};
use crate::mission::phases::{AbortReason, Phase, Transition};
use crate::mission::supervision::{ManualLossResponse, Notice};

/// What manual control asks of this tick.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PilotStep {
    /// A command for the flight (the kill switch's disarm, the loss's action).
    pub flight: Option<FlightCommand>,
    /// The mode the mode switch moved to, in flight: taken as the operator's command.
    pub command: Option<OperatorCommand>,
    /// The rotors at zero this tick (the kill switch, armed state kept).
    pub rotors_off: bool,
    /// A transition on the ground (the kill switch's disarm while lifting or arming).
    pub transition: Option<Transition>,
    /// What to tell people.
    pub notice: Option<Notice>,
}

impl PilotMode {
    /// The operator's command that selects it.
    pub fn command(self) -> OperatorCommand {
        match self {
            Self::Mission => OperatorCommand::Resume,
            Self::Hold => OperatorCommand::Hold,
            Self::Land => OperatorCommand::LandNow,
            Self::Position => OperatorCommand::Position,
        }
    }
}

impl PilotMode {
    /// The mode an operator's command selects, if it selects one.
    pub fn from_command(command: OperatorCommand) -> Option<Self> {
        match command {
            OperatorCommand::Resume => Some(Self::Mission),
            OperatorCommand::Hold => Some(Self::Hold),
            OperatorCommand::LandNow => Some(Self::Land),
            OperatorCommand::Position => Some(Self::Position),
            _ => None,
        }
    }
}

impl Mission {
    /// Whether the vehicle is in Position mode (asked for; in the air, the sticks steer it
    /// once the take-off is over, or it holds for a lost manual control).
    pub fn position_mode(&self) -> bool {
        self.position
    }

    /// The manual control in force at the last tick.
    pub fn manual(&self) -> Manual {
        self.pilot.current()
    }

    /// Whether the kill switch is on.
    pub fn kill_switch(&self) -> bool {
        self.pilot.kill_on()
    }

    /// This tick's manual samples and what they ask.
    pub(super) fn pilot_step(&mut self, input: &TickInput, dt: f32) -> PilotStep {
        // No person has been heard and nothing came: nothing to do (the usual tick of a
        // vehicle without manual control costs the control step no more than this test).
        if input.manual.rc.is_none()
            && input.manual.joystick.is_none()
            && self.pilot.unheard()
            && self.manual_hold.is_none()
        {
            return PilotStep::default();
        }
        let tick = self
            .pilot
            .tick(&input.manual, input.time_us, &self.config.manual);
        let (failsafe_delay, loss_action) = (
            self.config.manual.failsafe_delay,
            self.config.manual.loss_action,
        );
        let flying = matches!(self.phase, Phase::Flying(_));
        let mut step = PilotStep::default();
        match tick.kill {
            KillAction::None => {}
            KillAction::RotorsOff => step.rotors_off = true,
            KillAction::Disarm => {
                step.rotors_off = true;
                match self.phase {
                    Phase::Flying(_) => step.flight = Some(FlightCommand::Kill),
                    Phase::Lifting | Phase::Arming => {
                        step.transition = Some(self.abort(AbortReason::Killed));
                    }
                    _ => {}
                }
            }
        }
        if let Some(on) = tick.kill_switched {
            step.notice = Some(Notice::KillSwitch { on });
        }
        if flying && let Some(mode) = tick.switched_to {
            step.command = Some(mode.command());
        }
        if tick.lost {
            let response = if self.position && flying && self.steerable() {
                self.leave_steering();
                self.manual_hold = Some(failsafe_delay);
                self.apply_hold();
                ManualLossResponse::Hold(failsafe_delay, loss_action)
            } else if flying {
                ManualLossResponse::MissionGoesOn
            } else {
                ManualLossResponse::Nothing
            };
            step.notice = step.notice.or(Some(Notice::ManualLost { response }));
        }
        if tick.regained {
            let resumed = self.manual_hold.take().is_some();
            self.apply_hold();
            step.notice = step.notice.or(Some(Notice::ManualRegained { resumed }));
        }
        if let Some(left) = self.manual_hold.as_mut() {
            *left -= dt;
            if *left <= 0.0 || !self.cruising() {
                let acting = self.cruising();
                self.manual_hold = None;
                self.apply_hold();
                if acting {
                    match loss_action {
                        ManualLossAction::Hold => {
                            self.position = false;
                            self.held = true;
                            self.apply_hold();
                        }
                        ManualLossAction::Land => {
                            self.position = false;
                            if self.abort.is_none() {
                                self.abort = Some(AbortReason::ManualLost);
                            }
                            step.flight = step.flight.or(Some(FlightCommand::LandNow));
                        }
                        ManualLossAction::Terminate => {
                            self.position = false;
                            step.flight = Some(FlightCommand::Kill);
                        }
                    }
                }
            }
        }
        step
    }

    /// Position mode's steering for this tick, before the flight's step: the sticks' velocity
    /// once the take-off is over; nothing while held for a lost manual control.
    pub(super) fn steer_flight(&mut self, nav: &NavState) {
        if !self.position || self.manual_hold.is_some() {
            return;
        }
        let Manual::Valid(_, input) = self.pilot.current() else {
            return;
        };
        let Some(flight) = self.flight.as_mut() else {
            return;
        };
        if flight.phase() == FlightPhase::Takeoff && !flight.steered() {
            return;
        }
        let yaw = nav.attitude.attitude.to_euler().z;
        let command = ManualVelocity::from_sticks(&input.sticks, yaw, &self.config.manual.limits);
        if !flight.steer(Some(command), nav) {
            // Landing on a stopped rotor or without position: the flight's to finish.
            self.position = false;
        }
    }

    /// Whether the flight can take the sticks now: flying, not landing for a stopped rotor or
    /// without position, nothing stopped.
    fn steerable(&self) -> bool {
        self.flight.as_ref().is_some_and(|f| {
            f.stopped().is_none()
                && !matches!(
                    f.landing_cause(),
                    Some(
                        crate::flight::LandingCause::PositionLost
                            | crate::flight::LandingCause::RotorOut { .. }
                    )
                )
        })
    }

    /// The sticks let go: the flight's plan goes on from where the vehicle is.
    pub(super) fn leave_steering(&mut self) {
        if let Some(flight) = self.flight.as_mut() {
            let nav = self.navigator.state();
            flight.steer(None, &nav);
        }
    }

    /// Position mode asked for (the ground station or the mode switch): in flight, the sticks
    /// take over (refused without valid manual control, or landing on a stopped rotor or
    /// without position); the hold, a lost link's hold and a landing in place the pilot takes
    /// over end.
    pub(super) fn enter_position(&mut self) -> Result<(), CommandRefusal> {
        if !matches!(self.pilot.current(), Manual::Valid(..)) {
            return Err(CommandRefusal::NoManualControl { rc: false });
        }
        if !self.steerable() {
            return Err(CommandRefusal::Landing);
        }
        self.position = true;
        self.held = false;
        self.gcs_hold = None;
        self.manual_hold = None;
        self.abort = None;
        self.apply_hold();
        Ok(())
    }
}
