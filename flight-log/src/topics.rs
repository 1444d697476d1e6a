//! The logged topics and their records. Topics whose meaning is PX4's carry PX4's name and
//! field names (so Flight Review and PlotJuggler's PX4 layouts find them): `sensor_combined`,
//! `vehicle_attitude`, `vehicle_angular_velocity`, `vehicle_local_position`,
//! `vehicle_mocap_odometry`, `actuator_outputs`, `vehicle_status`, `battery_status`,
//! `vehicle_attitude_setpoint`, `vehicle_rates_setpoint`, `manual_control_setpoint`,
//! `manual_control_switches` (each the subset of PX4's fields this
//! vehicle has, with PX4's names and types). The rest are this vehicle's own: `rail_position`, `lift`, `formation`, `adaptation`, `fault`.
//! Each format lists the fields in the order [`Record::pack`] writes them, packed, the
//! timestamp (us, the flight controller's clock) first.

use crate::ulog::Packer;
use heapless::Vec;
use shared::scenario::MAX_ROBOTS;

/// The largest packed record, bytes.
pub const RECORD_CAPACITY: usize = 96;

/// A logged topic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Topic {
    /// Every IMU sample: body rates and specific force.
    SensorCombined,
    /// The attitude estimate.
    VehicleAttitude,
    /// The body rate estimate.
    VehicleAngularVelocity,
    /// The position and velocity estimate (NED, the motion-capture frame).
    VehicleLocalPosition,
    /// Each motion-capture fix.
    VehicleMocapOdometry,
    /// Each rotor's command.
    ActuatorOutputs,
    /// Armed, PX4's navigation state and the mission's phase.
    VehicleStatus,
    /// The pack's voltage.
    BatteryStatus,
    /// Each robot's rail position.
    RailPosition,
    /// Each lift of the estimation.
    Lift,
    /// The formation decided before take-off, or in flight after a load shift.
    Formation,
    /// What the in-flight adaptation did.
    Adaptation,
    /// The failures the mission watches.
    Fault,
    /// The cascade's attitude setpoint and normalised thrust.
    VehicleAttitudeSetpoint,
    /// The cascade's body-rate setpoint and normalised thrust.
    VehicleRatesSetpoint,
    /// The sticks in force (RC or joystick; docs/manual-control.md).
    ManualControlSetpoint,
    /// The mode and kill switches in force.
    ManualControlSwitches,
}

impl Topic {
    /// Every topic, in message-id order.
    pub const ALL: [Topic; 17] = [
        Topic::SensorCombined,
        Topic::VehicleAttitude,
        Topic::VehicleAngularVelocity,
        Topic::VehicleLocalPosition,
        Topic::VehicleMocapOdometry,
        Topic::ActuatorOutputs,
        Topic::VehicleStatus,
        Topic::BatteryStatus,
        Topic::RailPosition,
        Topic::Lift,
        Topic::Formation,
        Topic::Adaptation,
        Topic::Fault,
        Topic::VehicleAttitudeSetpoint,
        Topic::VehicleRatesSetpoint,
        Topic::ManualControlSetpoint,
        Topic::ManualControlSwitches,
    ];

    /// The subscription's message id.
    pub fn msg_id(self) -> u16 {
        self as u16
    }

