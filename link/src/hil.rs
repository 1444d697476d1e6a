//! Hardware in the loop as PX4's simulator MAVLink API has it (PX4 `simulator_mavlink`), in
//! lockstep.
//!
//! Plant to vehicle:
//! - `HIL_SENSOR` (sensor id 0) at the IMU rate: body-frame (FRD) specific force in m/s^2
//!   (`z = -9.81` at rest), body rates in rad/s, `time_usec` the simulated time in
//!   microseconds, `fields_updated` with the accelerometer and gyro bits;
//! - `ATT_POS_MOCAP` at the motion-capture rate: position in the world frame (NED, m), attitude
//!   quaternion (w, x, y, z; body FRD to NED), `time_usec` when the fix was taken (it arrives
//!   later, by the motion capture's latency).
//!
//! Vehicle to plant, once per `HIL_SENSOR`, stamped with that sensor's `time_usec`: one
//! `HIL_ACTUATOR_CONTROLS` with `mode` carrying `MAV_MODE_FLAG_SAFETY_ARMED` when armed (and
//! `MAV_MODE_FLAG_HIL_ENABLED` always) and `flags` = lockstep. Its channel map:
//!
//! | channels | robots up to 8 |
//! |---|---|
//! | `controls[0..8]` | robot `j`'s rotor thrust command as a fraction of its maximum, `[0, 1]` |
//! | `controls[8..16]` | robot `j`'s commanded position along the rail, arc length in metres |
//!
//! With more than 8 robots (up to [`MAX_ROBOTS`]) the same `HIL_ACTUATOR_CONTROLS` carries
//! robots 0..8, and an `ACTUATOR_OUTPUT_STATUS` with the same `time_usec`, sent just before it,
//! carries all of them: `actuator[j]` the thrust fraction of robot `j` and `actuator[16 + j]`
//! its rail position (m), `active` with the bits of the channels in use. Unused channels are 0.
//!
//! Lockstep (as PX4 SITL): the vehicle's clock is the last `HIL_SENSOR`'s `time_usec`, and its
//! control step runs when that message arrives ([`VehicleClock`]); the plant advances its
//! physics only once the matching `HIL_ACTUATOR_CONTROLS` is back ([`ReplyMatcher`]), with a
//! timeout of its own. The run is then the same whatever the speed of the emulator or the link.

use crate::msg::{
    ACTUATOR_OUTPUT_STATUS_DATA, ATT_POS_MOCAP_DATA, HIL_ACTUATOR_CONTROLS_DATA, HIL_SENSOR_DATA,
    HilActuatorControlsFlags, HilSensorUpdatedFlags, MavModeFlag,
};

/// Most robots the link carries: every robot the software takes.
pub use shared::scenario::MAX_ROBOTS;
/// Robots that fit `HIL_ACTUATOR_CONTROLS` alone.
pub const ROBOTS_IN_CONTROLS: usize = 8;

/// What is wrong with a received HIL message.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HilError {
    /// `HIL_SENSOR` without both the accelerometer and the gyro marked updated.
    SensorFieldsMissing {
        /// Its `fields_updated`.
        fields_updated: u32,
    },
    /// A value is NaN or infinite.
    NotFinite {
        /// The message.
        message: &'static str,
    },
    /// `HIL_SENSOR` from another sensor than IMU 0.
    OtherSensor {
        /// Its `id`.
        id: u8,
    },
    /// More than 8 robots and no `ACTUATOR_OUTPUT_STATUS` for this step.
    MissingOutputStatus,
    /// More robots than the link carries.
    TooManyRobots {
        /// Robots asked for.
        robots: usize,
    },
}

impl core::fmt::Display for HilError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::SensorFieldsMissing { fields_updated } => write!(
                f,
                "HIL_SENSOR fields_updated {fields_updated:#x} lacks the accelerometer and gyro bits"
            ),
            Self::NotFinite { message } => write!(f, "{message} carries a NaN or infinite value"),
            Self::OtherSensor { id } => {
                write!(f, "HIL_SENSOR from sensor {id}, only IMU 0 is used")
            }
            Self::MissingOutputStatus => write!(
                f,
                "more than 8 robots but no ACTUATOR_OUTPUT_STATUS came with HIL_ACTUATOR_CONTROLS"
            ),
            Self::TooManyRobots { robots } => {
                write!(
                    f,
                    "{robots} robots, the HIL link carries at most {MAX_ROBOTS}"
                )
            }
        }
    }
}

pub use shared::control::navigator::{ImuSample, MocapFix};
use shared::control::vector::{Quat, Vec3};

