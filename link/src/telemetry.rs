//! Telemetry at set rates: `SYS_STATUS`, `ATTITUDE_QUATERNION`,
//! `LOCAL_POSITION_NED`, each robot's rail position (`DEBUG_FLOAT_ARRAY` named `rail`: the
//! formation once the robots have moved to it; not a number until the positions are
//! confirmed), `GLOBAL_POSITION_INT` (through the map origin,
//! docs/ground-link.md#the-map-origin) and the ESC outputs (`ACTUATOR_OUTPUT_STATUS`, and
//! `SERVO_OUTPUT_RAW` for MAVProxy: docs/ground-link.md#bring-up-commands), the ESCs' own
//! telemetry (`ESC_STATUS`, `ESC_INFO`: [`crate::esc`]), each on its own interval that a ground station
//! sets with `MAV_CMD_SET_MESSAGE_INTERVAL` (or asks for once with `MAV_CMD_REQUEST_MESSAGE`),
//! as MAVLink's message interval protocol has it; the messages built from a
//! [`VehicleSnapshot`], the vehicle's state after its last control step; and the take-off
//! point ([`Home`], `HOME_POSITION`) and the origin (`GPS_GLOBAL_ORIGIN`) on request.
//!
//! The schedule is plain logic over the vehicle's microsecond clock: the firmware's send task
//! asks [`Schedule::next_due`] when to wake and [`Schedule::take_due`] what to send.

use crate::MessageData;
use crate::geo::GeoOrigin;
use crate::hil::MAX_ROBOTS;
use crate::msg::{
    ACTUATOR_OUTPUT_STATUS_DATA, ATTITUDE_QUATERNION_DATA, DEBUG_FLOAT_ARRAY_DATA, ESC_INFO_DATA,
    ESC_STATUS_DATA, EXTENDED_SYS_STATE_DATA, GLOBAL_POSITION_INT_DATA, GPS_GLOBAL_ORIGIN_DATA,
    HOME_POSITION_DATA, LOCAL_POSITION_NED_DATA, MavLandedState, MavResult, MavSysStatusSensor,
    MavVtolState, SERVO_OUTPUT_RAW_DATA, SYS_STATUS_DATA,
};
use shared::control::thrust_map::ThrustMap;
use shared::scenario::{MAX_TARGET_DISTANCE, MAX_TARGET_HEIGHT};

/// A message the vehicle streams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// `SYS_STATUS`: sensors present, enabled and healthy; the control loop's load.
    SysStatus = 0,
    /// `ATTITUDE_QUATERNION`: attitude and body rates.
    AttitudeQuaternion = 1,
    /// `LOCAL_POSITION_NED`: position and velocity from the take-off point.
    LocalPositionNed = 2,
    /// `DEBUG_FLOAT_ARRAY` `rail` ([`RAIL_ARRAY_ID`]): each robot's commanded arc length.
    RailPositions = 3,
    /// `GLOBAL_POSITION_INT`: the local position through the map origin.
    GlobalPositionInt = 4,
    /// `SERVO_OUTPUT_RAW`: the first eight ESC outputs as pulses (MAVProxy's view).
    ServoOutputRaw = 5,
    /// `ACTUATOR_OUTPUT_STATUS`: every ESC output, fractions of full command.
    ActuatorOutputStatus = 6,
    /// `ESC_STATUS`: each rotor's RPM from its ESC ([`crate::esc`]; sent only while ESCs
    /// report).
    EscStatus = 7,
    /// `ESC_INFO`: which ESCs answer, the rotors flown without ([`crate::esc`]; sent only
    /// while ESCs report).
    EscInfo = 8,
}

/// How many streams there are.
pub const STREAMS: usize = 9;
/// Outputs in one `SERVO_OUTPUT_RAW` (its port).
pub const SERVOS_PER_PORT: usize = 8;

/// `array_id` of the rail positions' `DEBUG_FLOAT_ARRAY`.
pub const RAIL_ARRAY_ID: u16 = 1;
/// `name` of the rail positions' `DEBUG_FLOAT_ARRAY`.
pub const RAIL_ARRAY_NAME: &str = "rail";

impl Stream {
    /// Every stream, in the order of their index.
    pub const ALL: [Stream; STREAMS] = [
        Stream::SysStatus,
        Stream::AttitudeQuaternion,
        Stream::LocalPositionNed,
        Stream::RailPositions,
        Stream::GlobalPositionInt,
        Stream::ServoOutputRaw,
        Stream::ActuatorOutputStatus,
        Stream::EscStatus,
        Stream::EscInfo,
    ];

    /// The MAVLink message id.
    pub const fn message_id(self) -> u32 {
        match self {
            Self::SysStatus => SYS_STATUS_DATA::ID,
            Self::AttitudeQuaternion => ATTITUDE_QUATERNION_DATA::ID,
            Self::LocalPositionNed => LOCAL_POSITION_NED_DATA::ID,
            Self::RailPositions => DEBUG_FLOAT_ARRAY_DATA::ID,
            Self::GlobalPositionInt => GLOBAL_POSITION_INT_DATA::ID,
            Self::ServoOutputRaw => SERVO_OUTPUT_RAW_DATA::ID,
            Self::ActuatorOutputStatus => ACTUATOR_OUTPUT_STATUS_DATA::ID,
            Self::EscStatus => ESC_STATUS_DATA::ID,
            Self::EscInfo => ESC_INFO_DATA::ID,
        }
    }