    /// The topic's name: its format's text before the colon.
    pub fn name(self) -> &'static str {
        let f = self.format();
        f.split(':').next().unwrap_or(f)
    }

    /// The ULog format: `name:type field;...`.
    pub fn format(self) -> &'static str {
        match self {
            Self::SensorCombined => {
                "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;\
                 int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;\
                 uint32_t accelerometer_integral_dt"
            }
            Self::VehicleAttitude => {
                "vehicle_attitude:uint64_t timestamp;uint64_t timestamp_sample;float[4] q"
            }
            Self::VehicleAngularVelocity => {
                "vehicle_angular_velocity:uint64_t timestamp;uint64_t timestamp_sample;\
                 float[3] xyz"
            }
            Self::VehicleLocalPosition => {
                "vehicle_local_position:uint64_t timestamp;uint64_t timestamp_sample;\
                 bool xy_valid;bool z_valid;bool v_xy_valid;bool v_z_valid;float x;float y;\
                 float z;float vx;float vy;float vz"
            }
            Self::VehicleMocapOdometry => {
                "vehicle_mocap_odometry:uint64_t timestamp;uint64_t timestamp_sample;\
                 float[3] position;float[4] q"
            }
            Self::ActuatorOutputs => {
                "actuator_outputs:uint64_t timestamp;uint32_t noutputs;float[16] output"
            }
            Self::VehicleStatus => {
                "vehicle_status:uint64_t timestamp;uint8_t arming_state;uint8_t nav_state;\
                 uint8_t mission_phase"
            }
            Self::BatteryStatus => {
                "battery_status:uint64_t timestamp;bool connected;float voltage_v;\
                 uint8_t warning"
            }
            Self::RailPosition => {
                "rail_position:uint64_t timestamp;uint8_t robots;float[16] commanded_m"
            }
            Self::Lift => {
                "lift:uint64_t timestamp;uint8_t pair;float information_nats;bool lifted;\
                 float thrust_n;uint32_t lifts;float com_x;float com_y;float mass;\
                 float confidence;float com_x_std;float com_y_std;float mass_std;float model_n"
            }
            Self::Formation => {
                "formation:uint64_t timestamp;uint8_t robots;float[16] position_m;float det_bbt;\
                 bool in_flight"
            }
            Self::Adaptation => {
                "adaptation:uint64_t timestamp;uint8_t event;float com_x;float com_y;float mass;\
                 float duration_s"
            }
            Self::Fault => {
                "fault:uint64_t timestamp;uint16_t rotors_out;uint16_t stalled_robots;bool imu;\
                 bool imu_dropped;bool gcs_link;uint8_t battery_warning"
            }
            Self::VehicleAttitudeSetpoint => {
                "vehicle_attitude_setpoint:uint64_t timestamp;float[4] q_d;float[3] thrust_body"
            }
            Self::VehicleRatesSetpoint => {
                "vehicle_rates_setpoint:uint64_t timestamp;float roll;float pitch;float yaw;\
                 float[3] thrust_body"
            }
            Self::ManualControlSetpoint => {
                "manual_control_setpoint:uint64_t timestamp;bool valid;uint8_t data_source;\
                 float roll;float pitch;float yaw;float throttle"
            }
            Self::ManualControlSwitches => {
                "manual_control_switches:uint64_t timestamp;uint8_t mode_slot;uint8_t kill_switch"
            }
        }
    }
}

/// Up to [`MAX_ROBOTS`] values as a `float[16]`, unused places 0.
pub fn per_robot(values: &[f32]) -> [f32; MAX_ROBOTS] {
    let mut out = [0.0; MAX_ROBOTS];
    for (o, v) in out.iter_mut().zip(values) {
        *o = *v;
    }
    out
}

