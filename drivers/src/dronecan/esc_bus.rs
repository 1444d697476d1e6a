//! The flight controller's side of a bus of DroneCAN ESCs, as PX4's `uavcan` module runs it:
//! one `RawCommand` a control step for every rotor (ESC index `j` is robot `j + 1`'s rotor,
//! the RawCommand's `j`-th command), each ESC's `Status` read by the ESC index it carries, and
//! the nodes' `NodeStatus` heartbeats. What it tells the rotor monitor: each rotor's RPM
//! while its ESC's Status is fresh, and which ESCs have gone silent or say they failed.
//!
//! An ESC's node ID is its own setting (PX4 leaves it to the ESC, or to dynamic node
//! allocation); the bus learns which node is which ESC from the Status each node sends, and
//! reads a node's `NodeStatus` (health, mode) as its ESC's. This node's own ID is the
//! parameter `UAVCAN_NODE_ID` (PX4's, default 1).

use super::bits::OutOfRoom;
use super::esc::{
    EscStatus, RAW_COMMAND_ID, RAW_COMMAND_SIGNATURE, STATUS_BYTES, STATUS_ID, STATUS_SIGNATURE,
    encode_raw_command, raw_command,
};
use super::node_status::{
    Health, Mode, NODE_STATUS_ID, NODE_STATUS_SIGNATURE, NodeStatus, OFFLINE_TIMEOUT_US,
};
use super::transfer::{CanFrame, FrameError, MAX_PAYLOAD, MessageId, Reassembler, frames};

/// ESCs one bus serves (one per robot).
pub const MAX_ESCS: usize = 16;

/// The priority of the flight controller's `RawCommand`, PX4's
/// `UAVCAN_COMMAND_TRANSFER_PRIORITY` (0 highest, 31 lowest).
pub const COMMAND_PRIORITY: u8 = 5;
/// The priority of the flight controller's `NodeStatus`: DroneCAN's default, 16.
pub const NODE_STATUS_PRIORITY: u8 = 16;

/// An ESC's RPM counts for this long after its Status, us: three Status periods at
/// [`super::bus_load::STATUS_HZ`], so one lost Status does not blank it.
pub const RPM_MAX_AGE_US: u64 = 60_000;
/// An ESC heard before and silent this long has failed, us: five Status periods.
pub const SILENT_AFTER_US: u64 = 100_000;

/// What one ESC last said.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EscReading {
    /// Its last Status.
    pub status: EscStatus,
    /// The node that sent it.
    pub node: u8,
    /// When it came, us.
    pub time_us: u64,
    /// The node's last heartbeat and when, if one came.
    pub heartbeat: Option<(NodeStatus, u64)>,
}

/// What a frame brought, when it ended a transfer the bus reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Heard {
    /// An ESC's Status (by its ESC index).
    Status(u8),
    /// A node's heartbeat.
    NodeStatus(u8),
    /// A transfer of a data type the bus does not read.
    Other,
}

/// Frames refused, by what was wrong.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameErrors {
    /// Out of order, repeated, or of an unseen start (toggle, transfer ID, no start).
    pub order: u32,
    /// CRC failures.
    pub crc: u32,
    /// Empty, too long, short, not a message, or a payload that did not decode.
    pub malformed: u32,
    /// A Status whose ESC index is past [`MAX_ESCS`].
    pub unknown_esc: u32,
}

/// The bus.
pub struct EscBus {
    own_node: u8,
    /// One slot per ESC, each the size of a Status (the only multi-frame transfer it reads).
    rx: Reassembler<MAX_ESCS, STATUS_BYTES>,
    escs: [Option<EscReading>; MAX_ESCS],
    command_transfer: u8,
    heartbeat_transfer: u8,
    errors: FrameErrors,
}

impl EscBus {
    /// A bus on which this flight controller is node `own_node` (1 to 127).
    pub const fn new(own_node: u8) -> Self {
        Self {
            own_node: if own_node < 1 {
                1
            } else if own_node > 127 {
                127
            } else {
                own_node
            },
            rx: Reassembler::new(),
            escs: [None; MAX_ESCS],
            command_transfer: 0,
            heartbeat_transfer: 0,
            errors: FrameErrors {
                order: 0,
                crc: 0,
                malformed: 0,
                unknown_esc: 0,
            },
        }
    }