    /// The stream of a message id, if the vehicle streams it.
    pub fn of_message(id: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.message_id() == id)
    }

    /// The interval at start and after a request for the default (interval 0), us: 1 Hz for
    /// the status and the ESCs' information, 2 Hz for the rail positions, 4 Hz for the ESC
    /// outputs and their RPM, 5 Hz for the global position (a map's), 10 Hz for attitude and
    /// local position.
    pub const fn default_interval_us(self) -> u32 {
        match self {
            Self::SysStatus | Self::EscInfo => 1_000_000,
            Self::RailPositions => 500_000,
            Self::ServoOutputRaw | Self::ActuatorOutputStatus | Self::EscStatus => 250_000,
            Self::GlobalPositionInt => 200_000,
            Self::AttitudeQuaternion | Self::LocalPositionNed => 100_000,
        }
    }
}

/// Shortest interval a ground station may set: 5 ms (200 Hz, half the control rate).
pub const MIN_INTERVAL_US: u32 = 5_000;
/// Longest interval a ground station may set: 1 hour.
pub const MAX_INTERVAL_US: u32 = 3_600_000_000;

/// When each stream is next due. (Compact: it is one of the firmware's statics.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// Interval of each stream, us; 0: off (an interval is at least [`MIN_INTERVAL_US`]).
    interval_us: [u32; STREAMS],
    /// When each stream is next due, us (vehicle time).
    next_us: [u64; STREAMS],
    /// Bit `i` set: stream `i` is sent once at the next chance, on or off
    /// (`MAV_CMD_REQUEST_MESSAGE`).
    once: u16,
}

impl Default for Schedule {
    fn default() -> Self {
        Self::new()
    }
}

impl Schedule {
    /// Every stream at its default interval, all due at once.
    pub const fn new() -> Self {
        Self {
            interval_us: [
                Stream::SysStatus.default_interval_us(),
                Stream::AttitudeQuaternion.default_interval_us(),
                Stream::LocalPositionNed.default_interval_us(),
                Stream::RailPositions.default_interval_us(),
                Stream::GlobalPositionInt.default_interval_us(),
                Stream::ServoOutputRaw.default_interval_us(),
                Stream::ActuatorOutputStatus.default_interval_us(),
                Stream::EscStatus.default_interval_us(),
                Stream::EscInfo.default_interval_us(),
            ],
            next_us: [0; STREAMS],
            once: 0,
        }
    }

    /// `MAV_CMD_SET_MESSAGE_INTERVAL` (param1 the message id, param2 the interval in us: -1
    /// off, 0 the default) at vehicle time `now_us`. The result is the `COMMAND_ACK`'s:
    /// `UNSUPPORTED` for a message the vehicle does not stream, `DENIED` for an interval
    /// outside [`MIN_INTERVAL_US`] to [`MAX_INTERVAL_US`] or not a number (nothing changes
    /// then).
    pub fn set_interval(&mut self, message_id: f32, interval_us: f32, now_us: u64) -> MavResult {
        let Some(stream) = stream_of(message_id) else {
            return MavResult::MAV_RESULT_UNSUPPORTED;
        };
        let interval = if interval_us == -1.0 {
            0
        } else if interval_us == 0.0 {
            stream.default_interval_us()
        } else if interval_us >= MIN_INTERVAL_US as f32 && interval_us <= MAX_INTERVAL_US as f32 {
            interval_us as u32
        } else {
            return MavResult::MAV_RESULT_DENIED;
        };
        let i = stream as usize;
        self.interval_us[i] = interval;
        self.next_us[i] = now_us;
        MavResult::MAV_RESULT_ACCEPTED
    }

    /// `MAV_CMD_REQUEST_MESSAGE` of `message_id`: sent once at the next chance. `false` if the
    /// vehicle does not stream that message.
    pub fn request_once(&mut self, message_id: u32) -> bool {
        match Stream::of_message(message_id) {
            Some(stream) => {
                self.once |= 1 << stream as u16;
                true
            }
            None => false,
        }
    }

    /// The interval of `stream` now, us (`None`: off).
    pub fn interval_us(&self, stream: Stream) -> Option<u32> {
        Some(self.interval_us[stream as usize]).filter(|&i| i != 0)
    }

    fn once(&self, i: usize) -> bool {
        self.once & (1 << i) != 0
    }

    /// When the next stream is due, us; `None` when every stream is off.
    pub fn next_due(&self) -> Option<u64> {
        (0..STREAMS)
            .filter_map(|i| {
                if self.once(i) {
                    Some(0)
                } else {
                    (self.interval_us[i] != 0).then_some(self.next_us[i])
                }
            })
            .min()
    }

    /// A stream due at `now_us`, if any (the one due earliest), its next time set one interval
    /// on. A vehicle that fell behind by more than one interval skips what it missed rather
    /// than sending a burst.
    pub fn take_due(&mut self, now_us: u64) -> Option<Stream> {
        if let Some(i) = (0..STREAMS).find(|&i| self.once(i)) {
            self.once &= !(1 << i);
            return Some(Stream::ALL[i]);
        }
        let i = (0..STREAMS)
            .filter(|&i| self.interval_us[i] != 0 && self.next_us[i] <= now_us)
            .min_by_key(|&i| self.next_us[i])?;
        let interval = u64::from(self.interval_us[i]);
        let next = self.next_us[i] + interval;
        self.next_us[i] = if next <= now_us {
            now_us + interval
        } else {
            next
        };
        Some(Stream::ALL[i])
    }
}

