//! The ground-station bridge of `hil --gcs udp:HOST:PORT`, as PX4's
//! HITL bridge does it: every MAVLink frame between the firmware and a ground station
//! (QGroundControl, MAVProxy, pymavlink) passes through, except the simulator's own HIL
//! messages, so the tool watches and commands the simulated vehicle.
//!
//! Frames from the firmware go to the given address, or to wherever the ground station last
//! spoke from. Frames from the ground station go to the firmware whole, between the plant's,
//! no faster than a radio link carries them (docs/ground-link.md#under-a-flood): the bridge
//! is a 921,600-baud link in real time with a 2 KiB buffer, and a frame that finds the buffer
//! full is dropped and counted, as a radio drops what it cannot carry.

use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow};
use link::MessageData;
use link::bandwidth::{LinkBudget, bytes_per_second};
use link::frame::Parser;
use link::msg::{
    ACTUATOR_OUTPUT_STATUS_DATA, ATT_POS_MOCAP_DATA, HIL_ACTUATOR_CONTROLS_DATA, HIL_SENSOR_DATA,
};
use link::vehicle::crc_extra;

use super::transport::{SharedWriter, write_frame};

/// Whether a message id belongs to the simulator's lockstep (never bridged).
pub fn is_hil(id: u32) -> bool {
    [
        HIL_SENSOR_DATA::ID,
        ATT_POS_MOCAP_DATA::ID,
        HIL_ACTUATOR_CONTROLS_DATA::ID,
        ACTUATOR_OUTPUT_STATUS_DATA::ID,
    ]
    .contains(&id)
}

/// The radio link's rate the bridge forwards a ground station's frames at, baud.
pub const GCS_BAUD: u32 = 921_600;
/// The radio's buffer: bytes the ground station may send ahead of the link's rate.
pub const GCS_BUFFER: u32 = 2048;

/// Frames from the ground station the bridge forwarded and dropped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GcsCounts {
    /// Forwarded to the firmware.
    pub forwarded: u64,
    /// Dropped: the radio's buffer was full.
    pub dropped: u64,
}

/// The counts, shared with the bridge's thread.
#[derive(Default)]
struct Counters {
    forwarded: AtomicU64,
    dropped: AtomicU64,
    /// When the ground station last sent anything, ms since the bridge started.
    heard_ms: AtomicU64,
}