/// One record of a topic, fixed size: what the control step hands the log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Record {
    /// `sensor_combined`.
    SensorCombined {
        /// Sample time, us.
        timestamp: u64,
        /// Body rates, rad/s (FRD).
        gyro_rad: [f32; 3],
        /// Specific force, m/s^2 (FRD).
        accelerometer_m_s2: [f32; 3],
        /// The sample's period, us.
        integral_dt: u32,
    },
    /// `vehicle_attitude`.
    VehicleAttitude {
        /// Time, us.
        timestamp: u64,
        /// Body to NED, (w, x, y, z).
        q: [f32; 4],
    },
    /// `vehicle_angular_velocity`.
    VehicleAngularVelocity {
        /// Time, us.
        timestamp: u64,
        /// Body rates, rad/s.
        xyz: [f32; 3],
    },
    /// `vehicle_local_position`.
    VehicleLocalPosition {
        /// Time, us.
        timestamp: u64,
        /// Whether the estimate is valid.
        valid: bool,
        /// NED position, m.
        position: [f32; 3],
        /// NED velocity, m/s.
        velocity: [f32; 3],
    },
    /// `vehicle_mocap_odometry`.
    VehicleMocapOdometry {
        /// Time the fix came, us.
        timestamp: u64,
        /// When the cameras saw it, us.
        timestamp_sample: u64,
        /// NED position, m.
        position: [f32; 3],
        /// Attitude, (w, x, y, z).
        q: [f32; 4],
    },
    /// `actuator_outputs`.
    ActuatorOutputs {
        /// Time, us.
        timestamp: u64,
        /// Rotors in use.
        noutputs: u32,
        /// Each rotor's command, fraction of its maximum thrust (0 disarmed).
        output: [f32; MAX_ROBOTS],
    },
    /// `vehicle_status`.
    VehicleStatus {
        /// Time, us.
        timestamp: u64,
        /// Whether the rotors may spin.
        armed: bool,
        /// PX4's navigation state nearest the phase.
        nav_state: u8,
        /// The mission's phase ([`super::recorder::phase_code`]).
        mission_phase: u8,
    },
    /// `battery_status`.
    BatteryStatus {
        /// Time, us.
        timestamp: u64,
        /// The voltage, V (none: no battery monitor).
        voltage_v: Option<f32>,
        /// 0 none, 1 low, 2 critical (PX4's `BATTERY_WARNING_*`).
        warning: u8,
    },
    /// `rail_position`.
    RailPosition {
        /// Time, us.
        timestamp: u64,
        /// Robots on the rail.
        robots: u8,
        /// Where each robot is commanded to be, arc length, m.
        commanded_m: [f32; MAX_ROBOTS],
    },
    /// `lift`: one lift's reading and the estimate after it.
    Lift {
        /// Time, us.
        timestamp: u64,
        /// The lifting pair's group.
        pair: u8,
        /// Its mutual information, nats.
        information_nats: f32,
        /// The reading: lift-off thrust per robot, N (none: could not lift).
        thrust_n: Option<f32>,
        /// Lifts so far whose update has come back.
        lifts: u32,
        /// The posterior mean after the last update: COM x, y (m), mass (kg); NaN before any.
        theta: [f32; 3],
        /// The posterior mass of the MAP's neighbourhood (NaN before any update).
        confidence: f32,
        /// The posterior's standard deviation of COM x, y (m) and mass (kg); NaN before any.
        spread: [f32; 3],
        /// The lift-off thrust per robot the model predicts for the pair at the estimate after
        /// the lift, N (NaN when none).
        model_n: f32,
    },
    /// `formation`.
    Formation {
        /// Time, us.
        timestamp: u64,
        /// Robots.
        robots: u8,
        /// Each robot's position, arc length, m.
        position_m: [f32; MAX_ROBOTS],
        /// `det(B B^T)` of the formation (NaN when not known).
        det_bbt: f32,
        /// Chosen in flight after a load shift.
        in_flight: bool,
    },
    /// `adaptation`: 0 the load shifted (COM and mass), 1 the robots move (duration), 2
    /// rebalanced, 3 gave up.
    Adaptation {
        /// Time, us.
        timestamp: u64,
        /// What happened.
        event: u8,
        /// The measured COM, m, and mass, kg (NaN unless shifted).
        com_mass: [f32; 3],
        /// The move's duration, s (NaN unless moving).
        duration_s: f32,
    },
    /// `fault`: the failures the mission watches, as they change.
    Fault {
        /// Time, us.
        timestamp: u64,
        /// Rotors the drivers report stopped (bit j: robot j).
        rotors_out: u16,
        /// Robots whose steppers stalled (bit j).
        stalled_robots: u16,
        /// The IMU driver reports a fault.
        imu: bool,
        /// The mission flies without the IMU.
        imu_dropped: bool,
        /// The ground station's heartbeat is in time.
        gcs_link: bool,
        /// 0 none, 1 low, 2 critical.
        battery_warning: u8,
    },
    /// `vehicle_attitude_setpoint`.
    VehicleAttitudeSetpoint {
        /// Time, us.
        timestamp: u64,
        /// The attitude setpoint, body to NED, (w, x, y, z).
        q_d: [f32; 4],
        /// PX4's normalised body thrust: the collective over the rotors' total maximum, on
        /// body z, negative up.
        thrust_body: [f32; 3],
    },
    /// `vehicle_rates_setpoint`.
    VehicleRatesSetpoint {
        /// Time, us.
        timestamp: u64,
        /// Body-rate setpoint, rad/s (FRD): roll, pitch, yaw.
        rate: [f32; 3],
        /// PX4's normalised body thrust, as in `VehicleAttitudeSetpoint`.
        thrust_body: [f32; 3],
    },
    /// `manual_control_setpoint`: the sticks in force, PX4's ranges.
    ManualControlSetpoint {
        /// Time, us.
        timestamp: u64,
        /// A source is in force and fresh.
        valid: bool,
        /// PX4's source: 0 RC, 1 a ground station's joystick (`MAVLINK_0`); 255 none.
        data_source: u8,
        /// Roll, pitch, yaw in -1..1 and throttle in -1..1 (PX4's: -1 down, 1 up).
        sticks: [f32; 4],
    },
    /// `manual_control_switches`, PX4's numbers.
    ManualControlSwitches {
        /// Time, us.
        timestamp: u64,
        /// The mode switch's slot, 1 to 6; 0 none.
        mode_slot: u8,
        /// The kill switch: 1 on, 3 off (PX4's `SWITCH_POS_ON`, `_OFF`).
        kill_switch: u8,
    },
}