/// The stream of a message id sent as a command's float parameter.
fn stream_of(message_id: f32) -> Option<Stream> {
    if message_id.is_finite() && message_id >= 0.0 && message_id == (message_id as u32) as f32 {
        Stream::of_message(message_id as u32)
    } else {
        None
    }
}

/// The vehicle's state after its last control step, for telemetry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleSnapshot {
    /// Vehicle time of the step, us.
    pub time_us: u64,
    /// Attitude, body (FRD) to NED, `[w, x, y, z]`.
    pub attitude: [f32; 4],
    /// Body rates, rad/s (roll, pitch, yaw).
    pub rates: [f32; 3],
    /// Position from the take-off point, NED, m.
    pub position: [f32; 3],
    /// Velocity, NED, m/s.
    pub velocity: [f32; 3],
    /// The position is from a recent motion-capture fix.
    pub position_valid: bool,
    /// The IMU works (no driver fault).
    pub imu_healthy: bool,
    /// The rotors may spin.
    pub armed: bool,
    /// Robots in use.
    pub robots: u8,
    /// Each robot's commanded position along the rail, arc length, m.
    pub rail: [f32; MAX_ROBOTS],
    /// The rail positions are known (confirmed by the operator): until then the ground is
    /// sent not a number for each.
    pub rail_known: bool,
    /// Each robot's rotor thrust command, fraction of its maximum (zero unless armed).
    pub thrust: [f32; MAX_ROBOTS],
    /// The control loop's load: the worst step since the last `SYS_STATUS`, in thousandths
    /// of the step's period.
    pub load_permille: u16,
    /// The pack's filtered voltage, mV (`u16::MAX`: not measured).
    pub battery_mv: u16,
    /// The battery is above its low threshold.
    pub battery_ok: bool,
    /// The flight mode ([`crate::modes::FlightMode::code`]).
    pub mode: u8,
    /// The route's progress, for `MISSION_CURRENT` and `MISSION_ITEM_REACHED`.
    pub route: RouteStatus,
    /// `EXTENDED_SYS_STATE`'s `landed_state` (`MAV_LANDED_STATE`).
    pub landed: u8,
    /// The rotors the vehicle flies without (found stopped), bit `i` for robot `i`.
    pub rotors_out: u16,
}

/// Where the vehicle is along its route (docs/ground-link.md#missions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RouteStatus {
    /// The item flown (the first one before the flight).
    pub current: u16,
    /// The last item reached, if any.
    pub reached: Option<u16>,
    /// `MISSION_CURRENT`'s `mission_state`.
    pub progress: crate::mission::wire::MissionProgress,
}

impl RouteStatus {
    /// No route.
    pub const NONE: Self = Self {
        current: 0,
        reached: None,
        progress: crate::mission::wire::MissionProgress::NoMission,
    };
}

/// The flight log's storage as `SYS_STATUS` reports it (`MAV_SYS_STATUS_LOGGING`,
/// docs/formats.md#flight-logs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogHealth {
    /// The vehicle keeps no logs (the bit is not present).
    Absent,
    /// The storage works: present, enabled and healthy.
    Ready,
    /// The storage failed (a card missing, full or failing): present and enabled, not
    /// healthy, until a log is opened again.
    Failed,
}

impl VehicleSnapshot {
    /// Before the first control step: level, at rest, nothing valid.
    pub const START: Self = Self {
        time_us: 0,
        attitude: [1.0, 0.0, 0.0, 0.0],
        rates: [0.0; 3],
        position: [0.0; 3],
        velocity: [0.0; 3],
        position_valid: false,
        imu_healthy: true,
        armed: false,
        robots: 0,
        rail: [0.0; MAX_ROBOTS],
        rail_known: false,
        thrust: [0.0; MAX_ROBOTS],
        load_permille: 0,
        battery_mv: u16::MAX,
        battery_ok: true,
        mode: 0,
        route: RouteStatus::NONE,
        landed: MavLandedState::MAV_LANDED_STATE_ON_GROUND as u8,
        rotors_out: 0,
    };

    /// `EXTENDED_SYS_STATE`: the landed state (MAVSDK's `landed_state` and `in_air`).
    pub fn extended_sys_state(&self) -> EXTENDED_SYS_STATE_DATA {
        let landed = [
            MavLandedState::MAV_LANDED_STATE_ON_GROUND,
            MavLandedState::MAV_LANDED_STATE_IN_AIR,
            MavLandedState::MAV_LANDED_STATE_TAKEOFF,
            MavLandedState::MAV_LANDED_STATE_LANDING,
        ]
        .into_iter()
        .find(|s| *s as u8 == self.landed)
        .unwrap_or(MavLandedState::MAV_LANDED_STATE_UNDEFINED);
        EXTENDED_SYS_STATE_DATA {
            vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
            landed_state: landed,
        }
    }

    fn time_boot_ms(&self) -> u32 {
        (self.time_us / 1000) as u32
    }

    /// `SYS_STATUS` as [`Self::sys_status`] gives it, with the flight log's storage
    /// (`MAV_SYS_STATUS_LOGGING`: present unless the vehicle keeps no logs, healthy while its
    /// storage works).
    pub fn sys_status_with_log(&self, log: LogHealth) -> SYS_STATUS_DATA {
        let mut status = self.sys_status();
        let logging = MavSysStatusSensor::MAV_SYS_STATUS_LOGGING;
        if log != LogHealth::Absent {
            status.onboard_control_sensors_present |= logging;
            status.onboard_control_sensors_enabled |= logging;
        }
        if log == LogHealth::Ready {
            status.onboard_control_sensors_health |= logging;
        }
        status
    }