/// A running bridge.
pub struct GcsBridge {
    counters: Arc<Counters>,
    started: Instant,
    socket: UdpSocket,
    peer: Arc<Mutex<SocketAddr>>,
    stop: Arc<AtomicBool>,
    /// The ground link is cut (`--inject gcs-loss`): nothing from the ground station passes.
    cut: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl GcsBridge {
    /// Parses `udp:HOST:PORT`.
    pub fn parse(text: &str) -> Result<SocketAddr, String> {
        let addr = text
            .strip_prefix("udp:")
            .ok_or_else(|| format!("`{text}` is not udp:HOST:PORT"))?;
        addr.to_socket_addrs()
            .ok()
            .and_then(|mut a| a.next())
            .ok_or_else(|| format!("`{text}` is not udp:HOST:PORT"))
    }

    /// Starts bridging between the firmware (`writer`) and the ground station at `ground`.
    pub fn start(ground: SocketAddr, writer: SharedWriter) -> Result<Self> {
        let bind = if ground.is_ipv4() {
            "0.0.0.0:0"
        } else {
            "[::]:0"
        };
        let socket =
            UdpSocket::bind(bind).context("cannot open the ground station's UDP socket")?;
        socket.set_read_timeout(Some(Duration::from_millis(100)))?;
        let peer = Arc::new(Mutex::new(ground));
        let stop = Arc::new(AtomicBool::new(false));
        let cut = Arc::new(AtomicBool::new(false));
        let counters = Arc::new(Counters::default());
        let started = Instant::now();
        let thread = {
            let socket = socket.try_clone()?;
            let peer = Arc::clone(&peer);
            let stop = Arc::clone(&stop);
            let cut = Arc::clone(&cut);
            let counters = Arc::clone(&counters);
            thread::spawn(move || {
                from_ground(&socket, &peer, &writer, &stop, &cut, &counters, started)
            })
        };
        Ok(Self {
            counters,
            started,
            socket,
            peer,
            stop,
            cut,
            thread: Some(thread),
        })
    }

    /// The local address the bridge sends from (and the ground station answers to).
    pub fn local_addr(&self) -> Result<SocketAddr> {
        self.socket.local_addr().map_err(|e| anyhow!(e))
    }

    /// Cuts the link from the ground station to the vehicle (`true`) or mends it: an injected
    /// loss of the ground link (what the ground station sends is dropped).
    pub fn cut(&self, cut: bool) {
        self.cut.store(cut, Ordering::Relaxed);
    }

    /// Frames from the ground station forwarded and dropped so far.
    pub fn counts(&self) -> GcsCounts {
        GcsCounts {
            forwarded: self.counters.forwarded.load(Ordering::Relaxed),
            dropped: self.counters.dropped.load(Ordering::Relaxed),
        }
    }

    /// How long since the ground station last sent anything (since the bridge started when
    /// it never has).
    pub fn silent_for(&self) -> Duration {
        let heard = Duration::from_millis(self.counters.heard_ms.load(Ordering::Relaxed));
        self.started.elapsed().saturating_sub(heard)
    }

    /// Sends one frame from the firmware to the ground station (HIL frames are skipped by the
    /// caller). A ground station that is not there loses nothing but the datagram.
    pub fn to_ground(&self, frame: &[u8]) {
        if let Ok(peer) = self.peer.lock() {
            let _ = self.socket.send_to(frame, *peer);
        }
    }
}

fn from_ground(
    socket: &UdpSocket,
    peer: &Mutex<SocketAddr>,
    writer: &SharedWriter,
    stop: &AtomicBool,
    cut: &AtomicBool,
    counters: &Counters,
    started: Instant,
) {
    let mut parser = Parser::new(crc_extra);
    // A whole datagram, however large.
    let mut buf = vec![0u8; 65_536];
    let mut radio = LinkBudget::new(bytes_per_second(GCS_BAUD), GCS_BUFFER, 0);
    while !stop.load(Ordering::Relaxed) {
        let Ok((n, from)) = socket.recv_from(&mut buf) else {
            continue;
        };
        if cut.load(Ordering::Relaxed) {
            continue;
        }
        if let Ok(mut p) = peer.lock() {
            *p = from;
        }
        let heard_ms = started.elapsed().as_millis() as u64;
        counters.heard_ms.store(heard_ms, Ordering::Relaxed);
        for &byte in &buf[..n] {
            let Some((frame, _)) = parser.push(byte) else {
                continue;
            };
            if is_hil(frame.message_id()) {
                continue;
            }
            let now_us = started.elapsed().as_micros() as u64;
            if !radio.take(frame.bytes().len(), now_us) {
                counters.dropped.fetch_add(1, Ordering::Relaxed);
                continue;
            }
            if write_frame(writer, frame.bytes()).is_err() {
                return;
            }
            counters.forwarded.fetch_add(1, Ordering::Relaxed);
        }
    }
}

impl Drop for GcsBridge {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_are_parsed_and_bad_ones_named() {
        assert!(GcsBridge::parse("udp:127.0.0.1:14550").is_ok());
        assert!(GcsBridge::parse("tcp:127.0.0.1:14550").is_err());
        assert!(GcsBridge::parse("udp:nowhere").is_err());
    }

    struct Collect(Arc<Mutex<Vec<u8>>>);

