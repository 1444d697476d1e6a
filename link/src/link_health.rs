//! What the link threw away, counted and told (docs/ground-link.md#under-a-flood): frames
//! received corrupt, replies the vehicle had no room to queue, parameter lists cut short by a
//! new request. `SYS_STATUS` carries the counts (`errors_comm`, `drop_rate_comm`,
//! `errors_count1`, `errors_count2`) and a `STATUSTEXT` says what was dropped, at most once
//! every [`REPORT_EVERY_US`].

use core::fmt;

use crate::frame::ParserStats;
use crate::msg::SYS_STATUS_DATA;

/// Shortest time between two texts about drops, us.
pub const REPORT_EVERY_US: u64 = 5_000_000;

/// The counts since start (each wrapping).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Frames received whole.
    pub received: u32,
    /// Frames received with a wrong checksum (dropped by the parser).
    pub corrupt: u32,
    /// Replies the vehicle dropped: its queue to the link was full.
    pub replies_dropped: u32,
    /// Parameter lists restarted or replaced before they ended.
    pub lists_restarted: u32,
}

/// What was dropped since the last text, for the ground (see [`LinkHealth::report_due`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DropReport {
    /// What was dropped in the period.
    pub dropped: Counts,
    /// The period's length, s (rounded).
    pub seconds: u32,
}

impl fmt::Display for DropReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let d = &self.dropped;
        write!(f, "link: in {} s", self.seconds)?;
        let mut sep = "";
        for (n, what) in [
            (d.replies_dropped, "replies dropped (the link was full)"),
            (
                d.lists_restarted,
                "parameter lists restarted by a new request",
            ),
            (d.corrupt, "corrupt frames dropped"),
        ] {
            if n > 0 {
                write!(f, "{sep} {n} {what}")?;
                sep = ",";
            }
        }
        Ok(())
    }
}

/// The link's counts and when drops were last told.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkHealth {
    counts: Counts,
    /// The counts when last told.
    told: Counts,
    /// When last told, us (`None`: never).
    told_at_us: Option<u64>,
}

impl Counts {
    /// Nothing counted.
    pub const ZERO: Self = Self {
        received: 0,
        corrupt: 0,
        replies_dropped: 0,
        lists_restarted: 0,
    };
}

impl LinkHealth {
    /// Nothing counted yet.
    pub const fn new() -> Self {
        Self {
            counts: Counts::ZERO,
            told: Counts::ZERO,
            told_at_us: None,
        }
    }

    /// The receiving parser's counts since start.
    pub fn parsed(&mut self, stats: ParserStats) {
        self.counts.received = stats.frames;
        self.counts.corrupt = stats.bad_checksums;
    }

    /// A reply the vehicle had no room to queue.
    pub fn reply_dropped(&mut self) {
        self.counts.replies_dropped = self.counts.replies_dropped.wrapping_add(1);
    }

    /// The parameter lists restarted since start ([`crate::param_lists::ParamLists::restarted`]).
    pub fn lists_restarted(&mut self, restarted: u32) {
        self.counts.lists_restarted = restarted;
    }

    /// The counts since start.
    pub fn counts(&self) -> Counts {
        self.counts
    }

    /// What was dropped since the last text, if anything was and the last text is at least
    /// [`REPORT_EVERY_US`] old at `now_us` (the period starts at the first drop counted).
    pub fn report_due(&mut self, now_us: u64) -> Option<DropReport> {
        let c = self.counts;
        let t = self.told;
        let dropped = Counts {
            received: c.received.wrapping_sub(t.received),
            corrupt: c.corrupt.wrapping_sub(t.corrupt),
            replies_dropped: c.replies_dropped.wrapping_sub(t.replies_dropped),
            lists_restarted: c.lists_restarted.wrapping_sub(t.lists_restarted),
        };
        if dropped.corrupt == 0 && dropped.replies_dropped == 0 && dropped.lists_restarted == 0 {
            // Nothing new: the next drop is told at once (or when the period is up).
            if self
                .told_at_us
                .is_none_or(|at| now_us >= at + REPORT_EVERY_US)
            {
                self.told_at_us = None;
            }
            return None;
        }
        let since = match self.told_at_us {
            Some(at) if now_us < at + REPORT_EVERY_US => return None,
            Some(at) => at,
            None => now_us.saturating_sub(REPORT_EVERY_US),
        };
        self.told = c;
        self.told_at_us = Some(now_us);
        Some(DropReport {
            dropped,
            seconds: ((now_us - since + 500_000) / 1_000_000) as u32,
        })
    }

    /// `SYS_STATUS` with the counts: `errors_comm` the corrupt frames, `drop_rate_comm` their
    /// share of the frames received (in 0.01 %), `errors_count1` the replies dropped,
    /// `errors_count2` the parameter lists restarted (each count held at 65,535).
    pub fn fill(&self, status: &mut SYS_STATUS_DATA) {
        let c = &self.counts;
        let held = |n: u32| u16::try_from(n).unwrap_or(u16::MAX);
        status.errors_comm = held(c.corrupt);
        let seen = u64::from(c.received) + u64::from(c.corrupt);
        status.drop_rate_comm = (u64::from(c.corrupt) * 10_000)
            .checked_div(seen)
            .unwrap_or(0) as u16;
        status.errors_count1 = held(c.replies_dropped);
        status.errors_count2 = held(c.lists_restarted);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn drops_are_told_at_once_then_at_most_every_five_seconds() {
        let mut h = LinkHealth::new();
        assert_eq!(h.report_due(1_000_000), None);
        h.reply_dropped();
        let first = h.report_due(1_000_000).expect("the first drop is told");
        assert_eq!(first.dropped.replies_dropped, 1);
        for _ in 0..99 {
            h.reply_dropped();
        }
        h.lists_restarted(40);
        assert_eq!(h.report_due(3_000_000), None);
        let next = h.report_due(6_000_000).expect("five seconds later");
        assert_eq!(next.dropped.replies_dropped, 99);
        assert_eq!(next.seconds, 5);
        assert_eq!(
            next.to_string(),
            "link: in 5 s 99 replies dropped (the link was full), 40 parameter lists \
             restarted by a new request"
        );
        // Quiet for a period: the next drop is told at once.
        assert_eq!(h.report_due(12_000_000), None);
        h.parsed(ParserStats {
            frames: 10,
            bad_checksums: 3,
            ..Default::default()
        });
        let late = h.report_due(12_500_000).expect("told at once");
        assert_eq!(late.to_string(), "link: in 5 s 3 corrupt frames dropped");
    }

    #[test]
    fn sys_status_carries_the_counts_held_at_their_limit() {
        let mut h = LinkHealth::new();
        h.parsed(ParserStats {
            frames: 300,
            bad_checksums: 100,
            ..Default::default()
        });
        for _ in 0..70_000 {
            h.reply_dropped();
        }
        h.lists_restarted(7);
        let mut s = SYS_STATUS_DATA::default();
        h.fill(&mut s);
        assert_eq!(s.errors_comm, 100);
        assert_eq!(s.drop_rate_comm, 2500);
        assert_eq!(s.errors_count1, u16::MAX);
        assert_eq!(s.errors_count2, 7);
    }
}