/// Packed data of one record.
pub type Packed = Vec<u8, RECORD_CAPACITY>;

/// Bytes of the largest record's whole ULog data message (header, message id, fields).
pub const MESSAGE_BYTES: usize = RECORD_CAPACITY + 5;

/// One record as its whole ULog data message, in a buffer of its own.
pub type DataMessage = Packer<[u8; MESSAGE_BYTES]>;

impl Record {
    /// The record's topic.
    pub fn topic(&self) -> Topic {
        match self {
            Self::SensorCombined { .. } => Topic::SensorCombined,
            Self::VehicleAttitude { .. } => Topic::VehicleAttitude,
            Self::VehicleAngularVelocity { .. } => Topic::VehicleAngularVelocity,
            Self::VehicleLocalPosition { .. } => Topic::VehicleLocalPosition,
            Self::VehicleMocapOdometry { .. } => Topic::VehicleMocapOdometry,
            Self::ActuatorOutputs { .. } => Topic::ActuatorOutputs,
            Self::VehicleStatus { .. } => Topic::VehicleStatus,
            Self::BatteryStatus { .. } => Topic::BatteryStatus,
            Self::RailPosition { .. } => Topic::RailPosition,
            Self::Lift { .. } => Topic::Lift,
            Self::Formation { .. } => Topic::Formation,
            Self::Adaptation { .. } => Topic::Adaptation,
            Self::Fault { .. } => Topic::Fault,
            Self::VehicleAttitudeSetpoint { .. } => Topic::VehicleAttitudeSetpoint,
            Self::VehicleRatesSetpoint { .. } => Topic::VehicleRatesSetpoint,
            Self::ManualControlSetpoint { .. } => Topic::ManualControlSetpoint,
            Self::ManualControlSwitches { .. } => Topic::ManualControlSwitches,
        }
    }

    /// The record's time, us.
    pub fn timestamp(&self) -> u64 {
        match *self {
            Self::SensorCombined { timestamp, .. }
            | Self::VehicleAttitude { timestamp, .. }
            | Self::VehicleAngularVelocity { timestamp, .. }
            | Self::VehicleLocalPosition { timestamp, .. }
            | Self::VehicleMocapOdometry { timestamp, .. }
            | Self::ActuatorOutputs { timestamp, .. }
            | Self::VehicleStatus { timestamp, .. }
            | Self::BatteryStatus { timestamp, .. }
            | Self::RailPosition { timestamp, .. }
            | Self::Lift { timestamp, .. }
            | Self::Formation { timestamp, .. }
            | Self::Adaptation { timestamp, .. }
            | Self::Fault { timestamp, .. }
            | Self::VehicleAttitudeSetpoint { timestamp, .. }
            | Self::VehicleRatesSetpoint { timestamp, .. }
            | Self::ManualControlSetpoint { timestamp, .. }
            | Self::ManualControlSwitches { timestamp, .. } => timestamp,
        }
    }

    /// The record's fields packed as its topic's format lists them.
    pub fn pack(&self) -> Packed {
        let mut m = self.message();
        let bytes = m.message().unwrap_or_default();
        Vec::from_slice(bytes.get(5..).unwrap_or_default()).unwrap_or_default()
    }

    /// The record as its ULog data message, in a buffer of its own.
    pub fn message(&self) -> DataMessage {
        let mut m = DataMessage::data(self.topic().msg_id());
        self.pack_fields(&mut m);
        m
    }

    /// Builds the record's ULog data message in `window` (the control step's: where the
    /// log's bytes are gathered): its length.
    #[inline]
    pub fn write_message(&self, window: &mut [u8; MESSAGE_BYTES]) -> usize {
        let mut m = Packer::data_in(window, self.topic().msg_id());
        self.pack_fields(&mut m);
        // Every record fits MESSAGE_BYTES (a test packs each).
        m.finish().unwrap_or(0)
    }

