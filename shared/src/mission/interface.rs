//! What goes into and comes out of one step of the mission ([`crate::mission::Mission::step`],
//! docs/system.md#mission-phases): the operator's commands and their replies, the hardware's
//! faults, the tick's input and output, and an IMU failure the mission acted on.

use crate::control::imu_monitor::ImuFailure;
use crate::control::navigator::{ImuSample, MocapFix, NavState};
use crate::flight::{AdaptEvent, CascadeSetpoints};
use crate::manual::ManualSamples;
use crate::mission::bringup::{CalibrationFailure, CalibrationKind, MotorTestRequest};
use crate::mission::jobs::JobRequest;
use crate::mission::phases::{AbortReason, Phase, Transition};
use crate::mission::supervision::{Notice, Supervision};
use crate::rail::moves::Positions;
use crate::scenario::MAX_ROBOTS;

/// A command from the operator (the ground station).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OperatorCommand {
    /// Start the mission (from idle).
    Start,
    /// Stop it: on the ground the rotors stop; in flight the vehicle lands where it is.
    Abort,
    /// In flight: land where the vehicle is.
    LandNow,
    /// Stop the rotors now, wherever the vehicle is (flight termination).
    Kill,
    /// In flight: hold where the vehicle is until [`Self::Resume`].
    Hold,
    /// Mission mode: before the start, start; held in flight, fly on; otherwise nothing to do.
    Resume,
    /// Position mode (docs/manual-control.md#position-mode): in the air, the sticks steer the
    /// payload; before the start, the start (with its checks), the sticks taking over after
    /// the take-off.
    Position,
    /// The robots stand at the payload description's `initial` positions (placed at their
    /// marks): the rail positions are known from now on (docs/ground-link.md#bring-up-commands).
    ConfirmRails,
    /// Move one robot along the rail, on the ground, rotors off.
    Jog {
        /// The robot, from 1.
        robot: u8,
        /// How far, um (positive: increasing arc length).
        micrometres: i32,
    },
    /// An IMU calibration at rest.
    Calibrate(CalibrationKind),
    /// Spin some rotors at an ESC command for a while (rotors off the payload: props off).
    MotorTest(MotorTestRequest),
}

impl OperatorCommand {
    /// The command's name for people: `start`, `abort`, `land now`, `kill`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Start => "start",
            Self::Abort => "abort",
            Self::LandNow => "land now",
            Self::Kill => "kill",
            Self::Hold => "hold",
            Self::Resume => "mission",
            Self::Position => "position",
            Self::ConfirmRails => "confirm rails",
            Self::Jog { .. } => "jog",
            Self::Calibrate(_) => "calibrate",
            Self::MotorTest(_) => "motor test",
        }
    }

    /// Whether it is a bring-up command (docs/ground-link.md#bring-up-commands): only on the
    /// ground with the rotors off, and never while the mission runs.
    pub fn is_bench(self) -> bool {
        matches!(
            self,
            Self::ConfirmRails | Self::Jog { .. } | Self::Calibrate(_) | Self::MotorTest(_)
        )
    }
}