    /// This node's ID on the bus.
    pub fn own_node(&self) -> u8 {
        self.own_node
    }

    /// Frames refused so far.
    pub fn errors(&self) -> FrameErrors {
        self.errors
    }

    /// ESC `index`'s last Status and heartbeat, if it has spoken.
    pub fn esc(&self, index: usize) -> Option<&EscReading> {
        self.escs.get(index)?.as_ref()
    }

    /// Takes one frame received at `now_us`.
    pub fn receive(&mut self, frame: &CanFrame, now_us: u64) -> Result<Option<Heard>, FrameError> {
        let Some(id) = MessageId::from_can_id(frame.id) else {
            self.errors.malformed += 1;
            return Err(FrameError::NotAMessage);
        };
        let signature = match id.data_type {
            STATUS_ID => STATUS_SIGNATURE,
            NODE_STATUS_ID => NODE_STATUS_SIGNATURE,
            _ => return Ok(Some(Heard::Other)),
        };
        let transfer = match self.rx.accept(frame, signature, now_us) {
            Ok(Some(t)) => t,
            Ok(None) => return Ok(None),
            Err(e) => {
                match e {
                    FrameError::Crc => self.errors.crc += 1,
                    FrameError::Toggle | FrameError::TransferId | FrameError::NoStart => {
                        self.errors.order += 1
                    }
                    _ => self.errors.malformed += 1,
                }
                return Err(e);
            }
        };
        let source = transfer.id.source;
        if id.data_type == STATUS_ID {
            let Some(status) = EscStatus::decode(transfer.payload()) else {
                self.errors.malformed += 1;
                return Err(FrameError::Short);
            };
            let Some(slot) = self.escs.get_mut(usize::from(status.esc_index)) else {
                self.errors.unknown_esc += 1;
                return Ok(None);
            };
            let heartbeat = slot.filter(|r| r.node == source).and_then(|r| r.heartbeat);
            *slot = Some(EscReading {
                status,
                node: source,
                time_us: now_us,
                heartbeat,
            });
            return Ok(Some(Heard::Status(status.esc_index)));
        }
        let Some(heartbeat) = NodeStatus::decode(transfer.payload()) else {
            self.errors.malformed += 1;
            return Err(FrameError::Short);
        };
        for reading in self.escs.iter_mut().flatten() {
            if reading.node == source {
                reading.heartbeat = Some((heartbeat, now_us));
            }
        }
        Ok(Some(Heard::NodeStatus(source)))
    }

    /// The frames of one `RawCommand` for the rotors' command fractions (`[0, 1]`, one per
    /// ESC index from 0, at most [`MAX_ESCS`]), each handed to `send`.
    pub fn command(
        &mut self,
        fractions: &[f32],
        mut send: impl FnMut(CanFrame),
    ) -> Result<(), OutOfRoom> {
        if fractions.len() > MAX_ESCS {
            return Err(OutOfRoom);
        }
        let mut commands = [0i16; MAX_ESCS];
        for (c, &f) in commands.iter_mut().zip(fractions) {
            *c = raw_command(f);
        }
        let mut payload = [0u8; MAX_PAYLOAD];
        let len = encode_raw_command(&commands[..fractions.len()], &mut payload)?;
        let id = MessageId {
            priority: COMMAND_PRIORITY,
            data_type: RAW_COMMAND_ID,
            source: self.own_node,
        };
        frames(
            id,
            RAW_COMMAND_SIGNATURE,
            self.command_transfer,
            &payload[..len],
        )
        .for_each(&mut send);
        self.command_transfer = (self.command_transfer + 1) & 0x1f;
        Ok(())
    }

    /// The frame of this node's `NodeStatus` (once a second).
    pub fn heartbeat(&mut self, uptime_sec: u32, health: Health, mode: Mode) -> CanFrame {
        let status = NodeStatus {
            uptime_sec,
            health,
            mode,
            sub_mode: 0,
            vendor_specific_status_code: 0,
        };
        let mut payload = [0u8; MAX_PAYLOAD];
        let len = status.encode(&mut payload).unwrap_or(0);
        let id = MessageId {
            priority: NODE_STATUS_PRIORITY,
            data_type: NODE_STATUS_ID,
            source: self.own_node,
        };
        let frame = frames(
            id,
            NODE_STATUS_SIGNATURE,
            self.heartbeat_transfer,
            &payload[..len],
        )
        .next()
        .unwrap_or(CanFrame {
            id: id.to_can_id(),
            data: [0; 8],
            len: 0,
        });
        self.heartbeat_transfer = (self.heartbeat_transfer + 1) & 0x1f;
        frame
    }

