//! The safety pilot's receiver for the ground station (docs/hardware.md#rc-receivers): the
//! last channel frame as `RC_CHANNELS` (pulse widths in us, `chancount`, `rssi` 0 to 254 from
//! CRSF's link quality, 255 unknown), sent only once a receiver has been heard; the frames
//! counted good and bad in `SYS_STATUS`' `errors_count2` and `errors_count1`.

use crate::msg::{RC_CHANNELS_DATA, SYS_STATUS_DATA};

/// Channels a receiver frame carries (CRSF and SBUS: 16).
pub const RC_CHANNELS: usize = 16;

/// What the receiver task last heard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RcStatus {
    /// A channel frame has come since start.
    pub heard: bool,
    /// The last frame's channels, us (0 past `count`).
    pub channels: [u16; RC_CHANNELS],
    /// How many channels the last frame carried.
    pub count: u8,
    /// `RC_CHANNELS`' `rssi`: 0 to 254, 255 unknown.
    pub rssi: u8,
    /// Frames whose checks passed.
    pub good: u32,
    /// Frames dropped (bad checksum, length, parity, cut short).
    pub bad: u32,
}

impl RcStatus {
    /// Nothing heard.
    pub const NONE: Self = Self {
        heard: false,
        channels: [0; RC_CHANNELS],
        count: 0,
        rssi: u8::MAX,
        good: 0,
        bad: 0,
    };

    /// `RC_CHANNELS` at `time_boot_ms`, or `None` before any frame.
    pub fn rc_channels(&self, time_boot_ms: u32) -> Option<RC_CHANNELS_DATA> {
        if !self.heard {
            return None;
        }
        let c = &self.channels;
        Some(RC_CHANNELS_DATA {
            time_boot_ms,
            chan1_raw: c[0],
            chan2_raw: c[1],
            chan3_raw: c[2],
            chan4_raw: c[3],
            chan5_raw: c[4],
            chan6_raw: c[5],
            chan7_raw: c[6],
            chan8_raw: c[7],
            chan9_raw: c[8],
            chan10_raw: c[9],
            chan11_raw: c[10],
            chan12_raw: c[11],
            chan13_raw: c[12],
            chan14_raw: c[13],
            chan15_raw: c[14],
            chan16_raw: c[15],
            chan17_raw: 0,
            chan18_raw: 0,
            chancount: self.count.min(RC_CHANNELS as u8),
            rssi: self.rssi,
        })
    }

    /// The frame counts in `SYS_STATUS`: `errors_count1` the frames dropped, `errors_count2`
    /// those that checked (each the low 16 bits of its count).
    pub fn fill_sys_status(&self, status: &mut SYS_STATUS_DATA) {
        status.errors_count1 = self.bad as u16;
        status.errors_count2 = self.good as u16;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_is_sent_before_a_frame_then_the_channels_and_counts() {
        assert!(RcStatus::NONE.rc_channels(5).is_none());
        let mut s = RcStatus::NONE;
        s.heard = true;
        s.count = 16;
        s.channels = core::array::from_fn(|c| 1000 + c as u16);
        s.good = 70_001;
        s.bad = 3;
        let m = s.rc_channels(1234).expect("sent");
        assert_eq!(
            (m.time_boot_ms, m.chan1_raw, m.chan16_raw),
            (1234, 1000, 1015)
        );
        assert_eq!((m.chan17_raw, m.chancount, m.rssi), (0, 16, 255));
        let mut status = SYS_STATUS_DATA::default();
        s.fill_sys_status(&mut status);
        assert_eq!(
            (status.errors_count1, status.errors_count2),
            (3, (70_001 - 65_536) as u16)
        );
    }
}