    /// `SYS_STATUS`: gyro, accelerometer, motion capture (as vision position), the motor
    /// outputs, the geofence and, once measured, the battery (its voltage; healthy above its
    /// low threshold); health clear for a failed IMU, no recent fix, or the vehicle outside
    /// the bounds it keeps its flights in. Current and remaining are not measured
    /// (-1, as MAVLink marks unknown values; so is a voltage not measured, `u16::MAX`).
    pub fn sys_status(&self) -> SYS_STATUS_DATA {
        let imu = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
            | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL;
        let mocap = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_VISION_POSITION;
        let motors = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS;
        // The bounds every target and route item must keep (docs/ground-link.md#missions), as
        // PX4 reports its geofence: always there and in force (MAVProxy and QGroundControl
        // read a missing bit as a breach).
        let fence = MavSysStatusSensor::MAV_SYS_STATUS_GEOFENCE;
        let present = imu | mocap | motors | fence;
        let mut enabled = imu | mocap | fence;
        if self.armed {
            enabled |= motors;
        }
        let mut health = motors;
        if self.inside_bounds() {
            health |= fence;
        }
        if self.imu_healthy {
            health |= imu;
        }
        if self.position_valid {
            health |= mocap;
        }
        let (mut present, mut enabled) = (present, enabled);
        if self.battery_mv != u16::MAX {
            let battery = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY;
            present |= battery;
            enabled |= battery;
            if self.battery_ok {
                health |= battery;
            }
        }
        SYS_STATUS_DATA {
            onboard_control_sensors_present: present,
            onboard_control_sensors_enabled: enabled,
            onboard_control_sensors_health: health,
            load: self.load_permille.min(1000),
            voltage_battery: self.battery_mv,
            current_battery: -1,
            battery_remaining: -1,
            ..Default::default()
        }
    }

    /// The vehicle is within the bounds its flights keep: [`MAX_TARGET_DISTANCE`] from the
    /// origin and [`MAX_TARGET_HEIGHT`] above it.
    pub fn inside_bounds(&self) -> bool {
        let [north, east, down] = self.position;
        north * north + east * east <= MAX_TARGET_DISTANCE * MAX_TARGET_DISTANCE
            && -down <= MAX_TARGET_HEIGHT
    }

    /// `ATTITUDE_QUATERNION`.
    pub fn attitude_quaternion(&self) -> ATTITUDE_QUATERNION_DATA {
        let [w, x, y, z] = self.attitude;
        ATTITUDE_QUATERNION_DATA {
            time_boot_ms: self.time_boot_ms(),
            q1: w,
            q2: x,
            q3: y,
            q4: z,
            rollspeed: self.rates[0],
            pitchspeed: self.rates[1],
            yawspeed: self.rates[2],
        }
    }

    /// `DEBUG_FLOAT_ARRAY` `rail` and its `data` (an extension field: its bytes, to send
    /// with `Encoder::encode_extended`), one arc length per robot in use (not a number while
    /// the positions are not known).
    pub fn rail_positions(&self) -> (DEBUG_FLOAT_ARRAY_DATA, [u8; 4 * MAX_ROBOTS], usize) {
        let robots = usize::from(self.robots).min(MAX_ROBOTS);
        let mut data = [0u8; 4 * MAX_ROBOTS];
        for (j, &s) in self.rail[..robots].iter().enumerate() {
            let s = if self.rail_known { s } else { f32::NAN };
            data[4 * j..4 * j + 4].copy_from_slice(&s.to_le_bytes());
        }
        let array = DEBUG_FLOAT_ARRAY_DATA {
            time_usec: self.time_us,
            array_id: RAIL_ARRAY_ID,
            name: RAIL_ARRAY_NAME.into(),
        };
        (array, data, 4 * robots)
    }

    /// Each robot's ESC command, fraction of full, through the thrust map `map` (zero when
    /// disarmed).
    pub fn esc_commands(&self, map: &ThrustMap) -> [f32; MAX_ROBOTS] {
        let robots = usize::from(self.robots).min(MAX_ROBOTS);
        let mut commands = [0.0; MAX_ROBOTS];
        if self.armed {
            for (c, &t) in commands.iter_mut().zip(&self.thrust[..robots]) {
                *c = map.command(t);
            }
        }
        commands
    }

    /// `ACTUATOR_OUTPUT_STATUS`: each robot's ESC command through `map`, fraction of full
    /// (`active`: a bit per robot in use).
    pub fn actuator_output_status(&self, map: &ThrustMap) -> ACTUATOR_OUTPUT_STATUS_DATA {
        let robots = usize::from(self.robots).min(MAX_ROBOTS);
        let commands = self.esc_commands(map);
        let mut actuator = [0.0f32; 32];
        actuator[..MAX_ROBOTS].copy_from_slice(&commands);
        ACTUATOR_OUTPUT_STATUS_DATA {
            time_usec: self.time_us,
            active: if robots >= 32 {
                u32::MAX
            } else {
                (1u32 << robots) - 1
            },
            actuator,
        }
    }