    /// Each ESC's RPM at `now_us`: NaN for one not heard from within [`RPM_MAX_AGE_US`].
    pub fn rpm_at(&self, now_us: u64) -> [f32; MAX_ESCS] {
        core::array::from_fn(|j| match &self.escs[j] {
            Some(r) if now_us.saturating_sub(r.time_us) <= RPM_MAX_AGE_US => r.status.rpm as f32,
            _ => f32::NAN,
        })
    }

    /// The ESCs among the first `escs` that have failed at `now_us`, bit `j` for ESC `j`:
    /// silent for [`SILENT_AFTER_US`] after speaking, or whose node's heartbeat (fresh
    /// within DroneCAN's offline timeout) says a major or fatal failure or that it is
    /// going offline. An ESC never heard from is not in it (see [`Self::unheard`]).
    pub fn failed(&self, escs: usize, now_us: u64) -> u16 {
        let mut bits = 0;
        for (j, reading) in self.escs.iter().enumerate().take(escs.min(MAX_ESCS)) {
            let Some(r) = reading else { continue };
            let silent = now_us.saturating_sub(r.time_us) > SILENT_AFTER_US;
            let says_failed = r.heartbeat.is_some_and(|(h, at)| {
                now_us.saturating_sub(at) <= OFFLINE_TIMEOUT_US
                    && (matches!(h.health, Health::Error | Health::Critical)
                        || h.mode == Mode::Offline)
            });
            if silent || says_failed {
                bits |= 1 << j;
            }
        }
        bits
    }

