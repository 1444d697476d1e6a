//! What the link's send task sends next (docs/ground-link.md#under-a-flood): a control step's
//! messages at once, the heartbeat when due, then only while the link's byte budget holds
//! bytes the replies, the telemetry streams due, the bulk transfers and the parameter lists,
//! in that order. A ground station that asks faster than the link carries fills its own
//! queues, never the vehicle's step or heartbeat.
//!
//! The heartbeat's second is the board's and the vehicle's ([`HeartbeatClock`]): on a flight
//! controller they are one clock, but in lockstep hardware-in-the-loop the vehicle's time is
//! the plant's (the control steps' time) while the board's is the emulator's, which runs
//! behind both it and the wall. A heartbeat timed by the board alone then came once every 4 to
//! 6 s of the vehicle's time, and MAVSDK (3 s without one) took the vehicle for gone and back
//! again in the middle of a mission. PX4 in lockstep keeps its 1 Hz in the simulator's time.

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

/// When the heartbeat is due: a second after the last one by the board's clock, or by the
/// vehicle's time (the control steps' time, us), whichever comes first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HeartbeatClock {
    /// The board's time of the next heartbeat, us.
    next_board_us: u64,
    /// The latest control step's time, us, once a step came.
    vehicle_us: Option<u64>,
    /// The vehicle's time of the next heartbeat, us.
    next_vehicle_us: u64,
}

impl HeartbeatClock {
    /// The heartbeat's period, us (MAVLink's 1 Hz).
    pub const PERIOD_US: u64 = 1_000_000;

    /// A clock whose first heartbeat is due at once.
    pub const fn new() -> Self {
        Self {
            next_board_us: 0,
            vehicle_us: None,
            next_vehicle_us: 0,
        }
    }

    /// A control step of the vehicle's time `time_us` was sent. A time that goes back (a
    /// plant started anew) starts the vehicle's second again from it.
    pub fn step_time(&mut self, time_us: u64) {
        match self.vehicle_us {
            Some(before) if time_us >= before => {}
            _ => self.next_vehicle_us = time_us.saturating_add(Self::PERIOD_US),
        }
        self.vehicle_us = Some(time_us);
    }

    /// Whether the heartbeat is due at the board's time `board_us`.
    pub fn due(&self, board_us: u64) -> bool {
        board_us >= self.next_board_us || self.vehicle_us.is_some_and(|t| t >= self.next_vehicle_us)
    }

    /// The heartbeat was sent at the board's time `board_us`.
    pub fn sent(&mut self, board_us: u64) {
        self.next_board_us = board_us.saturating_add(Self::PERIOD_US);
        if let Some(t) = self.vehicle_us {
            self.next_vehicle_us = t.saturating_add(Self::PERIOD_US);
        }
    }

    /// The board's time by which the next heartbeat is due, us (the vehicle's time moves on
    /// only with a step, which wakes the send task anyway).
    pub fn next_board_us(&self) -> u64 {
        self.next_board_us
    }
}

impl Default for HeartbeatClock {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SECOND: u64 = HeartbeatClock::PERIOD_US;

    #[test]
    fn on_one_clock_the_heartbeat_comes_once_a_second() {
        let mut c = HeartbeatClock::new();
        assert!(c.due(0));
        c.sent(0);
        let mut beats = 0;
        for ms in 1..=10_000u64 {
            let t = ms * 1000;
            c.step_time(t);
            if c.due(t) {
                c.sent(t);
                beats += 1;
            }
        }
        assert_eq!(beats, 10);
    }

    #[test]
    fn a_board_clock_behind_the_vehicles_time_still_beats_each_vehicle_second() {
        // The emulator's clock at a fifth of the plant's time: 60 s of flight.
        let mut c = HeartbeatClock::new();
        c.step_time(0);
        c.sent(0);
        let mut beats = 0;
        for step in 1..=24_000u64 {
            let vehicle = step * 2_500;
            let board = vehicle / 5;
            c.step_time(vehicle);
            if c.due(board) {
                c.sent(board);
                beats += 1;
            }
        }
        assert_eq!(beats, 60);
        assert_eq!(c.next_board_us(), 12_000_000 + SECOND);
    }

    #[test]
    fn without_steps_the_boards_clock_alone_times_it() {
        let mut c = HeartbeatClock::new();
        c.sent(5 * SECOND);
        assert!(!c.due(6 * SECOND - 1));
        assert!(c.due(6 * SECOND));
    }

    #[test]
    fn a_vehicle_time_that_starts_again_restarts_its_second() {
        let mut c = HeartbeatClock::new();
        c.step_time(100 * SECOND);
        c.sent(0);
        c.step_time(SECOND / 2);
        assert!(!c.due(1));
        c.step_time(SECOND + SECOND / 2);
        assert!(c.due(1));
    }

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
