//! Heartbeat: blinks the blue LED at 1 Hz so a person at the bench sees the executor run.

use embassy_stm32::gpio::Output;
use embassy_time::{Duration, Ticker};

/// Blinks `led` (active low) 100 ms on, 900 ms off, forever.
#[embassy_executor::task]
pub async fn heartbeat(mut led: Output<'static>) {
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        for tenth in 0..10u8 {
            if tenth == 0 {
                led.set_low();
            } else {
                led.set_high();
            }
            ticker.next().await;
        }
    }
}
