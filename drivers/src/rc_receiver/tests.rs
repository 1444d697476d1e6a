//! The receiver's port: protocols and ports from their parameters, frames good and bad, the
//! link quality, and the manual input a frame gives (none in failsafe).

use super::*;
use crate::crsf::{SYNC, crc8, encode_channels, frame_type};
use crate::rc::{CHANNELS, PACKED_LEN, from_us, pack_channels};
use std::vec::Vec;

fn frames(receiver: &mut RcReceiver, bytes: &[u8], line_error: bool, idle: bool) -> Vec<RcFrame> {
    let mut out = Vec::new();
    receiver.receive(bytes, line_error, idle, |f| out.push(*f));
    out
}

fn link_statistics(link_quality: u8) -> Vec<u8> {
    let payload = [50, 50, link_quality, 10, 0, 4, 3, 60, 100, 8];
    let mut f = std::vec![SYNC, (payload.len() + 2) as u8, frame_type::LINK_STATISTICS];
    f.extend_from_slice(&payload);
    f.push(crc8(&f[2..]));
    f
}

fn sbus(channels_us: &[u16; CHANNELS], flags: u8) -> Vec<u8> {
    let mut f = std::vec![crate::sbus::HEADER];
    f.extend_from_slice(&pack_channels(&channels_us.map(from_us)));
    f.push(flags);
    f.push(0x00);
    assert_eq!(f.len(), 3 + PACKED_LEN);
    f
}

#[test]
fn parameters_choose_the_protocol_its_line_and_the_port() {
    assert_eq!(RcProtocol::from_param(6), RcProtocol::Crsf);
    assert_eq!(RcProtocol::from_param(2), RcProtocol::Sbus);
    assert_eq!(RcProtocol::from_param(0), RcProtocol::None);
    assert_eq!(RcProtocol::from_param(3), RcProtocol::None);
    let crsf = RcProtocol::Crsf.line().expect("a line");
    assert_eq!(
        (
            crsf.baud,
            crsf.even_parity,
            crsf.two_stop_bits,
            crsf.inverted
        ),
        (420_000, false, false, false)
    );
    let sbus = RcProtocol::Sbus.line().expect("a line");
    assert_eq!(
        (
            sbus.baud,
            sbus.even_parity,
            sbus.two_stop_bits,
            sbus.inverted
        ),
        (100_000, true, true, true)
    );
    assert_eq!(RcProtocol::None.line(), None);
    assert_eq!(RcPort::from_param(202), RcPort::Gps2);
    assert_eq!(RcPort::from_param(103), RcPort::Telem3);
    assert_eq!(RcPort::from_param(0), RcPort::None);
}

#[test]
fn telem3_is_refused_while_robots_past_the_fourth_need_its_steppers() {
    assert_eq!(RcPort::Telem3.check(0), Ok(RcPort::Telem3));
    assert_eq!(RcPort::Telem3.check(4), Ok(RcPort::Telem3));
    let refused = RcPort::Telem3.check(8).expect_err("refused");
    assert_eq!(refused, PortRefusal::Telem3DrivesSteppers { robots: 8 });
    assert!(std::format!("{refused}").contains("robots 5-8"));
    assert_eq!(RcPort::Gps2.check(8), Ok(RcPort::Gps2));
}

#[test]
fn crsf_frames_that_check_come_out_and_the_rest_are_counted_bad() {
    let mut rx = RcReceiver::new(RcProtocol::Crsf);
    assert_eq!(rx.protocol(), RcProtocol::Crsf);
    let mut sticks = [1500u16; CHANNELS];
    sticks[2] = 1000;
    let good = encode_channels(&sticks);
    let got = frames(&mut rx, &good, false, true);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].channels, sticks);
    assert_eq!(rx.counts(), RcCounts { good: 1, bad: 0 });
    // A flipped bit: the CRC finds it.
    let mut bad = good;
    bad[5] ^= 0x10;
    assert!(frames(&mut rx, &bad, false, true).is_empty());
    // Cut short by an idle line.
    assert!(frames(&mut rx, &good[..20], false, true).is_empty());
    assert_eq!(rx.counts(), RcCounts { good: 1, bad: 2 });
    // The next whole frame comes through.
    assert_eq!(frames(&mut rx, &good, false, true).len(), 1);
    // Split over two reads with no idle between: one frame.
    assert!(frames(&mut rx, &good[..10], false, false).is_empty());
    assert_eq!(frames(&mut rx, &good[10..], false, true).len(), 1);
    assert_eq!(rx.counts(), RcCounts { good: 3, bad: 2 });
}

#[test]
fn crsf_link_quality_is_the_rssi_and_zero_means_failsafe() {
    let mut rx = RcReceiver::new(RcProtocol::Crsf);
    assert_eq!(rx.rssi(), 255, "unknown before link statistics");
    let mut bytes = link_statistics(50);
    bytes.extend_from_slice(&encode_channels(&[1500; CHANNELS]));
    let got = frames(&mut rx, &bytes, false, true);
    assert_eq!(rx.rssi(), 127);
    assert!(manual_input(&got[0], &RcMap::AETR).is_some());
    let mut bytes = link_statistics(0);
    bytes.extend_from_slice(&encode_channels(&[1500; CHANNELS]));
    let got = frames(&mut rx, &bytes, false, true);
    assert_eq!(rx.rssi(), 0);
    assert!(got[0].failsafe);
    assert_eq!(manual_input(&got[0], &RcMap::AETR), None);
    assert_eq!(rx.counts(), RcCounts { good: 4, bad: 0 });
    frames(&mut rx, &link_statistics(100), false, true);
    assert_eq!(rx.rssi(), 254);
}

#[test]
fn sbus_frames_between_idle_lines_a_flagged_byte_drops_its_frame() {
    let mut rx = RcReceiver::new(RcProtocol::Sbus);
    let mut sticks = [1500u16; CHANNELS];
    sticks[0] = 2000;
    let got = frames(&mut rx, &sbus(&sticks, 0), false, true);
    assert_eq!(got.len(), 1);
    let input = manual_input(&got[0], &RcMap::AETR).expect("sticks");
    assert!((input.sticks.roll - 1.0).abs() < 1e-3, "{input:?}");
    assert!(frames(&mut rx, &sbus(&sticks, 0), true, true).is_empty());
    let failsafe = frames(
        &mut rx,
        &sbus(&sticks, crate::sbus::flag::FAILSAFE),
        false,
        true,
    );
    assert_eq!(manual_input(&failsafe[0], &RcMap::AETR), None);
    assert_eq!(rx.counts(), RcCounts { good: 2, bad: 1 });
    assert_eq!(rx.rssi(), 255);
}

#[test]
fn no_protocol_takes_nothing() {
    let mut rx = RcReceiver::new(RcProtocol::None);
    assert!(frames(&mut rx, &encode_channels(&[1500; CHANNELS]), false, true).is_empty());
    assert_eq!(rx.counts(), RcCounts::default());
}