    /// The ESCs among the first `escs` never heard from, bit `j` for ESC `j`: not on the bus,
    /// or not set to its robot's ESC index.
    pub fn unheard(&self, escs: usize) -> u16 {
        let mut bits = 0;
        for (j, reading) in self.escs.iter().enumerate().take(escs.min(MAX_ESCS)) {
            if reading.is_none() {
                bits |= 1 << j;
            }
        }
        bits
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dronecan::esc::decode_raw_command;
    use std::vec::Vec;

    /// The frames ESC `index` (node `20 + index`) sends for a Status with `rpm`.
    fn status_frames(index: u8, rpm: i32, transfer: u8) -> Vec<CanFrame> {
        let status = EscStatus {
            error_count: 0,
            voltage: 15.8,
            current: 6.0,
            temperature: 310.0,
            rpm,
            power_rating_pct: 40,
            esc_index: index,
        };
        let mut sent = Vec::new();
        status.send(20 + index, transfer, |f| sent.push(f));
        sent
    }

    fn heartbeat_frame(node: u8, health: Health, mode: Mode) -> CanFrame {
        let mut payload = [0u8; MAX_PAYLOAD];
        let len = NodeStatus {
            uptime_sec: 9,
            health,
            mode,
            sub_mode: 0,
            vendor_specific_status_code: 0,
        }
        .encode(&mut payload)
        .expect("fits");
        let id = MessageId {
            priority: 16,
            data_type: NODE_STATUS_ID,
            source: node,
        };
        frames(id, NODE_STATUS_SIGNATURE, 0, &payload[..len])
            .next()
            .expect("a frame")
    }

    fn hear(bus: &mut EscBus, frames: &[CanFrame], now_us: u64) -> Option<Heard> {
        let mut heard = None;
        for f in frames {
            heard = bus.receive(f, now_us).expect("good frames");
        }
        heard
    }

    #[test]
    fn sixteen_escs_report_their_rpm_by_esc_index_until_it_is_stale() {
        let mut bus = EscBus::new(1);
        assert_eq!(bus.unheard(16), 0xffff);
        for j in 0..16u8 {
            let heard = hear(&mut bus, &status_frames(j, 7000 + i32::from(j), 0), 1_000);
            assert_eq!(heard, Some(Heard::Status(j)));
        }
        assert_eq!(bus.unheard(16), 0);
        let rpm = bus.rpm_at(1_000 + RPM_MAX_AGE_US);
        for (j, r) in rpm.iter().enumerate() {
            assert_eq!(*r, 7000.0 + j as f32);
        }
        assert!(
            bus.rpm_at(1_001 + RPM_MAX_AGE_US)
                .iter()
                .all(|r| r.is_nan())
        );
        assert_eq!(bus.esc(3).map(|r| r.node), Some(23));
    }

    #[test]
    fn an_esc_that_goes_silent_or_says_it_failed_is_named() {
        let mut bus = EscBus::new(1);
        for j in 0..8u8 {
            hear(&mut bus, &status_frames(j, 7000, 0), 0);
        }
        // ESCs 0-7 keep talking but 2 and 5; 6's node says a fatal failure.
        for j in [0u8, 1, 3, 4, 6, 7] {
            hear(&mut bus, &status_frames(j, 7000, 1), 80_000);
        }
        hear(
            &mut bus,
            &[heartbeat_frame(26, Health::Critical, Mode::Operational)],
            80_000,
        );
        assert_eq!(bus.failed(8, 80_000), 1 << 6, "silent 80 ms: not yet");
        assert_eq!(bus.failed(8, 100_001), 1 << 2 | 1 << 5 | 1 << 6);
        assert_eq!(bus.failed(4, 100_001), 1 << 2, "only the robots in use");
        // An operational heartbeat clears 6; a node going offline counts too.
        hear(
            &mut bus,
            &[heartbeat_frame(26, Health::Ok, Mode::Operational)],
            90_000,
        );
        hear(
            &mut bus,
            &[heartbeat_frame(21, Health::Ok, Mode::Offline)],
            90_000,
        );
        assert_eq!(bus.failed(8, 95_000), 1 << 1);
    }

    #[test]
    fn the_command_carries_each_rotors_fraction_in_esc_index_order() {
        let mut bus = EscBus::new(1);
        let fractions: Vec<f32> = (0..16).map(|j| j as f32 / 16.0).collect();
        let mut sent = Vec::new();
        bus.command(&fractions, |f| sent.push(f)).expect("16 fit");
        assert_eq!(sent.len(), 5);
        let mut rx = Reassembler::<1>::new();
        let mut payload = None;
        for f in &sent {
            payload = rx.accept(f, RAW_COMMAND_SIGNATURE, 0).expect("in order");
        }
        let t = payload.expect("whole");
        assert_eq!(t.id.priority, COMMAND_PRIORITY);
        assert_eq!((t.id.source, t.transfer_id), (1, 0));
        let mut commands = [0i16; 20];
        assert_eq!(decode_raw_command(t.payload(), &mut commands), 16);
        for (j, c) in commands[..16].iter().enumerate() {
            assert_eq!(*c, raw_command(j as f32 / 16.0));
        }
        let mut next = Vec::new();
        bus.command(&fractions[..4], |f| next.push(f))
            .expect("4 fit");
        assert_eq!(next.len(), 1);
        assert_eq!(
            next[0].bytes().last().map(|t| t & 0x1f),
            Some(1),
            "next transfer"
        );
        assert!(bus.command(&[0.5; 17], |_| {}).is_err(), "17 ESCs");
    }

    #[test]
    fn bad_frames_are_counted_by_what_was_wrong_and_change_nothing() {
        let mut bus = EscBus::new(1);
        let good = status_frames(4, 6500, 3);
        let mut corrupt = good.clone();
        corrupt[1].data[0] ^= 1;
        for f in &corrupt {
            let _ = bus.receive(f, 0);
        }
        let _ = bus.receive(&good[2], 0);
        for f in &status_frames(17, 6500, 3) {
            let _ = bus.receive(f, 0);
        }
        let errors = bus.errors();
        assert_eq!((errors.crc, errors.order, errors.unknown_esc), (1, 1, 1));
        assert!(bus.esc(4).is_none());
        let other = CanFrame {
            id: MessageId {
                priority: 16,
                data_type: 1063,
                source: 40,
            }
            .to_can_id(),
            data: [0xc0, 0, 0, 0, 0, 0, 0, 0],
            len: 1,
        };
        assert_eq!(bus.receive(&other, 0), Ok(Some(Heard::Other)));
        let own = bus.heartbeat(12, Health::Ok, Mode::Operational);
        assert_eq!(
            MessageId::from_can_id(own.id).map(|m| m.data_type),
            Some(NODE_STATUS_ID)
        );
    }
}
