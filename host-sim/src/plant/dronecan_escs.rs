//! The plant's DroneCAN ESCs (`mission --esc dronecan`, docs/hardware.md#can-escs): one
//! simulated ESC node per robot on one 1 Mbit/s bus, each sending its rotor's `Status` at
//! [`STATUS_HZ`] (the ESCs' staggered by an even share of the period, as free-running
//! ESCs drift apart), and the flight controller's `RawCommand` each control step. The frames
//! are `drivers::dronecan`'s, read by its `EscBus` as the firmware reads them, so the rotor
//! monitor sees each RPM only when a Status brings it, held until the next. The bus's frames
//! are counted for its load.

use drivers::dronecan::bus_load::{BusLoad, STATUS_HZ};
use drivers::dronecan::esc::EscStatus;
use drivers::dronecan::esc_bus::{EscBus, MAX_ESCS};
use shared::mission::EscRpm;

/// The flight controller's node ID on the bus (PX4's `UAVCAN_NODE_ID` default).
pub const FLIGHT_CONTROLLER_NODE: u8 = 1;
/// ESC `j`'s node ID: 10 + j, as an ESC set up by hand (PX4 leaves the node ID to the ESC).
pub const FIRST_ESC_NODE: u8 = 10;

/// The pack's voltage and each ESC's temperature the Status report, for the frames' bits.
const REPORTED_VOLTS: f32 = 15.8;
const REPORTED_KELVIN: f32 = 310.0;

/// The ESCs and the flight controller's side of their bus.
pub struct DroneCanEscs {
    bus: EscBus,
    robots: usize,
    next_status_us: [u64; MAX_ESCS],
    transfer: [u8; MAX_ESCS],
    load: BusLoad,
    started_us: Option<u64>,
    now_us: u64,
}

impl DroneCanEscs {
    /// `robots` ESCs (at most 16).
    pub fn new(robots: usize) -> Self {
        let robots = robots.min(MAX_ESCS);
        let period = 1_000_000 / u64::from(STATUS_HZ);
        Self {
            bus: EscBus::new(FLIGHT_CONTROLLER_NODE),
            robots,
            next_status_us: std::array::from_fn(|j| j as u64 * period / robots.max(1) as u64),
            transfer: [0; MAX_ESCS],
            load: BusLoad::default(),
            started_us: None,
            now_us: 0,
        }
    }

    /// One control step at `now_us`: the flight controller's `RawCommand` for `commands`
    /// (fractions of full thrust), and a Status from each ESC whose turn it is, with its
    /// rotor's `rpm`. Each rotor's RPM as the flight controller has it after the step.
    pub fn step(&mut self, now_us: u64, commands: &[f32], rpm: &[f32]) -> EscRpm {
        self.started_us.get_or_insert(now_us);
        self.now_us = now_us;
        let n = self.robots.min(commands.len());
        let load = &mut self.load;
        let _ = self
            .bus
            .command(&commands[..n], |frame| load.add(&frame, 1));
        let period = 1_000_000 / u64::from(STATUS_HZ);
        for j in 0..self.robots {
            if now_us < self.next_status_us[j] {
                continue;
            }
            self.next_status_us[j] += period * (1 + (now_us - self.next_status_us[j]) / period);
            let r = rpm.get(j).copied().unwrap_or(0.0);
            let status = EscStatus {
                error_count: 0,
                voltage: REPORTED_VOLTS,
                current: f32::NAN,
                temperature: REPORTED_KELVIN,
                rpm: r.round() as i32,
                power_rating_pct: (100.0 * commands.get(j).copied().unwrap_or(0.0)) as u8,
                esc_index: j as u8,
            };
            let (load, bus) = (&mut self.load, &mut self.bus);
            status.send(FIRST_ESC_NODE + j as u8, self.transfer[j], |frame| {
                load.add(&frame, 1);
                let _ = bus.receive(&frame, now_us);
            });
            self.transfer[j] = (self.transfer[j] + 1) & 0x1f;
        }
        let mut out = [f32::NAN; shared::scenario::MAX_ROBOTS];
        for (o, r) in out.iter_mut().zip(self.bus.rpm_at(now_us)) {
            *o = r;
        }
        out
    }

    /// The ESCs that went silent or said they failed (bit `j`: robot `j + 1`).
    pub fn failed(&self) -> u16 {
        self.bus.failed(self.robots, self.now_us)
    }

    /// The bus's traffic so far: frames a second and the share of its bit rate.
    pub fn load(&self) -> (f32, f32) {
        let seconds = self
            .started_us
            .map_or(0.0, |s| (self.now_us.saturating_sub(s)) as f32 * 1e-6);
        if seconds <= 0.0 {
            return (0.0, 0.0);
        }
        (
            self.load.frames_per_second(seconds),
            self.load.share(seconds),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_rpm_arrives_with_its_escs_status_and_is_held_until_the_next() {
        let mut escs = DroneCanEscs::new(16);
        let commands = [0.45f32; 16];
        let mut rpm = [7000.0f32; 16];
        let mut first_seen = [None; 16];
        for tick in 0..400u64 {
            let now = tick * 2_500;
            if tick == 200 {
                rpm[5] = 0.0;
            }
            let got = escs.step(now, &commands, &rpm);
            for (j, seen) in first_seen.iter_mut().enumerate() {
                if seen.is_none() && got[j].is_finite() {
                    *seen = Some(now);
                }
            }
            if tick == 200 {
                assert_eq!(got[5], 7000.0, "held until ESC 6's next Status");
            }
        }
        // Every ESC heard within its first period, staggered.
        let period = 1_000_000 / u64::from(STATUS_HZ);
        assert!(first_seen.iter().all(|s| s.is_some_and(|t| t <= period)));
        assert!(first_seen[15] > first_seen[0]);
        assert_eq!(escs.step(400 * 2_500, &commands, &rpm)[5], 0.0);
        let (frames, share) = escs.load();
        assert!((4_000.0..4_500.0).contains(&frames), "{frames} frames/s");
        assert!((0.5..0.6).contains(&share), "{share}");
        assert_eq!(escs.failed(), 0);
    }
}