/// Why a command was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandRefusal {
    /// The mission has already started.
    AlreadyStarted,
    /// The mission is over (landed or aborted).
    Finished,
    /// Landing asked for while not flying.
    NotFlying,
    /// No payload description has been loaded.
    NoPayload,
    /// No ground link: no ground station's heartbeat within `FS_GCS_LOSS_T`.
    NoGroundLink,
    /// The route has no such item (or, before the start, the flight cannot begin there).
    NoRouteItem,
    /// The vehicle is landing: nothing else is flown.
    Landing,
    /// The battery is below its low threshold (`BAT_LOW_V`).
    BatteryLow {
        /// The filtered pack voltage, mV.
        millivolts: u32,
    },
    /// A bring-up command while the mission runs (the vehicle may be armed).
    MissionRunning,
    /// The rail positions have not been confirmed since power-up or a stall.
    RailsUnconfirmed,
    /// A robot does not stand at its start position (it was jogged away).
    RobotOffMark {
        /// The robot, from 1.
        robot: u8,
        /// How far from its mark, mm (positive: ahead along the rail).
        millimetres: i32,
    },
    /// No robot of that number.
    NoSuchRobot {
        /// The number asked for.
        robot: u8,
        /// Robots the payload description has.
        robots: u8,
    },
    /// The jog would bring the robot closer than `min_spacing` to a neighbour.
    JogTooFar {
        /// The robot, from 1.
        robot: u8,
    },
    /// Motor tests are switched off (`COM_MOT_TEST_EN` = 0).
    MotorTestDisabled,
    /// A calibration, motor test or jog is under way.
    BenchBusy,
    /// The kill switch is on.
    KillSwitchOn,
    /// No valid manual control: `COM_RC_IN_MODE` requires an RC receiver (`rc`), or Position
    /// mode needs sticks.
    NoManualControl {
        /// An RC receiver's frames are what is missing.
        rc: bool,
    },
}

impl core::fmt::Display for CommandRefusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::AlreadyStarted => write!(f, "the mission has already started"),
            Self::Finished => write!(f, "the mission is over"),
            Self::NotFlying => write!(f, "not flying"),
            Self::NoRouteItem => write!(f, "the mission has no such item to fly from"),
            Self::Landing => write!(f, "the vehicle is landing"),
            Self::NoPayload => write!(f, "no payload description is loaded"),
            Self::NoGroundLink => write!(
                f,
                "no ground link: no ground-station heartbeat (no take-off without one)"
            ),
            Self::BatteryLow { millivolts } => write!(
                f,
                "battery low: {} V, below BAT_LOW_V",
                crate::numbers::Fixed(
                    crate::mission::supervision::hundredths_down(*millivolts as f32 * 1e-3),
                    2
                )
            ),
            Self::MissionRunning => write!(f, "the mission is running (the vehicle may be armed)"),
            Self::RailsUnconfirmed => write!(
                f,
                "rail: the robots' positions are not confirmed; place them at their marks and confirm (command 31010)"
            ),
            Self::RobotOffMark { robot, millimetres } => write!(
                f,
                "rail: robot {robot} stands {millimetres} mm from its start position; jog it back"
            ),
            Self::NoSuchRobot { robot, robots } => {
                write!(f, "no robot {robot}: the payload description has {robots}")
            }
            Self::JogTooFar { robot } => write!(
                f,
                "rail: robot {robot} would come closer than min_spacing to a neighbour"
            ),
            Self::MotorTestDisabled => write!(f, "motor tests are off (COM_MOT_TEST_EN = 0)"),
            Self::BenchBusy => write!(f, "a calibration, motor test or jog is under way"),
            Self::KillSwitchOn => write!(f, "the kill switch is on"),
            Self::NoManualControl { rc: true } => write!(
                f,
                "no RC receiver: COM_RC_IN_MODE requires one and no valid frame came in COM_RC_LOSS_T"
            ),
            Self::NoManualControl { rc: false } => {
                write!(
                    f,
                    "no manual control: Position mode needs an RC receiver or a joystick"
                )
            }
        }
    }
}

/// The answer to an operator command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CommandReply {
    /// The command.
    pub command: OperatorCommand,
    /// Accepted, or why not.
    pub outcome: Result<(), CommandRefusal>,
}

/// Failures the flight controller's drivers report: what the mission must not
/// ignore. On the ground either stops the mission; in flight it lands where it is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HardwareFaults {
    /// The IMU is stalled, saturated or implausible (its samples are not to be trusted).
    pub imu: bool,
    /// Robots whose steppers stalled, bit `j` for robot `j` (up to sixteen).
    pub stalled_robots: u16,
    /// Robots whose ESC reports its rotor stopped while commanded to turn, bit `j` for robot
    /// `j` (no board reads ESC telemetry yet: 0). Heeded in flight only, where the flight
    /// flies on without the rotor and lands ([`AbortReason::RotorOut`]); not part of
    /// [`Self::reason`].
    pub rotors_out: u16,
}