/// One IMU sample from the plant (`HIL_SENSOR`): the sample and the plant's time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantSample {
    /// Simulated time, us.
    pub time_us: u64,
    /// The sample (body FRD).
    pub imu: ImuSample,
}

fn accel_gyro_bits() -> HilSensorUpdatedFlags {
    HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_XACC
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_YACC
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ZACC
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_XGYRO
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_YGYRO
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ZGYRO
}

impl PlantSample {
    /// A level vehicle at rest at time 0: no rotation, gravity's specific force.
    pub const AT_REST: Self = Self {
        time_us: 0,
        imu: ImuSample {
            gyro: Vec3::ZERO,
            accel: Vec3::new(0.0, 0.0, -9.81),
        },
    };

    /// As `HIL_SENSOR` (IMU 0, accelerometer and gyro updated).
    pub fn to_message(&self) -> HIL_SENSOR_DATA {
        let (g, a) = (self.imu.gyro, self.imu.accel);
        HIL_SENSOR_DATA {
            time_usec: self.time_us,
            xacc: a.x,
            yacc: a.y,
            zacc: a.z,
            xgyro: g.x,
            ygyro: g.y,
            zgyro: g.z,
            fields_updated: accel_gyro_bits(),
            // The extension field `id` (IMU 0) is zero, which MAVLink 2 leaves out anyway.
            ..Default::default()
        }
    }

    /// From `HIL_SENSOR`, checked; `sensor_id` is its extension field `id` (0 when absent).
    pub fn from_message(m: &HIL_SENSOR_DATA, sensor_id: u8) -> Result<Self, HilError> {
        if sensor_id != 0 {
            return Err(HilError::OtherSensor { id: sensor_id });
        }
        if !m.fields_updated.contains(accel_gyro_bits()) {
            return Err(HilError::SensorFieldsMissing {
                fields_updated: m.fields_updated.bits(),
            });
        }
        let accel = [m.xacc, m.yacc, m.zacc];
        let gyro = [m.xgyro, m.ygyro, m.zgyro];
        if accel.iter().chain(&gyro).any(|v| !v.is_finite()) {
            return Err(HilError::NotFinite {
                message: "HIL_SENSOR",
            });
        }
        Ok(Self {
            time_us: m.time_usec,
            imu: ImuSample {
                gyro: Vec3::new(gyro[0], gyro[1], gyro[2]),
                accel: Vec3::new(accel[0], accel[1], accel[2]),
            },
        })
    }
}