    /// `SERVO_OUTPUT_RAW` of output port `port` (eight outputs a port, as PX4's MAIN 0 and
    /// AUX 1): robots `8 * port` to `8 * port + 7`'s ESC commands through `map` as the pulses
    /// a PWM ESC would get, 1000 us (stopped) to 2000 us (full).
    pub fn servo_output_raw(&self, map: &ThrustMap, port: u8) -> SERVO_OUTPUT_RAW_DATA {
        let c = self.esc_commands(map);
        let first = SERVOS_PER_PORT * usize::from(port);
        let us = |j: usize| {
            let command = c.get(first + j).copied().unwrap_or(0.0);
            1000 + (command.clamp(0.0, 1.0) * 1000.0 + 0.5) as u16
        };
        SERVO_OUTPUT_RAW_DATA {
            time_usec: self.time_us as u32,
            servo1_raw: us(0),
            servo2_raw: us(1),
            servo3_raw: us(2),
            servo4_raw: us(3),
            servo5_raw: us(4),
            servo6_raw: us(5),
            servo7_raw: us(6),
            servo8_raw: us(7),
            port,
        }
    }

    /// The `SERVO_OUTPUT_RAW` ports the robots in use fill (at least one).
    pub fn servo_ports(&self) -> u8 {
        usize::from(self.robots)
            .div_ceil(SERVOS_PER_PORT)
            .clamp(1, MAX_ROBOTS / SERVOS_PER_PORT) as u8
    }

    /// `LOCAL_POSITION_NED`.
    pub fn local_position_ned(&self) -> LOCAL_POSITION_NED_DATA {
        LOCAL_POSITION_NED_DATA {
            time_boot_ms: self.time_boot_ms(),
            x: self.position[0],
            y: self.position[1],
            z: self.position[2],
            vx: self.velocity[0],
            vy: self.velocity[1],
            vz: self.velocity[2],
        }
    }
}

/// A velocity, m/s, in MAVLink's cm/s, saturating (not a number: 0).
fn centimetres(v: f32) -> i16 {
    // `as` saturates and takes NaN to 0.
    (v * 100.0) as i16
}

impl VehicleSnapshot {
    /// `GLOBAL_POSITION_INT`: the position through the map `origin` (latitude, longitude,
    /// altitude above mean sea level; `relative_alt` the height above the origin, `-z`), the
    /// velocity in cm/s and the heading (yaw) in centidegrees. `None` when the origin is
    /// unusable or the position not finite ([`GeoOrigin::to_global`]).
    pub fn global_position_int(&self, origin: &GeoOrigin) -> Option<GLOBAL_POSITION_INT_DATA> {
        let p = origin.to_global(self.position)?;
        let [w, x, y, z] = self.attitude;
        let yaw = shared::math::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
        let degrees = yaw.to_degrees();
        let heading = if degrees < 0.0 {
            degrees + 360.0
        } else {
            degrees
        };
        // Not a number, or a rounding to 360 degrees: unknown, as MAVLink marks it.
        let hdg = match (heading * 100.0 + 0.5) as u16 {
            h if h < 36_000 && heading.is_finite() => h,
            36_000 => 0,
            _ => u16::MAX,
        };
        Some(GLOBAL_POSITION_INT_DATA {
            time_boot_ms: self.time_boot_ms(),
            lat: p.lat_e7,
            lon: p.lon_e7,
            alt: p.alt_mm,
            relative_alt: (-self.position[2] * 1000.0) as i32,
            vx: centimetres(self.velocity[0]),
            vy: centimetres(self.velocity[1]),
            vz: centimetres(self.velocity[2]),
            hdg,
        })
    }
}

/// The take-off point: the local position (NED) where the vehicle last armed; before any
/// flight, the origin itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Home {
    /// Where, m, NED from the origin.
    position: [f32; 3],
    /// The vehicle was armed at the last look.
    armed: bool,
}

impl Default for Home {
    fn default() -> Self {
        Self::START
    }
}

impl Home {
    /// Before any flight: the origin.
    pub const START: Self = Self {
        position: [0.0; 3],
        armed: false,
    };

    /// Looks at the vehicle's state: when it has armed since the last look, its position (if
    /// finite) is the new home. `true` when the home moved.
    pub fn observe(&mut self, vehicle: &VehicleSnapshot) -> bool {
        let armed_now = vehicle.armed && !self.armed;
        self.armed = vehicle.armed;
        if armed_now && vehicle.position.iter().all(|v| v.is_finite()) {
            let moved = self.position != vehicle.position;
            self.position = vehicle.position;
            return moved;
        }
        false
    }

    /// The home's local position, m, NED from the origin.
    pub fn position(&self) -> [f32; 3] {
        self.position
    }

    /// `HOME_POSITION` through the map `origin` (the local position too, the approach
    /// vector zero, the attitude level); `None` when the origin is unusable.
    pub fn home_position(&self, origin: &GeoOrigin) -> Option<HOME_POSITION_DATA> {
        let p = origin.to_global(self.position)?;
        let [x, y, z] = self.position;
        Some(HOME_POSITION_DATA {
            latitude: p.lat_e7,
            longitude: p.lon_e7,
            altitude: p.alt_mm,
            x,
            y,
            z,
            q: [1.0, 0.0, 0.0, 0.0],
            ..Default::default()
        })
    }
}

