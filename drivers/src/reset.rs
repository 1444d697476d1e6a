//! Why the STM32H7 last reset, from its reset status register `RCC_RSR` (RM0433
//! section 8.7.39: flags in bits 16..=30, cleared by writing `RMVF`, bit 16). After a watchdog
//! reset the firmware comes up disarmed and tells the ground why.

/// `RCC_RSR` flags (RM0433).
mod flag {
    pub const LPWRRST: u32 = 1 << 30;
    pub const WWDG1RST: u32 = 1 << 28;
    pub const IWDG1RST: u32 = 1 << 26;
    pub const SFTRST: u32 = 1 << 24;
    pub const PORRST: u32 = 1 << 23;
    pub const PINRST: u32 = 1 << 22;
    pub const BORRST: u32 = 1 << 21;
}

/// The reset that started this run, the most telling flag first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResetReason {
    /// The independent watchdog expired: the control task stopped feeding it.
    Watchdog,
    /// The window watchdog expired.
    WindowWatchdog,
    /// Illegal low-power entry.
    LowPower,
    /// Brown-out: the supply dipped.
    BrownOut,
    /// Power on.
    PowerOn,
    /// A software reset (the bootloader, or a reboot command).
    Software,
    /// The reset pin (the reset button or a debug probe).
    Pin,
    /// No flag set (the flags were cleared and nothing since).
    Unknown,
}

impl ResetReason {
    /// The reason `RCC_RSR` holds. A power-on reset also sets the pin and brown-out flags, a
    /// watchdog reset the pin flag: the first matching line of this list wins.
    pub fn from_rsr(rsr: u32) -> Self {
        if rsr & flag::IWDG1RST != 0 {
            Self::Watchdog
        } else if rsr & flag::WWDG1RST != 0 {
            Self::WindowWatchdog
        } else if rsr & flag::LPWRRST != 0 {
            Self::LowPower
        } else if rsr & flag::PORRST != 0 {
            Self::PowerOn
        } else if rsr & flag::BORRST != 0 {
            Self::BrownOut
        } else if rsr & flag::SFTRST != 0 {
            Self::Software
        } else if rsr & flag::PINRST != 0 {
            Self::Pin
        } else {
            Self::Unknown
        }
    }

    /// Whether the reset was a failure the ground must hear of (the vehicle stays disarmed).
    pub fn is_fault(self) -> bool {
        matches!(
            self,
            Self::Watchdog | Self::WindowWatchdog | Self::LowPower | Self::BrownOut
        )
    }

    /// For people: what happened.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Watchdog => "watchdog reset: the control loop stopped",
            Self::WindowWatchdog => "window watchdog reset",
            Self::LowPower => "reset on an illegal low-power entry",
            Self::BrownOut => "brown-out reset: the supply voltage dipped",
            Self::PowerOn => "power-on start",
            Self::Software => "software reset",
            Self::Pin => "reset by the reset pin",
            Self::Unknown => "start, reset cause not recorded",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_telling_flag_wins() {
        // Power on: RM0433 lists POR with BOR and PIN set together; reset value 0x00E6_0000
        // also holds bits 17 and 18 (CPU and domain resets).
        assert_eq!(ResetReason::from_rsr(0x00E6_0000), ResetReason::PowerOn);
        // A watchdog reset drives the reset pin too.
        assert_eq!(
            ResetReason::from_rsr(flag::IWDG1RST | flag::PINRST),
            ResetReason::Watchdog
        );
        assert_eq!(ResetReason::from_rsr(flag::PINRST), ResetReason::Pin);
        assert_eq!(
            ResetReason::from_rsr(flag::SFTRST | flag::PINRST),
            ResetReason::Software
        );
        assert_eq!(
            ResetReason::from_rsr(flag::BORRST | flag::PINRST),
            ResetReason::BrownOut
        );
        assert_eq!(ResetReason::from_rsr(0), ResetReason::Unknown);
        assert!(ResetReason::Watchdog.is_fault());
        assert!(!ResetReason::PowerOn.is_fault());
        assert!(
            ResetReason::from_rsr(flag::IWDG1RST)
                .describe()
                .contains("watchdog")
        );
    }
}
