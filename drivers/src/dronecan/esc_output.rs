//! What the flight controller puts on the ESCs' CAN bus, and what it takes from it, while
//! `ESC_PROTOCOL` is DroneCAN (docs/hardware.md#can-escs): the core of the firmware's CAN
//! task, so that every decision it makes is host-tested.
//!
//! Each update (a control step's command, or the feed timeout) sends one `RawCommand` for the
//! payload's rotors, in ESC-index order: the command while armed, zeros (stop, as PX4's
//! `UavcanEscController` sends) while disarmed or when the control step has stopped feeding
//! it, as [`crate::esc_gate::EscGate`] decides for the FMU outputs. Once a second the node's
//! own `NodeStatus` goes out. With another protocol in force the bus stays quiet and reports
//! no RPM and no failed ESC: the FMU outputs drive the rotors then.

use super::esc_bus::{EscBus, MAX_ESCS};
use super::node_status::{Health, Mode};
use super::transfer::{CanFrame, FrameError};
use crate::esc_gate::{EscCommand, EscGate};
use crate::pulse::EscProtocol;

/// The node's `NodeStatus` period, us (DroneCAN's default: once a second).
pub const HEARTBEAT_PERIOD_US: u64 = 1_000_000;

/// One control step's command to the CAN ESCs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CanEscCommand {
    /// The protocol, the fractions (`[0, 1]`, robot `j` at `j`) and whether armed.
    pub command: EscCommand<MAX_ESCS>,
    /// The payload's rotors: the first this many fractions go out.
    pub escs: usize,
}

/// The flight controller's side of the CAN ESCs, with the protocol gate.
pub struct CanEscOutput {
    bus: EscBus,
    gate: EscGate,
    escs: usize,
    next_heartbeat_us: u64,
    started_us: Option<u64>,
}

impl CanEscOutput {
    /// Quiet (the protocol DShot600, as the FMU outputs start), this node `own_node`.
    pub const fn new(own_node: u8) -> Self {
        Self {
            bus: EscBus::new(own_node),
            gate: EscGate::new(EscProtocol::Dshot600),
            escs: 0,
            next_heartbeat_us: 0,
            started_us: None,
        }
    }

    /// Whether DroneCAN is the protocol in force.
    pub fn active(&self) -> bool {
        self.gate.protocol() == EscProtocol::DroneCan
    }

    /// The bus (its ESCs' last words, its frame errors).
    pub fn bus(&self) -> &EscBus {
        &self.bus
    }

    /// One update at `now_us`, with the latest command or `None` when none came within the
    /// feed timeout: the frames to send, each handed to `send`. The protocol changes only
    /// while disarmed ([`EscGate`]).
    pub fn update(
        &mut self,
        command: Option<&CanEscCommand>,
        now_us: u64,
        mut send: impl FnMut(CanFrame),
    ) {
        let started = *self.started_us.get_or_insert(now_us);
        let update = self.gate.update(command.map(|c| &c.command));
        if let Some(c) = command
            && c.command.protocol == self.gate.protocol()
        {
            self.escs = c.escs.min(MAX_ESCS);
        }
        if !self.active() {
            return;
        }
        // Sixteen fractions fit a RawCommand: this cannot fail.
        let _ = self.bus.command(&update.fractions[..self.escs], &mut send);
        if now_us >= self.next_heartbeat_us {
            self.next_heartbeat_us = now_us + HEARTBEAT_PERIOD_US;
            let uptime = ((now_us - started) / 1_000_000) as u32;
            send(self.bus.heartbeat(uptime, Health::Ok, Mode::Operational));
        }
    }

    /// Takes one frame received at `now_us` (read whatever the protocol, so the ESCs are known
    /// before the switch).
    pub fn receive(&mut self, frame: &CanFrame, now_us: u64) -> Result<(), FrameError> {
        self.bus.receive(frame, now_us).map(|_| ())
    }

    /// Each rotor's RPM at `now_us` from its ESC's Status (NaN for one not heard within
    /// [`super::esc_bus::RPM_MAX_AGE_US`]); `None` unless DroneCAN is in force.
    pub fn rpm(&self, now_us: u64) -> Option<[f32; MAX_ESCS]> {
        self.active().then(|| self.bus.rpm_at(now_us))
    }