/// `GPS_GLOBAL_ORIGIN`: the map origin (altitude above mean sea level, mm).
pub fn gps_global_origin(origin: &GeoOrigin) -> GPS_GLOBAL_ORIGIN_DATA {
    let p = origin.point();
    GPS_GLOBAL_ORIGIN_DATA {
        latitude: p.lat_e7,
        longitude: p.lon_e7,
        altitude: p.alt_mm,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ATT: f32 = ATTITUDE_QUATERNION_DATA::ID as f32;

    /// The streams sent over `[0, until_us)` when the sender wakes at every due time.
    fn sent(s: &mut Schedule, until_us: u64) -> std::vec::Vec<(u64, Stream)> {
        let mut out = std::vec::Vec::new();
        while let Some(t) = s.next_due() {
            if t >= until_us {
                break;
            }
            while let Some(stream) = s.take_due(t) {
                out.push((t, stream));
            }
        }
        out
    }

    fn count(log: &[(u64, Stream)], stream: Stream) -> usize {
        log.iter().filter(|(_, s)| *s == stream).count()
    }

    #[test]
    fn the_defaults_stream_at_their_rates() {
        let mut s = Schedule::new();
        let log = sent(&mut s, 2_000_000);
        assert_eq!(count(&log, Stream::SysStatus), 2);
        assert_eq!(count(&log, Stream::RailPositions), 4);
        assert_eq!(count(&log, Stream::AttitudeQuaternion), 20);
        assert_eq!(count(&log, Stream::LocalPositionNed), 20);
        assert_eq!(count(&log, Stream::GlobalPositionInt), 10);
    }

    #[test]
    fn a_set_interval_changes_the_rate_and_minus_one_stops_it() {
        let mut s = Schedule::new();
        assert_eq!(
            s.set_interval(ATT, 20_000.0, 0),
            MavResult::MAV_RESULT_ACCEPTED
        );
        let log = sent(&mut s, 1_000_000);
        assert_eq!(count(&log, Stream::AttitudeQuaternion), 50);
        assert_eq!(
            s.set_interval(ATT, -1.0, 1_000_000),
            MavResult::MAV_RESULT_ACCEPTED
        );
        assert_eq!(s.interval_us(Stream::AttitudeQuaternion), None);
        let log = sent(&mut s, 2_000_000);
        assert_eq!(count(&log, Stream::AttitudeQuaternion), 0);
        assert_eq!(count(&log, Stream::LocalPositionNed), 10);
        // 0: back to the default.
        assert_eq!(s.set_interval(ATT, 0.0, 0), MavResult::MAV_RESULT_ACCEPTED);
        assert_eq!(s.interval_us(Stream::AttitudeQuaternion), Some(100_000));
    }

    #[test]
    fn bad_requests_are_refused_and_change_nothing() {
        let mut s = Schedule::new();
        let before = s;
        for (id, interval, result) in [
            (0.0, 20_000.0, MavResult::MAV_RESULT_UNSUPPORTED), // HEARTBEAT: not a stream
            (f32::NAN, 20_000.0, MavResult::MAV_RESULT_UNSUPPORTED),
            (ATT + 0.5, 20_000.0, MavResult::MAV_RESULT_UNSUPPORTED),
            (ATT, 100.0, MavResult::MAV_RESULT_DENIED), // 10 kHz
            (ATT, -2.0, MavResult::MAV_RESULT_DENIED),
            (ATT, f32::INFINITY, MavResult::MAV_RESULT_DENIED),
            (ATT, f32::NAN, MavResult::MAV_RESULT_DENIED),
        ] {
            assert_eq!(s.set_interval(id, interval, 5), result, "{id} {interval}");
            assert_eq!(s, before);
        }
    }

    #[test]
    fn a_request_sends_once_even_when_off() {
        let mut s = Schedule::new();
        assert_eq!(
            s.set_interval(SYS_STATUS_DATA::ID as f32, -1.0, 0),
            MavResult::MAV_RESULT_ACCEPTED
        );
        let _ = sent(&mut s, 1_000_000);
        assert!(s.request_once(SYS_STATUS_DATA::ID));
        assert!(!s.request_once(0));
        assert_eq!(s.next_due(), Some(0));
        assert_eq!(s.take_due(1_000_000), Some(Stream::SysStatus));
        let log = sent(&mut s, 3_000_000);
        assert_eq!(count(&log, Stream::SysStatus), 0);
    }

    #[test]
    fn a_late_sender_skips_rather_than_bursts() {
        let mut s = Schedule::new();
        let _ = sent(&mut s, 1);
        // Woken 1 s late: each stream once, then on its interval from now.
        let mut late = std::vec::Vec::new();
        while let Some(stream) = s.take_due(1_000_000) {
            late.push(stream);
        }
        assert_eq!(late.len(), STREAMS);
        assert_eq!(s.next_due(), Some(1_100_000));
    }

    #[test]
    fn every_stream_off_means_nothing_due() {
        let mut s = Schedule::new();
        for stream in Stream::ALL {
            s.set_interval(stream.message_id() as f32, -1.0, 0);
        }
        assert_eq!(s.next_due(), None);
        assert_eq!(s.take_due(u64::MAX / 2), None);
    }

    #[test]
    fn the_flight_logs_storage_is_present_and_healthy_while_it_works() {
        let logging = MavSysStatusSensor::MAV_SYS_STATUS_LOGGING;
        let snap = VehicleSnapshot::START;
        let none = snap.sys_status_with_log(LogHealth::Absent);
        assert!(!none.onboard_control_sensors_present.contains(logging));
        assert_eq!(none, snap.sys_status());
        let ready = snap.sys_status_with_log(LogHealth::Ready);
        assert!(ready.onboard_control_sensors_present.contains(logging));
        assert!(ready.onboard_control_sensors_enabled.contains(logging));
        assert!(ready.onboard_control_sensors_health.contains(logging));
        let failed = snap.sys_status_with_log(LogHealth::Failed);
        assert!(failed.onboard_control_sensors_present.contains(logging));
        assert!(!failed.onboard_control_sensors_health.contains(logging));
    }

    #[test]
    fn the_messages_carry_the_snapshot() {
        let snap = VehicleSnapshot {
            time_us: 12_345_678,
            attitude: [0.5, 0.5, -0.5, 0.5],
            rates: [0.1, -0.2, 0.3],
            position: [1.0, 2.0, -3.0],
            velocity: [0.5, 0.0, -0.25],
            position_valid: true,
            imu_healthy: false,
            armed: true,
            robots: 3,
            rail: [
                0.5, 1.25, 2.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0,
            ],
            rail_known: true,
            load_permille: 1500,
            battery_mv: u16::MAX,
            battery_ok: true,
            ..VehicleSnapshot::START
        };
        let (array, data, len) = snap.rail_positions();
        assert_eq!(
            (array.array_id, array.name.to_str().ok()),
            (RAIL_ARRAY_ID, Some("rail"))
        );
        assert_eq!(len, 12);
        let arcs: std::vec::Vec<f32> = data[..len]
            .chunks(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(arcs, [0.5, 1.25, 2.0]);
        // Not confirmed: not a number for each robot.
        let unknown = VehicleSnapshot {
            rail_known: false,
            ..snap
        };
        let (_, data, len) = unknown.rail_positions();
        assert!(
            data[..len]
                .chunks(4)
                .all(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]).is_nan())
        );
        let q = snap.attitude_quaternion();
        assert_eq!(q.time_boot_ms, 12_345);
        assert_eq!([q.q1, q.q2, q.q3, q.q4], snap.attitude);
        assert_eq!([q.rollspeed, q.pitchspeed, q.yawspeed], snap.rates);
        let p = snap.local_position_ned();
        assert_eq!(
            [p.x, p.y, p.z, p.vx, p.vy, p.vz],
            [1.0, 2.0, -3.0, 0.5, 0.0, -0.25]
        );
        let st = snap.sys_status();
        let gyro = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO;
        let vision = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_VISION_POSITION;
        assert!(st.onboard_control_sensors_present.contains(gyro));
        assert!(!st.onboard_control_sensors_health.contains(gyro));
        assert!(st.onboard_control_sensors_health.contains(vision));
        assert_eq!(st.load, 1000);
        assert_eq!(st.voltage_battery, u16::MAX);
        let resting = VehicleSnapshot::START.sys_status();
        assert!(resting.onboard_control_sensors_health.contains(gyro));
        assert!(!resting.onboard_control_sensors_health.contains(vision));
        let battery = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY;
        assert!(!resting.onboard_control_sensors_present.contains(battery));
    }

    #[test]
    fn the_geofence_is_reported_as_px4_reports_it_and_breached_outside_the_bounds() {
        let fence = MavSysStatusSensor::MAV_SYS_STATUS_GEOFENCE;
        let at = |position| VehicleSnapshot {
            position,
            ..VehicleSnapshot::START
        };
        for inside in [[0.0, 0.0, 0.0], [19.0, -5.0, -9.5]] {
            let st = at(inside).sys_status();
            assert!(st.onboard_control_sensors_present.contains(fence));
            assert!(st.onboard_control_sensors_enabled.contains(fence));
            assert!(
                st.onboard_control_sensors_health.contains(fence),
                "{inside:?}"
            );
        }
        for outside in [[15.0, 15.0, -1.0], [0.0, 0.0, -10.5]] {
            let st = at(outside).sys_status();
            assert!(st.onboard_control_sensors_present.contains(fence));
            assert!(
                !st.onboard_control_sensors_health.contains(fence),
                "{outside:?}"
            );
        }
    }

    #[test]
    fn a_measured_battery_is_reported_with_its_health() {
        let battery = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY;
        let good = VehicleSnapshot {
            battery_mv: 15_730,
            ..VehicleSnapshot::START
        }
        .sys_status();
        assert_eq!(good.voltage_battery, 15_730);
        assert!(good.onboard_control_sensors_present.contains(battery));
        assert!(good.onboard_control_sensors_health.contains(battery));
        let low = VehicleSnapshot {
            battery_mv: 13_100,
            battery_ok: false,
            ..VehicleSnapshot::START
        }
        .sys_status();
        assert!(low.onboard_control_sensors_enabled.contains(battery));
        assert!(!low.onboard_control_sensors_health.contains(battery));
    }

    /// PX4's simulation home, the parameters' default.
    const ORIGIN: GeoOrigin = GeoOrigin {
        lat_e7: 473_977_420,
        lon_e7: 85_455_940,
        alt_m: 488.0,
    };

    #[test]
    fn the_global_position_is_the_local_one_through_the_origin() {
        // Yawed 90 degrees (east), 2 m up, 10 m north and 5 m east of the origin.
        let half = core::f32::consts::FRAC_1_SQRT_2;
        let snap = VehicleSnapshot {
            time_us: 3_000_000,
            attitude: [half, 0.0, 0.0, half],
            position: [10.0, 5.0, -2.0],
            velocity: [1.5, -0.25, 400.0],
            ..VehicleSnapshot::START
        };
        let g = snap.global_position_int(&ORIGIN).expect("a usable origin");
        let p = ORIGIN.to_global(snap.position).expect("usable");
        assert_eq!((g.lat, g.lon, g.alt), (p.lat_e7, p.lon_e7, p.alt_mm));
        // 10 m north is 899 1e-7 degrees at 47 degrees; 5 m east 662.
        assert_eq!((g.lat - ORIGIN.lat_e7, g.lon - ORIGIN.lon_e7), (899, 662));
        assert_eq!((g.alt, g.relative_alt), (490_000, 2_000));
        assert_eq!((g.vx, g.vy, g.vz), (150, -25, i16::MAX));
        assert_eq!((g.hdg, g.time_boot_ms), (9_000, 3_000));
        let west = VehicleSnapshot {
            attitude: [half, 0.0, 0.0, -half],
            ..snap
        };
        assert_eq!(
            west.global_position_int(&ORIGIN).map(|g| g.hdg),
            Some(27_000)
        );
        let broken = VehicleSnapshot {
            attitude: [f32::NAN; 4],
            velocity: [f32::NAN; 3],
            ..snap
        };
        let g = broken
            .global_position_int(&ORIGIN)
            .expect("the position holds");
        assert_eq!((g.hdg, g.vx), (u16::MAX, 0));
        let lost = VehicleSnapshot {
            position: [f32::NAN, 0.0, 0.0],
            ..snap
        };
        assert_eq!(lost.global_position_int(&ORIGIN), None);
        let polar = GeoOrigin {
            lat_e7: 890_000_000,
            ..ORIGIN
        };
        assert_eq!(snap.global_position_int(&polar), None);
    }

    #[test]
    fn home_is_where_the_vehicle_armed_and_the_origin_before() {
        let mut home = Home::START;
        let h = home.home_position(&ORIGIN).expect("usable");
        assert_eq!(
            (h.latitude, h.longitude, h.altitude),
            (473_977_420, 85_455_940, 488_000)
        );
        assert_eq!(h.q, [1.0, 0.0, 0.0, 0.0]);
        let ground = VehicleSnapshot {
            position: [1.0, -2.0, 0.0],
            ..VehicleSnapshot::START
        };
        assert!(!home.observe(&ground), "not armed: no home");
        let armed = VehicleSnapshot {
            armed: true,
            ..ground
        };
        assert!(home.observe(&armed));
        let flying = VehicleSnapshot {
            position: [5.0, 5.0, -3.0],
            ..armed
        };
        assert!(!home.observe(&flying), "only at arming");
        assert_eq!(home.position(), [1.0, -2.0, 0.0]);
        let h = home.home_position(&ORIGIN).expect("usable");
        assert_eq!((h.x, h.y, h.z), (1.0, -2.0, 0.0));
        assert_eq!(
            Some((h.latitude, h.longitude)),
            ORIGIN
                .to_global([1.0, -2.0, 0.0])
                .map(|p| (p.lat_e7, p.lon_e7))
        );
        // Landed, disarmed, armed again elsewhere: the new take-off point.
        assert!(!home.observe(&VehicleSnapshot {
            armed: false,
            ..flying
        }));
        assert!(home.observe(&flying));
        assert_eq!(home.position(), [5.0, 5.0, -3.0]);
        let o = gps_global_origin(&ORIGIN);
        assert_eq!(
            (o.latitude, o.longitude, o.altitude),
            (473_977_420, 85_455_940, 488_000)
        );
    }

    #[test]
    fn the_esc_outputs_are_the_thrust_maps_commands_and_stopped_when_disarmed() {
        let mut snap = VehicleSnapshot::START;
        snap.robots = 3;
        snap.armed = true;
        // The square law: 4 % and 16 % of full thrust are 20 % and 40 % command.
        snap.thrust[..3].copy_from_slice(&[0.04, 0.16, 0.0]);
        let map = ThrustMap::SQUARE;
        let status = snap.actuator_output_status(&map);
        assert_eq!(status.active, 0b111);
        assert!((status.actuator[0] - 0.2).abs() < 1e-5);
        assert!((status.actuator[1] - 0.4).abs() < 1e-5);
        assert_eq!(status.actuator[2], 0.0);
        let raw = snap.servo_output_raw(&map, 0);
        assert_eq!(
            (raw.servo1_raw, raw.servo2_raw, raw.servo3_raw),
            (1200, 1400, 1000)
        );
        assert_eq!(raw.servo8_raw, 1000);
        snap.armed = false;
        assert!(
            snap.actuator_output_status(&map)
                .actuator
                .iter()
                .all(|&a| a == 0.0)
        );
        assert_eq!(snap.servo_output_raw(&map, 0).servo1_raw, 1000);
        // Robots past the eighth on the second port (AUX), as PX4 sends them.
        snap.armed = true;
        snap.robots = 12;
        snap.thrust[9] = 0.16;
        assert_eq!(snap.servo_ports(), 2);
        let aux = snap.servo_output_raw(&map, 1);
        assert_eq!((aux.port, aux.servo2_raw, aux.servo5_raw), (1, 1400, 1000));
        snap.robots = 3;
        assert_eq!(snap.servo_ports(), 1);
        for stream in [Stream::ServoOutputRaw, Stream::ActuatorOutputStatus] {
            assert_eq!(Stream::of_message(stream.message_id()), Some(stream));
        }
    }
}
