//! The RC receiver task (docs/hardware.md#rc-receivers): on the link executor, below the
//! control step, never in it. It opens the board's receiver port with the protocol and port the
//! parameters ask for (`RC_INPUT_PROTO`, `RC_PORT_CONFIG`; again whenever they change, or the
//! payload's robot count changes what TELEM3 may carry), hands every read to
//! `drivers::rc_receiver`, and passes each channel frame's manual input through the channel map
//! in force (`RC_MAP_*`) to the control step ([`super::RC_INPUT`]); a frame in failsafe gives
//! none. The last frame and the counts go to the ground station ([`super::RC_STATUS`]:
//! `RC_CHANNELS`, `SYS_STATUS`). Glue only: every decision is `drivers::rc_receiver`'s.

use core::sync::atomic::Ordering;

use drivers::rc_receiver::{RcPort, RcProtocol, RcReceiver, manual_input};
use embassy_time::{Duration, Timer, with_timeout};
use link::telemetry::RC_CHANNELS;

use super::autonomy::Severity;
use super::{BENCH_CONFIG, OUTBOX, PAYLOAD_ROBOTS, RC_INPUT, RC_STATUS};
use crate::board::{Board, RcSerial, Selected};

/// How long a read waits before the task looks at the parameters again.
const LOOK_AGAIN: Duration = Duration::from_millis(100);

/// What the port was opened for: the protocol, the port, and the robots TELEM3 was checked
/// against (0 for another port).
type Wanted = (RcProtocol, RcPort, u8);

fn wanted() -> Wanted {
    let hardware = BENCH_CONFIG.lock(|c| c.get()).hardware;
    let port = RcPort::from_param(hardware.rc_port);
    let robots = if port == RcPort::Telem3 {
        PAYLOAD_ROBOTS.load(Ordering::Relaxed)
    } else {
        0
    };
    (RcProtocol::from_param(hardware.rc_protocol), port, robots)
}

fn say(severity: Severity, args: core::fmt::Arguments<'_>) {
    let _ = OUTBOX.try_send(super::comms::report(severity, args));
}

/// Opens the port for `want`; the receiver that parses it (none when refused, said why).
fn open(serial: &mut <Selected as Board>::RcSerial, want: Wanted) -> RcReceiver {
    let (protocol, port, robots) = want;
    let Some(line) = protocol.line().filter(|_| port != RcPort::None) else {
        return RcReceiver::new(RcProtocol::None);
    };
    if let Err(refusal) = port.check(robots) {
        say(Severity::Error, format_args!("{refusal}"));
        return RcReceiver::new(RcProtocol::None);
    }
    match serial.open(port, line) {
        Ok(()) => {
            say(
                Severity::Info,
                format_args!("RC: {} on {}", protocol.name(), port.name()),
            );
            RcReceiver::new(protocol)
        }
        Err(why) => {
            say(
                Severity::Error,
                format_args!("RC on {} refused: {why}", port.name()),
            );
            RcReceiver::new(RcProtocol::None)
        }
    }
}

/// Reads the receiver forever.
#[embassy_executor::task]
pub async fn rc_receiver(mut serial: <Selected as Board>::RcSerial) {
    let mut in_use: Option<Wanted> = None;
    let mut receiver = RcReceiver::new(RcProtocol::None);
    let mut buf = [0u8; 64];
    loop {
        let want = wanted();
        if in_use != Some(want) {
            in_use = Some(want);
            receiver = open(&mut serial, want);
        }
        if receiver.protocol() == RcProtocol::None {
            Timer::after(LOOK_AGAIN).await;
            continue;
        }
        let Ok(read) = with_timeout(LOOK_AGAIN, serial.read(&mut buf)).await else {
            continue;
        };
        let map = BENCH_CONFIG.lock(|c| c.get()).hardware.rc_map;
        let mut last = None;
        receiver.receive(
            buf.get(..read.len).unwrap_or(&[]),
            read.line_error,
            read.idle,
            |frame| {
                if let Some(input) = manual_input(frame, &map) {
                    RC_INPUT.signal(input);
                }
                last = Some(*frame);
            },
        );
        let counts = receiver.counts();
        let rssi = receiver.rssi();
        RC_STATUS.lock(|cell| {
            let mut status = cell.get();
            if let Some(frame) = last {
                status.heard = true;
                status.count = frame.count.min(RC_CHANNELS as u8);
                status.channels = frame.channels;
            }
            status.rssi = rssi;
            status.good = counts.good;
            status.bad = counts.bad;
            cell.set(status);
        });
    }
}