impl HardwareFaults {
    /// None.
    pub const NONE: Self = Self {
        imu: false,
        stalled_robots: 0,
        rotors_out: 0,
    };

    /// The abort reason of the first fault that concerns a mission with `robots` robots.
    pub fn reason(&self, robots: usize) -> Option<AbortReason> {
        if self.imu {
            return Some(AbortReason::ImuFault);
        }
        let mask = if robots >= 16 {
            u16::MAX
        } else {
            (1u16 << robots) - 1
        };
        let stalled = self.stalled_robots & mask;
        (stalled != 0).then(|| AbortReason::RobotStalled {
            robot: stalled.trailing_zeros() as u8,
        })
    }
}

/// What one tick takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickInput {
    /// When the IMU sample was taken, us (the flight controller's clock; in lockstep
    /// hardware-in-the-loop, the simulator's).
    pub time_us: u64,
    /// The IMU sample.
    pub imu: ImuSample,
    /// A motion-capture fix that arrived since the previous tick.
    pub mocap: Option<MocapFix>,
    /// An operator command that arrived since the previous tick.
    pub command: Option<OperatorCommand>,
    /// What the drivers report failed ([`HardwareFaults::NONE`] in simulation).
    pub faults: HardwareFaults,
    /// Each rotor's RPM from its ESC's telemetry ([`EscRpm`]), or `None` without ESC
    /// telemetry: the rotor monitor then judges from the vehicle's response alone.
    pub esc_rpm: Option<EscRpm>,
    /// The ground station's heartbeat and the battery's voltage.
    pub supervision: Supervision,
    /// Manual control's samples since the previous tick ([`ManualSamples::NONE`] without).
    pub manual: ManualSamples,
}

/// Each rotor's RPM from its ESC's telemetry, robot by robot; NaN for a rotor without a
/// fresh, valid reading this tick.
pub type EscRpm = [f32; MAX_ROBOTS];

/// What one tick commands.
#[derive(Clone, Debug, PartialEq)]
pub struct TickOutput {
    /// Thrust of each robot's rotor, N (commanded units); zero unless `armed`.
    pub thrusts: [f32; MAX_ROBOTS],
    /// Where each robot should be on the rail now (arc lengths).
    pub robots: Positions,
    /// Whether the rotors may spin.
    pub armed: bool,
    /// A motor test spun the rotors this tick (armed on the ground, the mission not
    /// running; the tick that ends the test included).
    pub motor_test: bool,
    /// The phase after this tick.
    pub phase: Phase,
    /// The transition this tick made, if any.
    pub transition: Option<Transition>,
    /// What the in-flight adaptation did this tick, if anything.
    pub adaptation: Option<AdaptEvent>,
    /// A computation to run off the tick, if this tick asked for one.
    pub job: Option<JobRequest>,
    /// The answer to this tick's operator command, if one came.
    pub reply: Option<CommandReply>,
    /// What the ground link's and the battery's supervision has to tell people this tick.
    pub notice: Option<Notice>,
    /// A calibration that ended this tick: its kind and the offsets found (already in
    /// force) or why it failed.
    pub calibrated: Option<(CalibrationKind, Result<[f32; 3], CalibrationFailure>)>,
    /// The state estimate after this tick.
    pub nav: NavState,
    /// What the flight's cascade asked of the vehicle this tick: while flying with the rotors
    /// turning, `None` otherwise.
    pub cascade: Option<CascadeSetpoints>,
    /// The kill switch holds the rotors at zero this tick (the vehicle may still be armed).
    pub killed: bool,
}

/// An IMU failure the monitor found and the mission acted on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImuDetection {
    /// What was wrong.
    pub failure: ImuFailure,
    /// The tick's time when it was found, us (the clock of [`TickInput::time_us`]).
    pub time_us: u64,
}
