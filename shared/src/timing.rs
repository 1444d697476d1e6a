//! Health of a fixed-rate loop: the measured period of each tick, its jitter, and overruns.
//!
//! The flight controller runs its control step at [`CONTROL_RATE_HZ`]
//! (docs/models.md#flight-cascade); the simulator runs `shared` at the same rate. Each tick the loop
//! reports the time it woke; [`LoopMonitor::step`] returns the `dt` the controllers should
//! integrate with, clamped so that one late wake-up cannot kick an integrator, and keeps
//! statistics that the firmware logs once a second.

/// Rate of the control loop on the flight controller, Hz.
pub const CONTROL_RATE_HZ: u32 = 400;

/// Overrun threshold in half periods: a period above 3/2 of nominal is an overrun.
const OVERRUN_HALF_PERIODS: u64 = 3;

/// Statistics of the ticks since the last [`LoopMonitor::take_stats`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoopStats {
    /// Ticks measured (the first tick after start has no period and is not counted).
    pub ticks: u32,
    /// Ticks whose period exceeded 1.5 times the nominal one.
    pub overruns: u32,
    /// Shortest measured period, microseconds (`u32::MAX` when no tick was measured).
    pub min_period_us: u32,
    /// Longest measured period, microseconds.
    pub max_period_us: u32,
}

impl LoopStats {
    const EMPTY: Self = Self {
        ticks: 0,
        overruns: 0,
        min_period_us: u32::MAX,
        max_period_us: 0,
    };
}

/// Measures a loop meant to run every `period_us` microseconds.
#[derive(Clone, Debug)]
pub struct LoopMonitor {
    period_us: u32,
    last_us: Option<u64>,
    stats: LoopStats,
}

impl LoopMonitor {
    /// A monitor for a loop of the given nominal period (microseconds, at least 1).
    pub const fn new(period_us: u32) -> Self {
        Self {
            period_us: if period_us == 0 { 1 } else { period_us },
            last_us: None,
            stats: LoopStats::EMPTY,
        }
    }

    /// A monitor for a loop running at `rate_hz` (at least 1 Hz).
    pub const fn at_rate(rate_hz: u32) -> Self {
        let rate = if rate_hz == 0 { 1 } else { rate_hz };
        Self::new(1_000_000 / rate)
    }

    /// Nominal period, seconds.
    pub fn nominal_dt(&self) -> f32 {
        self.period_us as f32 * 1e-6
    }

    /// Records a tick that woke at `now_us` (a monotonic clock in microseconds) and returns the
    /// `dt` in seconds to integrate with: the measured period clamped to half and twice the
    /// nominal one (the nominal one on the first tick, or if the clock went backwards).
    pub fn step(&mut self, now_us: u64) -> f32 {
        let nominal = self.period_us as u64;
        let Some(last) = self.last_us.replace(now_us) else {
            return self.nominal_dt();
        };
        let Some(period) = now_us.checked_sub(last) else {
            return self.nominal_dt();
        };
        let s = &mut self.stats;
        s.ticks = s.ticks.saturating_add(1);
        let period_u32 = u32::try_from(period).unwrap_or(u32::MAX);
        s.min_period_us = s.min_period_us.min(period_u32);
        s.max_period_us = s.max_period_us.max(period_u32);
        // Saturating: a clock that jumps by more than half of u64 (a hostile HIL_SENSOR time)
        // is an overrun, not an overflow.
        if period.saturating_mul(2) > OVERRUN_HALF_PERIODS * nominal {
            s.overruns = s.overruns.saturating_add(1);
        }
        let clamped = period.clamp(nominal / 2, 2 * nominal);
        clamped as f32 * 1e-6
    }

    /// The statistics gathered since the last call, and a fresh start for the next window.
    pub fn take_stats(&mut self) -> LoopStats {
        core::mem::replace(&mut self.stats, LoopStats::EMPTY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_loop_has_nominal_dt_and_no_overrun() {
        let mut m = LoopMonitor::at_rate(CONTROL_RATE_HZ);
        for k in 0..401u64 {
            let dt = m.step(1_000 + k * 2_500);
            assert!((dt - 0.0025).abs() < 1e-9);
        }
        let s = m.take_stats();
        assert_eq!((s.ticks, s.overruns), (400, 0));
        assert_eq!((s.min_period_us, s.max_period_us), (2_500, 2_500));
        assert_eq!(m.take_stats().ticks, 0, "window restarts");
    }

    #[test]
    fn late_tick_is_an_overrun_and_its_dt_is_clamped() {
        let mut m = LoopMonitor::at_rate(CONTROL_RATE_HZ);
        m.step(0);
        m.step(2_500);
        let dt = m.step(2_500 + 20_000); // 8 periods late
        assert!((dt - 0.005).abs() < 1e-9, "clamped to twice nominal: {dt}");
        let early = m.step(2_500 + 20_000 + 100);
        assert!((early - 0.00125).abs() < 1e-9, "clamped to half nominal");
        let s = m.take_stats();
        assert_eq!((s.ticks, s.overruns), (3, 1));
        assert_eq!((s.min_period_us, s.max_period_us), (100, 20_000));
        assert!(
            (m.step(0) - 0.0025).abs() < 1e-9,
            "clock going back gives nominal"
        );
    }

    /// Found by the `link_input` fuzz target: a `HIL_SENSOR` whose time jumps by
    /// more than half of `u64` overflowed the overrun test (`2 * period`).
    #[test]
    fn a_clock_jump_past_half_of_u64_is_an_overrun_not_an_overflow() {
        let mut m = LoopMonitor::at_rate(CONTROL_RATE_HZ);
        m.step(0);
        let dt = m.step(u64::MAX);
        assert!((dt - 0.005).abs() < 1e-9, "clamped to twice nominal: {dt}");
        let s = m.take_stats();
        assert_eq!((s.ticks, s.overruns), (1, 1));
        assert_eq!(s.max_period_us, u32::MAX);
    }
}