/// `fix` as `ATT_POS_MOCAP`.
pub fn mocap_message(fix: &MocapFix) -> ATT_POS_MOCAP_DATA {
    let (p, q) = (fix.position, fix.attitude);
    ATT_POS_MOCAP_DATA {
        time_usec: fix.stamp_us,
        q: [q.w, q.x, q.y, q.z],
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// A fix from position `position` (NED, m), attitude `q` (w, x, y, z, body FRD to NED) and
/// time `stamp_us`, checked (every number finite); `message` names the message for the error.
pub fn mocap_fix_of(
    position: [f32; 3],
    q: [f32; 4],
    stamp_us: u64,
    message: &'static str,
) -> Result<MocapFix, HilError> {
    if position.iter().chain(&q).any(|v| !v.is_finite()) {
        return Err(HilError::NotFinite { message });
    }
    Ok(MocapFix {
        position: Vec3::new(position[0], position[1], position[2]),
        attitude: Quat {
            w: q[0],
            x: q[1],
            y: q[2],
            z: q[3],
        },
        stamp_us,
    })
}

/// A fix from `ATT_POS_MOCAP`, checked.
pub fn mocap_from_message(m: &ATT_POS_MOCAP_DATA) -> Result<MocapFix, HilError> {
    mocap_fix_of([m.x, m.y, m.z], m.q, m.time_usec, "ATT_POS_MOCAP")
}

/// The vehicle's actuator commands of one control step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Actuators {
    /// The `time_usec` of the `HIL_SENSOR` this step answers, us.
    pub time_us: u64,
    /// Robots in use.
    pub robots: usize,
    /// Rotor thrust command of each robot, fraction of its maximum, `[0, 1]`.
    pub thrust: [f32; MAX_ROBOTS],
    /// Commanded position of each robot along the rail, arc length, m.
    pub rail: [f32; MAX_ROBOTS],
    /// Armed: the rotors may turn.
    pub armed: bool,
}

/// The messages one [`Actuators`] goes out as.
#[derive(Clone, Debug, PartialEq)]
pub struct ActuatorMessages {
    /// Sent first when more than 8 robots: all robots' channels.
    pub status: Option<ACTUATOR_OUTPUT_STATUS_DATA>,
    /// The lockstep reply.
    pub controls: HIL_ACTUATOR_CONTROLS_DATA,
}

impl Actuators {
    /// The messages, per the channel map above (robots beyond [`MAX_ROBOTS`] are cut).
    pub fn to_messages(&self) -> ActuatorMessages {
        let n = self.robots.min(MAX_ROBOTS);
        let mut controls = [0.0; 16];
        let k = n.min(ROBOTS_IN_CONTROLS);
        controls[..k].copy_from_slice(&self.thrust[..k]);
        controls[ROBOTS_IN_CONTROLS..ROBOTS_IN_CONTROLS + k].copy_from_slice(&self.rail[..k]);
        let mut mode = MavModeFlag::MAV_MODE_FLAG_HIL_ENABLED;
        if self.armed {
            mode |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        let status = (n > ROBOTS_IN_CONTROLS).then(|| {
            let mut actuator = [0.0; 32];
            let mut active = 0u32;
            for j in 0..n {
                actuator[j] = self.thrust[j];
                actuator[MAX_ROBOTS + j] = self.rail[j];
                active |= (1 << j) | (1 << (MAX_ROBOTS + j));
            }
            ACTUATOR_OUTPUT_STATUS_DATA {
                time_usec: self.time_us,
                active,
                actuator,
            }
        });
        ActuatorMessages {
            status,
            controls: HIL_ACTUATOR_CONTROLS_DATA {
                time_usec: self.time_us,
                flags: HilActuatorControlsFlags::HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP,
                controls,
                mode,
            },
        }
    }

    /// Reads the commands of `robots` robots back (the plant's side); `status` is the
    /// `ACTUATOR_OUTPUT_STATUS` received with the same `time_usec`, if any.
    pub fn from_messages(
        controls: &HIL_ACTUATOR_CONTROLS_DATA,
        status: Option<&ACTUATOR_OUTPUT_STATUS_DATA>,
        robots: usize,
    ) -> Result<Self, HilError> {
        if robots > MAX_ROBOTS {
            return Err(HilError::TooManyRobots { robots });
        }
        let mut out = Self {
            time_us: controls.time_usec,
            robots,
            armed: controls
                .mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
            ..Default::default()
        };
        if robots <= ROBOTS_IN_CONTROLS {
            for j in 0..robots {
                out.thrust[j] = controls.controls[j];
                out.rail[j] = controls.controls[ROBOTS_IN_CONTROLS + j];
            }
        } else {
            let status = status
                .filter(|s| s.time_usec == controls.time_usec)
                .ok_or(HilError::MissingOutputStatus)?;
            for j in 0..robots {
                out.thrust[j] = status.actuator[j];
                out.rail[j] = status.actuator[MAX_ROBOTS + j];
            }
        }
        let used = out.thrust[..robots].iter().chain(&out.rail[..robots]);
        if used.clone().any(|v| !v.is_finite()) {
            return Err(HilError::NotFinite {
                message: "HIL_ACTUATOR_CONTROLS",
            });
        }
        Ok(out)
    }
}

/// The vehicle's side of lockstep: its clock is the last `HIL_SENSOR`'s time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VehicleClock {
    last_us: Option<u64>,
    ticks: u64,
}

/// A control step the vehicle takes on a `HIL_SENSOR`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    /// Steps taken before this one.
    pub index: u64,
    /// The vehicle's time, us.
    pub time_us: u64,
    /// Time since the previous step, us (0 for the first).
    pub dt_us: u64,
}

/// Why a `HIL_SENSOR` cannot be a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClockError {
    /// Its time is not after the previous one's.
    NotIncreasing {
        /// The previous time, us.
        previous_us: u64,
        /// This one's, us.
        time_us: u64,
    },
}

impl core::fmt::Display for ClockError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::NotIncreasing {
                previous_us,
                time_us,
            } => write!(
                f,
                "HIL_SENSOR time {time_us} us is not after the previous {previous_us} us"
            ),
        }
    }
}

impl VehicleClock {
    /// A clock that has seen no sensor yet.
    pub const fn new() -> Self {
        Self {
            last_us: None,
            ticks: 0,
        }
    }

    /// Whether a `HIL_SENSOR` has arrived: the vehicle is in HIL.
    pub fn in_hil(&self) -> bool {
        self.last_us.is_some()
    }

    /// The vehicle's time, us (0 before the first sensor).
    pub fn now_us(&self) -> u64 {
        self.last_us.unwrap_or(0)
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.ticks
    }

