//! What the link's send task sends next (docs/ground-link.md#under-a-flood): a control step's
//! messages at once, the heartbeat when due, then only while the link's byte budget holds
//! bytes the replies, the telemetry streams due, the bulk transfers and the parameter lists,
//! in that order. A ground station that asks faster than the link carries fills its own
//! queues, never the vehicle's step or heartbeat.

/// What waits to be sent, as the send task sees it before each group of frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Waiting {
    /// A control step's messages are queued.
    pub step: bool,
    /// The heartbeat is due.
    pub heartbeat_due: bool,
    /// The link's budget holds bytes now.
    pub budget_allows: bool,
    /// A reply is queued.
    pub reply: bool,
    /// A telemetry stream is due.
    pub telemetry_due: bool,
    /// A bulk transfer's message is queued.
    pub bulk: bool,
    /// A parameter list is in flight.
    pub list: bool,
}

/// Where the next group of frames comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// A control step's messages: at once.
    Step,
    /// The heartbeat (with the mission's status and a time-sync request).
    Heartbeat,
    /// A reply, within the link's rate.
    Reply,
    /// The telemetry streams due, within the link's rate.
    Telemetry,
    /// A bulk transfer's message, within the link's rate.
    Bulk,
    /// A parameter list's next value, within the link's rate.
    ListValue,
    /// Nothing now: wait for something to send or for the time to send it ([`wake_at`]).
    Wait,
}

/// The next source by priority.
pub fn next_source(w: &Waiting) -> Source {
    if w.step {
        Source::Step
    } else if w.heartbeat_due {
        Source::Heartbeat
    } else if !w.budget_allows {
        Source::Wait
    } else if w.reply {
        Source::Reply
    } else if w.telemetry_due {
        Source::Telemetry
    } else if w.bulk {
        Source::Bulk
    } else if w.list {
        Source::ListValue
    } else {
        Source::Wait
    }
}

/// When a waiting send task must look again, us, if nothing arrives before: the next
/// heartbeat, and the budget's refill while it is spent, else the next telemetry stream due.
pub fn wake_at(
    next_beat_us: u64,
    budget_allows: bool,
    budget_ready_us: u64,
    telemetry_due_us: Option<u64>,
) -> u64 {
    if !budget_allows {
        next_beat_us.min(budget_ready_us)
    } else if let Some(due) = telemetry_due_us {
        next_beat_us.min(due)
    } else {
        next_beat_us
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Waiting = Waiting {
        step: true,
        heartbeat_due: true,
        budget_allows: true,
        reply: true,
        telemetry_due: true,
        bulk: true,
        list: true,
    };

    #[test]
    fn each_source_goes_before_the_ones_below_it() {
        let mut w = ALL;
        let order = [
            Source::Step,
            Source::Heartbeat,
            Source::Reply,
            Source::Telemetry,
            Source::Bulk,
            Source::ListValue,
            Source::Wait,
        ];
        for expected in order {
            assert_eq!(next_source(&w), expected);
            match expected {
                Source::Step => w.step = false,
                Source::Heartbeat => w.heartbeat_due = false,
                Source::Reply => w.reply = false,
                Source::Telemetry => w.telemetry_due = false,
                Source::Bulk => w.bulk = false,
                Source::ListValue => w.list = false,
                Source::Wait => {}
            }
        }
    }

    #[test]
    fn a_spent_budget_holds_back_what_may_wait_but_not_the_step_or_the_heartbeat() {
        let spent = Waiting {
            budget_allows: false,
            ..ALL
        };
        assert_eq!(next_source(&spent), Source::Step);
        let no_step = Waiting {
            step: false,
            ..spent
        };
        assert_eq!(next_source(&no_step), Source::Heartbeat);
        let flood = Waiting {
            step: false,
            heartbeat_due: false,
            ..spent
        };
        assert_eq!(next_source(&flood), Source::Wait);
    }

    #[test]
    fn a_waiting_task_wakes_for_the_heartbeat_the_budget_or_the_telemetry() {
        assert_eq!(wake_at(1_000, false, 400, Some(200)), 400);
        assert_eq!(wake_at(1_000, true, 400, Some(200)), 200);
        assert_eq!(wake_at(1_000, true, 400, None), 1_000);
        assert_eq!(wake_at(300, false, 400, None), 300);
    }
}