    impl std::io::Write for Collect {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0
                .lock()
                .map_err(|_| std::io::ErrorKind::Other)?
                .extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn frames_pass_both_ways_but_hil_ones_stay() -> Result<()> {
        use link::frame::{Encoder, Frame};
        let ground = UdpSocket::bind("127.0.0.1:0")?;
        ground.set_read_timeout(Some(Duration::from_secs(2)))?;
        let to_firmware = Arc::new(Mutex::new(Vec::new()));
        let writer: SharedWriter =
            Arc::new(Mutex::new(Box::new(Collect(Arc::clone(&to_firmware)))));
        let bridge = GcsBridge::start(ground.local_addr()?, writer)?;
        // Firmware to ground.
        let mut enc = Encoder::new(1, 1);
        let mut f = Frame::default();
        enc.encode(&link::msg::HEARTBEAT_DATA::default(), &mut f);
        bridge.to_ground(f.bytes());
        let mut buf = [0u8; 300];
        let (n, from) = ground.recv_from(&mut buf)?;
        assert_eq!(&buf[..n], f.bytes());
        // Ground to firmware: a HIL_SENSOR (dropped) then a heartbeat (passed).
        let mut gcs = Encoder::new(255, 190);
        let mut sensor = Frame::default();
        gcs.encode(&link::hil::PlantSample::AT_REST.to_message(), &mut sensor);
        let mut beat = Frame::default();
        gcs.encode(&link::msg::HEARTBEAT_DATA::default(), &mut beat);
        let mut datagram = sensor.bytes().to_vec();
        datagram.extend_from_slice(beat.bytes());
        ground.send_to(&datagram, from)?;
        let start = std::time::Instant::now();
        while to_firmware.lock().map(|v| v.is_empty()).unwrap_or(true)
            && start.elapsed() < Duration::from_secs(2)
        {
            thread::sleep(Duration::from_millis(10));
        }
        let got = to_firmware.lock().map(|v| v.clone()).unwrap_or_default();
        assert_eq!(got, beat.bytes());
        Ok(())
    }

    #[test]
    fn a_flood_is_cut_to_the_radio_link_rate_and_the_excess_counted() -> Result<()> {
        use link::frame::{Encoder, Frame};
        let ground = UdpSocket::bind("127.0.0.1:0")?;
        let to_firmware = Arc::new(Mutex::new(Vec::new()));
        let writer: SharedWriter =
            Arc::new(Mutex::new(Box::new(Collect(Arc::clone(&to_firmware)))));
        let bridge = GcsBridge::start(ground.local_addr()?, writer)?;
        let mut gcs = Encoder::new(255, 190);
        let mut beat = Frame::default();
        gcs.encode(&link::msg::HEARTBEAT_DATA::default(), &mut beat);
        // 1,000 heartbeats (21 bytes each) at once: the buffer takes 2 KiB of them.
        let datagram = beat.bytes().repeat(1000);
        let started = std::time::Instant::now();
        ground.send_to(&datagram, bridge.local_addr()?)?;
        while bridge.counts().forwarded + bridge.counts().dropped < 1000
            && started.elapsed() < Duration::from_secs(2)
        {
            thread::sleep(Duration::from_millis(10));
        }
        let counts = bridge.counts();
        assert_eq!(counts.forwarded + counts.dropped, 1000, "{counts:?}");
        // What the buffer held, and what the link carried meanwhile (well under 0.2 s).
        let most = (GCS_BUFFER as usize + 92_160 / 5) / beat.bytes().len();
        let least = GCS_BUFFER as usize / beat.bytes().len();
        let forwarded = counts.forwarded as usize;
        assert!((least..=most).contains(&forwarded), "{counts:?}");
        let got = to_firmware.lock().map(|v| v.len()).unwrap_or(0);
        assert_eq!(got, forwarded * beat.bytes().len());
        Ok(())
    }

    #[test]
    fn hil_messages_are_not_bridged() {
        assert!(is_hil(HIL_SENSOR_DATA::ID));
        assert!(is_hil(HIL_ACTUATOR_CONTROLS_DATA::ID));
        assert!(!is_hil(link::msg::HEARTBEAT_DATA::ID));
    }
}