    /// Packs the record's fields after the message id.
    #[inline(always)]
    fn pack_fields<B: AsMut<[u8]>>(&self, m: &mut Packer<B>) {
        let p = m.u64(self.timestamp());
        match *self {
            Self::SensorCombined {
                gyro_rad,
                accelerometer_m_s2,
                integral_dt,
                ..
            } => p
                .f32s(&gyro_rad)
                .u32(integral_dt)
                .i32(0)
                .f32s(&accelerometer_m_s2)
                .u32(integral_dt),
            Self::VehicleAttitude { timestamp, q } => p.u64(timestamp).f32s(&q),
            Self::VehicleAngularVelocity { timestamp, xyz } => p.u64(timestamp).f32s(&xyz),
            Self::VehicleLocalPosition {
                timestamp,
                valid,
                position,
                velocity,
            } => {
                let v = u8::from(valid);
                p.u64(timestamp)
                    .u8(v)
                    .u8(v)
                    .u8(v)
                    .u8(v)
                    .f32s(&position)
                    .f32s(&velocity)
            }
            Self::VehicleMocapOdometry {
                timestamp_sample,
                position,
                q,
                ..
            } => p.u64(timestamp_sample).f32s(&position).f32s(&q),
            Self::ActuatorOutputs {
                noutputs, output, ..
            } => p.u32(noutputs).f32s(&output),
            Self::VehicleStatus {
                armed,
                nav_state,
                mission_phase,
                ..
            } => p
                // PX4's arming_state: 1 disarmed, 2 armed.
                .u8(if armed { 2 } else { 1 })
                .u8(nav_state)
                .u8(mission_phase),
            Self::BatteryStatus {
                voltage_v, warning, ..
            } => p
                .u8(u8::from(voltage_v.is_some()))
                .f32(voltage_v.unwrap_or(0.0))
                .u8(warning),
            Self::RailPosition {
                robots,
                commanded_m,
                ..
            } => p.u8(robots).f32s(&commanded_m),
            Self::Lift {
                pair,
                information_nats,
                thrust_n,
                lifts,
                theta,
                confidence,
                spread,
                model_n,
                ..
            } => p
                .u8(pair)
                .f32(information_nats)
                .u8(u8::from(thrust_n.is_some()))
                .f32(thrust_n.unwrap_or(f32::NAN))
                .u32(lifts)
                .f32s(&theta)
                .f32(confidence)
                .f32s(&spread)
                .f32(model_n),
            Self::Formation {
                robots,
                position_m,
                det_bbt,
                in_flight,
                ..
            } => p
                .u8(robots)
                .f32s(&position_m)
                .f32(det_bbt)
                .u8(u8::from(in_flight)),
            Self::Adaptation {
                event,
                com_mass,
                duration_s,
                ..
            } => p.u8(event).f32s(&com_mass).f32(duration_s),
            Self::Fault {
                rotors_out,
                stalled_robots,
                imu,
                imu_dropped,
                gcs_link,
                battery_warning,
                ..
            } => p
                .u16(rotors_out)
                .u16(stalled_robots)
                .u8(u8::from(imu))
                .u8(u8::from(imu_dropped))
                .u8(u8::from(gcs_link))
                .u8(battery_warning),
            Self::VehicleAttitudeSetpoint {
                q_d, thrust_body, ..
            } => p.f32s(&q_d).f32s(&thrust_body),
            Self::VehicleRatesSetpoint {
                rate, thrust_body, ..
            } => p.f32s(&rate).f32s(&thrust_body),
            Self::ManualControlSetpoint {
                valid,
                data_source,
                sticks,
                ..
            } => p.u8(u8::from(valid)).u8(data_source).f32s(&sticks),
            Self::ManualControlSwitches {
                mode_slot,
                kill_switch,
                ..
            } => p.u8(mode_slot).u8(kill_switch),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The packed size a format describes.
    fn format_size(format: &str) -> usize {
        let fields = format.split_once(':').expect("a name").1;
        fields
            .split(';')
            .map(|field| {
                let kind = field.split(' ').next().expect("a type");
                let (base, count) = match kind.split_once('[') {
                    Some((b, n)) => (b, n.trim_end_matches(']').parse::<usize>().expect("n")),
                    None => (kind, 1),
                };
                let size = match base {
                    "uint64_t" | "int64_t" | "double" => 8,
                    "uint32_t" | "int32_t" | "float" => 4,
                    "uint16_t" | "int16_t" => 2,
                    "uint8_t" | "int8_t" | "bool" | "char" => 1,
                    other => panic!("unknown type {other} in {format}"),
                };
                size * count
            })
            .sum()
    }

    fn one_of_each() -> [Record; 17] {
        let t = 1_000;
        [
            Record::SensorCombined {
                timestamp: t,
                gyro_rad: [0.1, 0.2, 0.3],
                accelerometer_m_s2: [0.0, 0.0, -9.8],
                integral_dt: 2500,
            },
            Record::VehicleAttitude {
                timestamp: t,
                q: [1.0, 0.0, 0.0, 0.0],
            },
            Record::VehicleAngularVelocity {
                timestamp: t,
                xyz: [0.0; 3],
            },
            Record::VehicleLocalPosition {
                timestamp: t,
                valid: true,
                position: [1.0, 2.0, -3.0],
                velocity: [0.0; 3],
            },
            Record::VehicleMocapOdometry {
                timestamp: t,
                timestamp_sample: t - 10,
                position: [0.0; 3],
                q: [1.0, 0.0, 0.0, 0.0],
            },
            Record::ActuatorOutputs {
                timestamp: t,
                noutputs: 8,
                output: [0.5; MAX_ROBOTS],
            },
            Record::VehicleStatus {
                timestamp: t,
                armed: true,
                nav_state: 3,
                mission_phase: 9,
            },
            Record::BatteryStatus {
                timestamp: t,
                voltage_v: Some(15.8),
                warning: 0,
            },
            Record::RailPosition {
                timestamp: t,
                robots: 8,
                commanded_m: [0.25; MAX_ROBOTS],
            },
            Record::Lift {
                timestamp: t,
                pair: 10,
                information_nats: 1.5,
                thrust_n: Some(6.7),
                lifts: 1,
                theta: [0.2, 0.0, 3.3],
                confidence: 0.5,
                spread: [0.02, 0.01, 0.05],
                model_n: 6.6,
            },
            Record::Formation {
                timestamp: t,
                robots: 8,
                position_m: [0.5; MAX_ROBOTS],
                det_bbt: 3.8e-3,
                in_flight: false,
            },
            Record::Adaptation {
                timestamp: t,
                event: 0,
                com_mass: [0.1, 0.0, 3.3],
                duration_s: f32::NAN,
            },
            Record::Fault {
                timestamp: t,
                rotors_out: 1 << 3,
                stalled_robots: 0,
                imu: false,
                imu_dropped: false,
                gcs_link: true,
                battery_warning: 1,
            },
            Record::VehicleAttitudeSetpoint {
                timestamp: t,
                q_d: [1.0, 0.0, 0.0, 0.0],
                thrust_body: [0.0, 0.0, -0.45],
            },
            Record::VehicleRatesSetpoint {
                timestamp: t,
                rate: [0.1, -0.1, 0.0],
                thrust_body: [0.0, 0.0, -0.45],
            },
            Record::ManualControlSetpoint {
                timestamp: t,
                valid: true,
                data_source: 0,
                sticks: [0.0, 0.5, 0.0, 0.0],
            },
            Record::ManualControlSwitches {
                timestamp: t,
                mode_slot: 2,
                kill_switch: 3,
            },
        ]
    }

    #[test]
    fn every_record_packs_to_the_size_its_format_describes() {
        for record in one_of_each() {
            let topic = record.topic();
            let packed = record.pack();
            assert_eq!(
                packed.len(),
                format_size(topic.format()),
                "{}: packed {} bytes",
                topic.name(),
                packed.len()
            );
            assert_eq!(packed[..8], 1_000u64.to_le_bytes(), "{}", topic.name());
        }
    }

    #[test]
    fn topics_have_distinct_ids_and_names_and_fit_a_message() {
        for (i, t) in Topic::ALL.iter().enumerate() {
            assert_eq!(usize::from(t.msg_id()), i);
            assert!(t.format().starts_with(t.name()));
            assert!(t.format().contains(":uint64_t timestamp;"));
            assert!(crate::ulog::Message::format(t.format()).is_ok());
            assert!(!t.format().contains("; ") && !t.format().contains("  "));
            for other in &Topic::ALL[i + 1..] {
                assert_ne!(t.name(), other.name());
            }
        }
    }
}