    /// The payload's ESCs that went silent or say they failed, bit `j` for robot `j + 1`; none
    /// unless DroneCAN is in force.
    pub fn failed(&self, now_us: u64) -> u16 {
        if self.active() {
            self.bus.failed(self.escs, now_us)
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::super::esc::{
        EscStatus, RAW_COMMAND_ID, RAW_COMMAND_SIGNATURE, decode_raw_command, raw_command,
    };
    use super::super::node_status::NODE_STATUS_ID;
    use super::super::transfer::{MessageId, Reassembler};
    use super::*;
    use std::vec::Vec;

    fn command(protocol: EscProtocol, armed: bool, escs: usize) -> CanEscCommand {
        let mut fractions = [0.0; MAX_ESCS];
        for (j, f) in fractions.iter_mut().enumerate() {
            *f = 0.05 * (j + 1) as f32;
        }
        CanEscCommand {
            command: EscCommand {
                protocol,
                fractions,
                armed,
            },
            escs,
        }
    }

    /// The frames of one update, sorted by data type: the RawCommand's commands, decoded
    /// through a reassembler, and whether a NodeStatus went out.
    fn sent(
        out: &mut CanEscOutput,
        c: Option<&CanEscCommand>,
        now_us: u64,
    ) -> (Option<Vec<i16>>, bool) {
        let mut frames = Vec::new();
        out.update(c, now_us, |f| frames.push(f));
        let mut rx = Reassembler::<1>::new();
        let (mut commands, mut heartbeat) = (None, false);
        for f in &frames {
            let id = MessageId::from_can_id(f.id).expect("a message");
            assert_eq!(id.source, 7, "sent as this node");
            if id.data_type == NODE_STATUS_ID {
                heartbeat = true;
                continue;
            }
            assert_eq!(id.data_type, RAW_COMMAND_ID);
            if let Some(t) = rx.accept(f, RAW_COMMAND_SIGNATURE, now_us).expect("whole") {
                let mut raw = [0i16; MAX_ESCS];
                let n = decode_raw_command(t.payload(), &mut raw);
                commands = Some(raw[..n].to_vec());
            }
        }
        (commands, heartbeat)
    }

    #[test]
    fn armed_on_dronecan_each_update_commands_the_payloads_rotors_and_a_heartbeat_goes_each_second()
    {
        let mut out = CanEscOutput::new(7);
        // Switched to DroneCAN while disarmed: zeros for the twelve ESCs, and a heartbeat.
        let disarmed = command(EscProtocol::DroneCan, false, 12);
        let (zeros, heartbeat) = sent(&mut out, Some(&disarmed), 0);
        assert_eq!(zeros.as_deref(), Some(&[0i16; 12][..]));
        assert!(heartbeat && out.active());
        let armed = command(EscProtocol::DroneCan, true, 12);
        let (commands, heartbeat) = sent(&mut out, Some(&armed), 2_500);
        let expected: Vec<i16> = (0..12)
            .map(|j| raw_command(0.05 * (j + 1) as f32))
            .collect();
        assert_eq!(commands, Some(expected));
        assert!(!heartbeat, "one heartbeat a second");
        let (_, heartbeat) = sent(&mut out, Some(&armed), 1_000_000);
        assert!(heartbeat);
        // The control step stopped feeding: stop, every update.
        let (stopped, _) = sent(&mut out, None, 1_002_500);
        assert_eq!(stopped.as_deref(), Some(&[0i16; 12][..]));
    }

    #[test]
    fn with_another_protocol_the_bus_stays_quiet_and_the_protocol_changes_only_disarmed() {
        let mut out = CanEscOutput::new(7);
        let dshot = command(EscProtocol::Dshot600, true, 8);
        assert_eq!(sent(&mut out, Some(&dshot), 0), (None, false));
        assert_eq!(out.rpm(0), None);
        // Asked for DroneCAN while armed: not taken, still quiet.
        let can_armed = command(EscProtocol::DroneCan, true, 8);
        assert_eq!(sent(&mut out, Some(&can_armed), 2_500), (None, false));
        assert!(!out.active());
        let (zeros, _) = sent(
            &mut out,
            Some(&command(EscProtocol::DroneCan, false, 8)),
            5_000,
        );
        assert_eq!(zeros.as_deref(), Some(&[0i16; 8][..]));
        // And back to PWM, disarmed: quiet again, no RPM, no failed ESC reported.
        let pwm = command(EscProtocol::Pwm, false, 8);
        assert_eq!(sent(&mut out, Some(&pwm), 7_500), (None, false));
        assert_eq!(out.rpm(7_500), None);
        assert_eq!(out.failed(10_000_000), 0);
    }

    #[test]
    fn an_escs_status_gives_its_rotors_rpm_and_its_silence_names_it_failed() {
        let mut out = CanEscOutput::new(1);
        let c = command(EscProtocol::DroneCan, false, 4);
        out.update(Some(&c), 0, |_| {});
        let status = |index: u8, rpm: i32| EscStatus {
            error_count: 0,
            voltage: 15.8,
            current: 2.0,
            temperature: 310.0,
            rpm,
            power_rating_pct: 40,
            esc_index: index,
        };
        for j in 0..4u8 {
            status(j, 4_000 + i32::from(j)).send(20 + j, 0, |f| {
                out.receive(&f, 10_000).expect("taken");
            });
        }
        let rpm = out.rpm(20_000).expect("DroneCAN in force");
        assert_eq!(&rpm[..4], &[4_000.0, 4_001.0, 4_002.0, 4_003.0]);
        assert!(rpm[4].is_nan(), "no fifth ESC");
        assert_eq!(out.failed(20_000), 0);
        // ESC 2 speaks again, the others fall silent: they are named once silent long enough.
        status(2, 4_100).send(22, 1, |f| out.receive(&f, 100_000).expect("taken"));
        assert_eq!(out.failed(150_000), 0b1011);
        // A frame that is no message is refused, saying so.
        let service = CanFrame {
            id: 0x80,
            data: [0xC0, 0, 0, 0, 0, 0, 0, 0],
            len: 1,
        };
        assert!(out.receive(&service, 150_000).is_err());
    }
}
