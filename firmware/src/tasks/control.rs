//! The 400 Hz control task: wakes on an embassy `Ticker` at `shared`'s control rate and runs
//! one step of the shared logic per tick.
//!
//! For now the step is the loop monitor (`shared::timing`): it measures each period, hands the
//! `dt` the controllers will integrate with, and logs the loop's health once a second. The
//! estimator, controller and mixer of `shared` plug in here as they arrive.

use embassy_time::{Duration, Instant, Ticker};
use shared::timing::{CONTROL_RATE_HZ, LoopMonitor};

/// Runs the control step at [`CONTROL_RATE_HZ`] forever.
#[embassy_executor::task]
pub async fn control_loop() {
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(CONTROL_RATE_HZ)));
    let mut monitor = LoopMonitor::at_rate(CONTROL_RATE_HZ);
    let mut ticks_in_window = 0u32;
    loop {
        ticker.next().await;
        let _dt = monitor.step(Instant::now().as_micros());
        ticks_in_window += 1;
        if ticks_in_window == CONTROL_RATE_HZ {
            ticks_in_window = 0;
            let s = monitor.take_stats();
            defmt::info!(
                "control loop: {} ticks, period {}..{} us, {} overruns",
                s.ticks,
                s.min_period_us,
                s.max_period_us,
                s.overruns
            );
        }
    }
}