    /// A `HIL_SENSOR` stamped `time_us` arrived: the step it starts.
    pub fn on_sensor(&mut self, time_us: u64) -> Result<Step, ClockError> {
        let dt_us = match self.last_us {
            Some(previous_us) if time_us <= previous_us => {
                return Err(ClockError::NotIncreasing {
                    previous_us,
                    time_us,
                });
            }
            Some(previous_us) => time_us - previous_us,
            None => 0,
        };
        self.last_us = Some(time_us);
        let step = Step {
            index: self.ticks,
            time_us,
            dt_us,
        };
        self.ticks += 1;
        Ok(step)
    }
}

/// When a job's result is due: a fixed number of control steps after the
/// step that asked for it, whatever the speed of the processor or the emulator. At that step
/// the vehicle takes the result, and in lockstep holds its reply until the job is done, as
/// PX4's lockstep waits for its modules.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JobDeadline {
    due: Option<u64>,
}

/// A job was asked for while another one is still running.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JobBusy {
    /// Step at which the running job's result is due.
    pub due: u64,
}

impl JobDeadline {
    /// No job running.
    pub const fn new() -> Self {
        Self { due: None }
    }

    /// A job asked for at step `step`, its result due `deadline_steps` later (at least 1):
    /// returns the step at which it is due.
    pub fn request(&mut self, step: u64, deadline_steps: u32) -> Result<u64, JobBusy> {
        if let Some(due) = self.due {
            return Err(JobBusy { due });
        }
        let due = step + u64::from(deadline_steps.max(1));
        self.due = Some(due);
        Ok(due)
    }

    /// Whether step `step` must take the result (it is due now, or overdue).
    pub fn is_due(&self, step: u64) -> bool {
        self.due.is_some_and(|due| step >= due)
    }

    /// Whether a job is running.
    pub fn pending(&self) -> bool {
        self.due.is_some()
    }

    /// The result was taken.
    pub fn taken(&mut self) {
        self.due = None;
    }
}

/// The plant's side of lockstep: which reply it waits for, and the extra status of steps with
/// more than 8 robots.
#[derive(Clone, Debug, Default)]
pub struct ReplyMatcher {
    awaiting: Option<u64>,
    status: Option<ACTUATOR_OUTPUT_STATUS_DATA>,
}

/// What the plant does with a message while it waits.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// Not the reply (a stale one, or an `ACTUATOR_OUTPUT_STATUS` kept for it).
    NotYet,
    /// The step's commands: the plant may advance.
    Commands(Actuators),
}

impl ReplyMatcher {
    /// A matcher waiting for nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// The sensor stamped `time_us` went out: its reply is awaited.
    pub fn sent(&mut self, time_us: u64) {
        self.awaiting = Some(time_us);
        self.status = None;
    }

    /// The time of the step whose reply is awaited.
    pub fn awaiting(&self) -> Option<u64> {
        self.awaiting
    }

    /// An `ACTUATOR_OUTPUT_STATUS` arrived.
    pub fn on_status(&mut self, status: &ACTUATOR_OUTPUT_STATUS_DATA) {
        if Some(status.time_usec) == self.awaiting {
            self.status = Some(status.clone());
        }
    }

