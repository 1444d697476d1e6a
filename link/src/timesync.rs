//! MAVLink's time synchronisation (`TIMESYNC`): the motion-capture computer's clock
//! mapped to the flight controller's, so a fix's own timestamp says when it was taken in the
//! vehicle's time (the estimators compensate the fix's latency from it).
//!
//! As PX4 does it: the vehicle answers every request (`tc1` 0) with its own time in `tc1` and
//! the request's `ts1`, and sends requests of its own; an answer to one of those gives a round
//! trip and an offset sample `(ts1 + now) / 2 - tc1` (the remote clock read at the middle of
//! the round trip), kept when the round trip is short and smoothed. Once [`SYNC_SAMPLES`] have
//! agreed the offset is in force; a sample far from it (the other computer's clock jumped)
//! starts over.

use crate::msg::TIMESYNC_DATA;

/// Longest round trip whose sample is kept, ns: a slower answer says little about when the
/// other side read its clock.
pub const MAX_ROUND_TRIP_NS: i64 = 20_000_000;
/// Samples before the offset is used.
pub const SYNC_SAMPLES: u32 = 5;
/// A sample this far from the offset in force means the other clock jumped, ns.
pub const RESYNC_NS: i64 = 100_000_000;
/// A new sample moves the smoothed offset by this fraction of its difference (1 / 10).
const SMOOTHING_DIVISOR: i64 = 10;
/// Requests remembered (their answers may come out of order or late).
const PENDING: usize = 4;

/// The estimate of the other computer's clock.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeSync {
    /// Local minus remote time, ns.
    offset_ns: i64,
    /// Samples taken since the last start over.
    samples: u32,
    /// `ts1` of the last requests sent.
    pending: [i64; PENDING],
    next_pending: usize,
}

/// What a received `TIMESYNC` is.
#[derive(Clone, Debug, PartialEq)]
pub enum Received {
    /// A request: send this answer.
    Answer(TIMESYNC_DATA),
    /// An answer to one of the vehicle's requests, used.
    Sample {
        /// Its round trip, ns.
        round_trip_ns: i64,
    },
    /// An answer to no request of the vehicle's, or too slow to use.
    Ignored,
}

impl TimeSync {
    /// No estimate yet.
    pub const fn new() -> Self {
        Self {
            offset_ns: 0,
            samples: 0,
            pending: [0; PENDING],
            next_pending: 0,
        }
    }

    /// A request to send now (`now_ns`: the vehicle's clock), remembered for its answer.
    pub fn request(&mut self, now_ns: i64) -> TIMESYNC_DATA {
        self.pending[self.next_pending] = now_ns;
        self.next_pending = (self.next_pending + 1) % PENDING;
        TIMESYNC_DATA {
            tc1: 0,
            ts1: now_ns,
        }
    }

    /// Takes a received `TIMESYNC` at `now_ns`.
    pub fn receive(&mut self, message: &TIMESYNC_DATA, now_ns: i64) -> Received {
        if message.tc1 == 0 {
            return Received::Answer(TIMESYNC_DATA {
                tc1: now_ns,
                ts1: message.ts1,
            });
        }
        let Some(slot) = self
            .pending
            .iter()
            .position(|&sent| sent != 0 && sent == message.ts1)
        else {
            return Received::Ignored;
        };
        self.pending[slot] = 0;
        let round_trip_ns = now_ns.saturating_sub(message.ts1);
        if !(0..=MAX_ROUND_TRIP_NS).contains(&round_trip_ns) {
            return Received::Ignored;
        }
        let middle = message.ts1.saturating_add(round_trip_ns / 2);
        let sample = middle.saturating_sub(message.tc1);
        let jumped = sample.abs_diff(self.offset_ns) > RESYNC_NS as u64;
        if self.samples == 0 || (self.samples >= SYNC_SAMPLES && jumped) {
            self.offset_ns = sample;
            self.samples = 1;
        } else {
            let difference = sample.saturating_sub(self.offset_ns);
            self.offset_ns = self
                .offset_ns
                .saturating_add(difference / SMOOTHING_DIVISOR);
            self.samples = self.samples.saturating_add(1);
        }
        Received::Sample { round_trip_ns }
    }

    /// Whether the offset is in force.
    pub fn synced(&self) -> bool {
        self.samples >= SYNC_SAMPLES
    }

    /// The other computer's time `remote_us` on the vehicle's clock, us, once synced.
    pub fn to_local_us(&self, remote_us: u64) -> Option<u64> {
        if !self.synced() {
            return None;
        }
        let local = i128::from(remote_us) + i128::from(self.offset_ns / 1000);
        u64::try_from(local).ok()
    }

