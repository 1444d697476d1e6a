//! The link's rate as a budget of bytes (docs/ground-link.md#under-a-flood): a token bucket
//! that fills at the link's rate and holds at most a burst. What must go (a control step's
//! messages, the heartbeat) spends from it even past empty; what may wait (replies,
//! telemetry, bulk transfers) goes only while it holds bytes, so all of it together stays
//! within what the link carries. The firmware's send task keeps one on the vehicle's clock;
//! the HIL plant keeps one for a ground station's traffic, as a radio would.

/// Bytes a second a serial link carries at `baud` (8N1: ten bits a byte).
pub const fn bytes_per_second(baud: u32) -> u32 {
    baud / 10
}

/// A byte budget that fills at a fixed rate (see the module's text).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkBudget {
    /// Bytes a second.
    rate: u32,
    /// Most bytes held, in millionths of a byte.
    cap: i64,
    /// Bytes held, in millionths of a byte (negative: spent ahead).
    held: i64,
    /// When it was last filled, us.
    filled_at_us: u64,
}

impl LinkBudget {
    /// A full budget of `rate` bytes a second holding at most `burst` bytes, at `now_us`.
    pub const fn new(rate: u32, burst: u32, now_us: u64) -> Self {
        let cap = burst as i64 * 1_000_000;
        Self {
            rate,
            cap,
            held: cap,
            filled_at_us: now_us,
        }
    }

    /// Bytes a second.
    pub fn rate(&self) -> u32 {
        self.rate
    }

    /// Adds what the link carried since the last fill (a clock that went back adds nothing).
    pub fn fill(&mut self, now_us: u64) {
        let elapsed = now_us.saturating_sub(self.filled_at_us);
        self.filled_at_us = self.filled_at_us.max(now_us);
        let added = (elapsed as i64).saturating_mul(i64::from(self.rate));
        self.held = self.held.saturating_add(added).min(self.cap);
    }

    /// Takes `bytes` that went out (or must go), even past empty.
    pub fn spend(&mut self, bytes: usize) {
        let bytes = i64::try_from(bytes).unwrap_or(i64::MAX / 2_000_000);
        self.held = self.held.saturating_sub(bytes.saturating_mul(1_000_000));
    }

    /// Whether what may wait may go now (filled to `now_us`): the budget holds bytes.
    pub fn allows(&mut self, now_us: u64) -> bool {
        self.fill(now_us);
        self.held > 0
    }

    /// Takes `bytes` if the budget (filled to `now_us`) holds that many: a radio's buffer that
    /// takes a frame whole or drops it.
    pub fn take(&mut self, bytes: usize, now_us: u64) -> bool {
        self.fill(now_us);
        let wanted = i64::try_from(bytes)
            .unwrap_or(i64::MAX)
            .saturating_mul(1_000_000);
        if wanted > self.held {
            return false;
        }
        self.held -= wanted;
        true
    }

    /// When the budget next holds bytes, us: now if it does.
    pub fn ready_at(&self) -> u64 {
        if self.held > 0 || self.rate == 0 {
            return self.filled_at_us;
        }
        let wait_us = (-self.held) / i64::from(self.rate) + 1;
        self.filled_at_us.saturating_add(wait_us as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_serial_link_carries_a_tenth_of_its_baud_rate_in_bytes() {
        assert_eq!(bytes_per_second(921_600), 92_160);
        assert_eq!(bytes_per_second(57_600), 5_760);
    }

    #[test]
    fn what_may_wait_goes_only_within_the_rate_over_a_long_run() {
        // 100 s of 40-byte messages offered every 100 us (400 kB/s) on a 92,160 B/s link.
        let mut budget = LinkBudget::new(92_160, 1024, 0);
        let mut sent = 0usize;
        for t in (0..100_000_000u64).step_by(100) {
            if budget.allows(t) {
                budget.spend(40);
                sent += 40;
            }
        }
        let rate = sent as f64 / 100.0;
        assert!((rate - 92_160.0).abs() < 200.0, "{rate} B/s");
    }

    #[test]
    fn what_must_go_spends_ahead_and_what_may_wait_waits_for_it() {
        let mut budget = LinkBudget::new(1000, 100, 0);
        budget.spend(600); // 500 bytes ahead: half a second.
        assert!(!budget.allows(0));
        assert_eq!(budget.ready_at(), 500_001);
        assert!(!budget.allows(499_000));
        assert!(budget.allows(501_000));
    }

    #[test]
    fn a_burst_is_held_at_most_and_a_clock_going_back_adds_nothing() {
        let mut budget = LinkBudget::new(1000, 100, 0);
        budget.fill(10_000_000); // ten idle seconds: still 100 bytes.
        assert!(budget.take(100, 10_000_000));
        assert!(!budget.take(1, 10_000_000));
        budget.fill(5_000_000);
        assert!(!budget.take(1, 10_000_000));
        assert!(budget.take(1, 10_001_000));
    }

    #[test]
    fn a_radio_drops_a_frame_it_has_no_room_for_and_keeps_the_budget() {
        let mut budget = LinkBudget::new(1000, 50, 0);
        assert!(!budget.take(51, 0));
        assert!(budget.take(50, 0));
    }
}