    /// A `HIL_ACTUATOR_CONTROLS` arrived; `robots` are in use.
    pub fn on_controls(
        &mut self,
        controls: &HIL_ACTUATOR_CONTROLS_DATA,
        robots: usize,
    ) -> Result<Reply, HilError> {
        if Some(controls.time_usec) != self.awaiting {
            return Ok(Reply::NotYet);
        }
        let commands = Actuators::from_messages(controls, self.status.as_ref(), robots)?;
        self.awaiting = None;
        self.status = None;
        Ok(Reply::Commands(commands))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn commands(robots: usize) -> Actuators {
        let mut a = Actuators {
            time_us: 2500,
            robots,
            armed: true,
            ..Default::default()
        };
        for j in 0..robots {
            a.thrust[j] = 0.05 * j as f32;
            a.rail[j] = 0.3 * j as f32 + 0.1;
        }
        a
    }

    #[test]
    fn eight_robots_fit_hil_actuator_controls_alone() {
        let a = commands(8);
        let m = a.to_messages();
        assert!(m.status.is_none());
        assert_eq!(m.controls.controls[3], a.thrust[3]);
        assert_eq!(m.controls.controls[8 + 3], a.rail[3]);
        assert!(
            m.controls
                .mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
        );
        assert_eq!(
            m.controls.flags,
            HilActuatorControlsFlags::HIL_ACTUATOR_CONTROLS_FLAGS_LOCKSTEP
        );
        assert_eq!(Actuators::from_messages(&m.controls, None, 8), Ok(a));
    }

    #[test]
    fn more_than_eight_robots_need_the_output_status() {
        let a = commands(12);
        let m = a.to_messages();
        let status = m.status.clone().expect("12 robots send the status");
        assert_eq!(status.actuator[11], a.thrust[11]);
        assert_eq!(status.actuator[16 + 11], a.rail[11]);
        assert_eq!(status.active & (1 << 11), 1 << 11);
        assert_eq!(status.active & (1 << 12), 0);
        assert_eq!(
            Actuators::from_messages(&m.controls, Some(&status), 12),
            Ok(a)
        );
        assert_eq!(
            Actuators::from_messages(&m.controls, None, 12),
            Err(HilError::MissingOutputStatus)
        );
    }

    #[test]
    fn disarmed_clears_the_armed_bit() {
        let mut a = commands(4);
        a.armed = false;
        let m = a.to_messages();
        assert!(
            !m.controls
                .mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
        );
        assert!(
            !Actuators::from_messages(&m.controls, None, 4)
                .unwrap()
                .armed
        );
    }

    #[test]
    fn sensor_messages_round_trip_and_bad_ones_are_named() {
        let s = PlantSample {
            time_us: 42,
            imu: ImuSample {
                gyro: Vec3::new(0.1, -0.2, 0.3),
                accel: Vec3::new(0.0, 0.0, -9.81),
            },
        };
        assert_eq!(PlantSample::from_message(&s.to_message(), 0), Ok(s));
        let mut m = s.to_message();
        m.fields_updated = HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_XACC;
        assert!(matches!(
            PlantSample::from_message(&m, 0),
            Err(HilError::SensorFieldsMissing { .. })
        ));
        let mut m = s.to_message();
        m.zgyro = f32::NAN;
        assert!(matches!(
            PlantSample::from_message(&m, 0),
            Err(HilError::NotFinite { .. })
        ));
        assert_eq!(
            PlantSample::from_message(&s.to_message(), 1),
            Err(HilError::OtherSensor { id: 1 })
        );
        let fix = MocapFix {
            stamp_us: 10_000,
            position: Vec3::new(1.0, 2.0, -0.5),
            attitude: Quat::IDENTITY,
        };
        assert_eq!(mocap_from_message(&mocap_message(&fix)), Ok(fix));
        let mut bad = mocap_message(&fix);
        bad.q[2] = f32::NAN;
        assert!(matches!(
            mocap_from_message(&bad),
            Err(HilError::NotFinite {
                message: "ATT_POS_MOCAP"
            })
        ));
    }

    #[test]
    fn the_vehicle_clock_follows_the_sensor_and_refuses_going_back() {
        let mut c = VehicleClock::new();
        assert!(!c.in_hil());
        assert_eq!(c.on_sensor(1000).unwrap().dt_us, 0);
        let s = c.on_sensor(3500).unwrap();
        assert_eq!((s.index, s.dt_us, c.now_us()), (1, 2500, 3500));
        assert_eq!(
            c.on_sensor(3500),
            Err(ClockError::NotIncreasing {
                previous_us: 3500,
                time_us: 3500
            })
        );
        assert_eq!(c.steps(), 2);
    }

    #[test]
    fn a_job_result_is_due_a_fixed_number_of_steps_after_its_request() {
        let mut d = JobDeadline::new();
        assert!(!d.is_due(0));
        assert_eq!(d.request(10, 40), Ok(50));
        assert_eq!(d.request(11, 40), Err(JobBusy { due: 50 }));
        assert!(!d.is_due(49));
        assert!(d.is_due(50));
        d.taken();
        assert!(!d.pending());
        assert_eq!(
            d.request(60, 0),
            Ok(61),
            "a result is never due in its own step"
        );
    }

    #[test]
    fn the_plant_takes_only_the_reply_to_its_last_sensor() {
        let mut r = ReplyMatcher::new();
        r.sent(5000);
        let mut stale = commands(8);
        stale.time_us = 2500;
        let m = stale.to_messages();
        assert_eq!(r.on_controls(&m.controls, 8), Ok(Reply::NotYet));
        let mut now = commands(10);
        now.time_us = 5000;
        let m = now.to_messages();
        r.on_status(m.status.as_ref().unwrap());
        assert_eq!(r.on_controls(&m.controls, 10), Ok(Reply::Commands(now)));
        assert_eq!(r.awaiting(), None);
    }
}
