//! ESC pulses for ESCs without DShot: the pulse width of a command fraction for each
//! protocol ([`EscProtocol`], `shared`'s). PWM: 1000 us (stop) to 2000 us (full) at 400 Hz; OneShot125: 125 us to
//! 250 us, one pulse per control step. The board's timers turn the width into compare counts.

pub use shared::mission::esc_protocol::{EscProtocol, UnknownProtocol};

/// The pulses a protocol puts on the FMU outputs.
pub trait Pulses {
    /// The pulse width (ns) for a command fraction in `[0, 1]`: the stop width at or below
    /// zero, for a non-finite fraction, and always 0 (no pulse: the line held low) for DShot
    /// and DroneCAN, which send frames instead.
    fn pulse_ns(self, fraction: f32) -> u32;
    /// Pulses per second the outputs run at, for a control step of `tick_hz`.
    fn update_hz(self, tick_hz: u32) -> u32;
}

impl Pulses for EscProtocol {
    fn pulse_ns(self, fraction: f32) -> u32 {
        let (stop, span) = match self {
            Self::Dshot600 | Self::DroneCan => return 0,
            Self::Pwm => (1_000_000, 1_000_000),
            Self::OneShot125 => (125_000, 125_000),
        };
        if fraction.is_nan() || fraction <= 0.0 {
            return stop;
        }
        stop + shared::math::round(fraction.min(1.0) * span as f32) as u32
    }

    fn update_hz(self, tick_hz: u32) -> u32 {
        match self {
            Self::Dshot600 | Self::OneShot125 | Self::DroneCan => tick_hz,
            Self::Pwm => tick_hz.min(400),
        }
    }
}

/// Compare counts for a pulse of `pulse_ns` on a timer counting at `count_hz` (rounded to the
/// nearest count, saturating at `u16::MAX`).
pub fn pulse_counts(pulse_ns: u32, count_hz: u32) -> u16 {
    let counts = (u64::from(pulse_ns) * u64::from(count_hz) + 500_000_000) / 1_000_000_000;
    u16::try_from(counts).unwrap_or(u16::MAX)
}

/// The compare value for a pulse of `pulse_ns` on a timer whose period is `period_ns` and
/// `max_duty` counts (rounded down, at most `max_duty`).
pub fn duty_of(pulse_ns: u32, period_ns: u32, max_duty: u32) -> u32 {
    if period_ns == 0 {
        return 0;
    }
    let duty = u64::from(pulse_ns) * u64::from(max_duty) / u64::from(period_ns);
    duty.min(u64::from(max_duty)) as u32
}

/// Period of the PWM and OneShot125 outputs at [`Pulses::update_hz`] 400 Hz, ns.
pub const PERIOD_400HZ_NS: u32 = 2_500_000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulse_widths_span_the_protocols_ranges() {
        assert_eq!(EscProtocol::Pwm.pulse_ns(0.0), 1_000_000);
        assert_eq!(EscProtocol::Pwm.pulse_ns(0.5), 1_500_000);
        assert_eq!(EscProtocol::Pwm.pulse_ns(2.0), 2_000_000);
        assert_eq!(EscProtocol::Pwm.pulse_ns(f32::NAN), 1_000_000);
        assert_eq!(EscProtocol::OneShot125.pulse_ns(-1.0), 125_000);
        assert_eq!(EscProtocol::OneShot125.pulse_ns(1.0), 250_000);
        assert_eq!(EscProtocol::Dshot600.pulse_ns(1.0), 0);
        assert_eq!(EscProtocol::DroneCan.pulse_ns(1.0), 0);
        assert_eq!(EscProtocol::Pwm.update_hz(400), 400);
        assert_eq!(EscProtocol::Pwm.update_hz(1000), 400);
    }

    /// 400 Hz with 60,000 counts a period: 1500 us is 36,000 counts, 125 us 3,000.
    #[test]
    fn duty_within_the_period() {
        assert_eq!(duty_of(1_500_000, PERIOD_400HZ_NS, 60_000), 36_000);
        assert_eq!(duty_of(125_000, PERIOD_400HZ_NS, 60_000), 3_000);
        assert_eq!(duty_of(3_000_000, PERIOD_400HZ_NS, 60_000), 60_000);
        assert_eq!(duty_of(1_000, 0, 60_000), 0);
    }

    /// A 1 MHz timer: 1500 us is 1500 counts; at 240 MHz 125 us is 30,000 counts.
    #[test]
    fn counts_at_the_timers_clock() {
        assert_eq!(pulse_counts(1_500_000, 1_000_000), 1500);
        assert_eq!(pulse_counts(125_000, 240_000_000), 30_000);
        assert_eq!(pulse_counts(2_000_000, 240_000_000), u16::MAX);
    }
}