    /// When a fix stamped `remote_us` by the other computer and received at `arrival_us` was
    /// taken, on the vehicle's clock: its own stamp mapped, when synced and no older than
    /// `max_age_us` (and not after its arrival); its arrival otherwise.
    pub fn stamp(&self, remote_us: u64, arrival_us: u64, max_age_us: u64) -> u64 {
        match self.to_local_us(remote_us) {
            Some(t) if t <= arrival_us && arrival_us - t <= max_age_us => t,
            _ => arrival_us,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The other side: its clock is the vehicle's minus `behind_ns`; it answers after
    /// `out_ns` on the way there (and `back_ns` on the way back).
    fn exchange(
        sync: &mut TimeSync,
        now_ns: i64,
        behind_ns: i64,
        out_ns: i64,
        back_ns: i64,
    ) -> Received {
        let request = sync.request(now_ns);
        let remote_then = now_ns + out_ns - behind_ns;
        let answer = TIMESYNC_DATA {
            tc1: remote_then,
            ts1: request.ts1,
        };
        sync.receive(&answer, now_ns + out_ns + back_ns)
    }

    #[test]
    fn requests_are_answered_with_the_vehicles_time() {
        let mut sync = TimeSync::new();
        let request = TIMESYNC_DATA { tc1: 0, ts1: 1234 };
        assert_eq!(
            sync.receive(&request, 99_000),
            Received::Answer(TIMESYNC_DATA {
                tc1: 99_000,
                ts1: 1234
            })
        );
        assert!(!sync.synced());
    }

    #[test]
    fn symmetric_round_trips_give_the_offset_after_enough_samples() {
        let mut sync = TimeSync::new();
        let behind = 5_000_000_000; // the mocap PC's clock is 5 s behind
        for k in 0..SYNC_SAMPLES {
            assert_eq!(sync.to_local_us(1_000_000), None, "used after {k} samples");
            let t = 10_000_000_000 + i64::from(k) * 1_000_000_000;
            assert_eq!(
                exchange(&mut sync, t, behind, 2_000_000, 2_000_000),
                Received::Sample {
                    round_trip_ns: 4_000_000
                }
            );
        }
        assert!(sync.synced());
        // A fix the PC stamped at its 20 s was taken at the vehicle's 25 s.
        assert_eq!(sync.to_local_us(20_000_000), Some(25_000_000));
    }

    #[test]
    fn an_asymmetric_trip_errs_by_half_the_difference_and_noise_is_smoothed() {
        let mut sync = TimeSync::new();
        for k in 0..50 {
            // 1 ms out, 3 ms back: the sample is 1 ms off; alternate +-0.5 ms jitter.
            let jitter = if k % 2 == 0 { 500_000 } else { -500_000 };
            exchange(
                &mut sync,
                1_000_000_000 * (k + 1),
                7_000_000 + jitter,
                1_000_000,
                3_000_000,
            );
        }
        let local = sync.to_local_us(1_000_000).expect("synced");
        let err_us = local as i64 - 1_007_000; // truth: 1 s remote is 1.007 s local
        assert!((err_us - 1_000).abs() < 300, "offset error {err_us} us");
    }

    #[test]
    fn slow_stray_and_repeated_answers_are_not_used() {
        let mut sync = TimeSync::new();
        assert_eq!(
            exchange(&mut sync, 1_000_000_000, 0, 15_000_000, 15_000_000),
            Received::Ignored
        );
        let stray = TIMESYNC_DATA { tc1: 5, ts1: 777 };
        assert_eq!(sync.receive(&stray, 2_000_000_000), Received::Ignored);
        let request = sync.request(3_000_000_000);
        let answer = TIMESYNC_DATA {
            tc1: 3_000_000_000,
            ts1: request.ts1,
        };
        assert!(matches!(
            sync.receive(&answer, 3_001_000_000),
            Received::Sample { .. }
        ));
        assert_eq!(sync.receive(&answer, 3_002_000_000), Received::Ignored);
        // An answer from the past (before the request) is no round trip.
        let request = sync.request(4_000_000_000);
        let early = TIMESYNC_DATA {
            tc1: 1,
            ts1: request.ts1,
        };
        assert_eq!(sync.receive(&early, 3_999_000_000), Received::Ignored);
    }

    #[test]
    fn hostile_answers_do_not_panic_or_sync() {
        let mut sync = TimeSync::new();
        for tc1 in [i64::MIN, i64::MAX, -1, 1] {
            let request = sync.request(1_000_000);
            let answer = TIMESYNC_DATA {
                tc1,
                ts1: request.ts1,
            };
            let _ = sync.receive(&answer, 1_500_000);
            let _ = sync.to_local_us(u64::MAX);
            let _ = sync.stamp(u64::MAX, 0, u64::MAX);
        }
        let extreme = TIMESYNC_DATA {
            tc1: i64::MIN,
            ts1: i64::MAX,
        };
        assert_eq!(sync.receive(&extreme, i64::MIN), Received::Ignored);
    }

    #[test]
    fn a_jump_of_the_other_clock_starts_over() {
        let mut sync = TimeSync::new();
        for k in 0..SYNC_SAMPLES {
            exchange(
                &mut sync,
                1_000_000_000 * i64::from(k + 1),
                0,
                1_000_000,
                1_000_000,
            );
        }
        assert_eq!(sync.to_local_us(2_000_000), Some(2_000_000));
        // The PC's clock steps 1 h ahead.
        exchange(
            &mut sync,
            10_000_000_000,
            -3_600_000_000_000,
            1_000_000,
            1_000_000,
        );
        assert!(!sync.synced());
        for k in 1..SYNC_SAMPLES {
            exchange(
                &mut sync,
                10_000_000_000 + 1_000_000_000 * i64::from(k),
                -3_600_000_000_000,
                1_000_000,
                1_000_000,
            );
        }
        assert_eq!(sync.to_local_us(3_602_000_000), Some(2_000_000));
    }

    #[test]
    fn fixes_are_stamped_in_vehicle_time_or_on_arrival() {
        let mut sync = TimeSync::new();
        // Not synced: the arrival.
        assert_eq!(sync.stamp(123, 50_000, 500_000), 50_000);
        for k in 0..SYNC_SAMPLES {
            exchange(
                &mut sync,
                1_000_000_000 * i64::from(k + 1),
                1_000_000_000,
                1_000_000,
                1_000_000,
            );
        }
        // The PC is 1 s behind: its 9.99 s is the vehicle's 10.99 s, 10 ms before arrival.
        assert_eq!(sync.stamp(9_990_000, 11_000_000, 500_000), 10_990_000);
        // Older than the limit, or after the arrival: the arrival.
        assert_eq!(sync.stamp(9_000_000, 11_000_000, 500_000), 11_000_000);
        assert_eq!(sync.stamp(10_500_000, 11_000_000, 500_000), 11_000_000);
    }
}
