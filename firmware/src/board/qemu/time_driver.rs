//! embassy's time driver on the mps2-an500's two CMSDK APB timers (Arm CMSDK technical
//! reference, "APB timer"; QEMU's `hw/timer/cmsdk-apb-timer.c`), both at 25 MHz.
//!
//! - Timer 0 counts down from `0xFFFF_FFFF` forever; its interrupt at each wrap (every 171 s)
//!   extends it to 64 bits. [`raw_count`] is its count as an up-counter.
//! - Timer 1 is the alarm: loaded with the counts to the next expiry of embassy's timer queue,
//!   it interrupts at zero and is stopped there.
//!
//! embassy's tick is 1 us (`tick-hz-1_000_000`): 25 counts. Under `qemu-system-arm -icount
//! shift=0` the virtual clock runs at one instruction per nanosecond, so one count is 40
//! instructions.

use core::cell::{Cell, RefCell};
use core::ptr::{read_volatile, write_volatile};
use core::task::Waker;

use critical_section::{CriticalSection, Mutex};
use embassy_time_driver::Driver;
use embassy_time_queue_utils::Queue;

const TIMER0: usize = 0x4000_0000;
const TIMER1: usize = 0x4000_1000;
const CTRL: usize = 0x00;
const VALUE: usize = 0x04;
const RELOAD: usize = 0x08;
const INTSTATUS: usize = 0x0C;

const CTRL_ENABLE: u32 = 1 << 0;
const CTRL_IRQ_ENABLE: u32 = 1 << 3;
const INT_FIRED: u32 = 1 << 0;

/// Timer counts per embassy tick (25 MHz / 1 MHz).
const COUNTS_PER_TICK: u64 = 25;

fn read(addr: usize) -> u32 {
    // SAFETY: a register of timer 0 or 1 on this board.
    unsafe { read_volatile(addr as *const u32) }
}

fn write(addr: usize, value: u32) {
    // SAFETY: a register of timer 0 or 1 on this board.
    unsafe { write_volatile(addr as *mut u32, value) }
}

struct CmsdkTimeDriver {
    /// Wraps of timer 0 accounted for.
    wraps: Mutex<Cell<u32>>,
    queue: Mutex<RefCell<Queue>>,
}

embassy_time_driver::time_driver_impl!(static DRIVER: CmsdkTimeDriver = CmsdkTimeDriver {
    wraps: Mutex::new(Cell::new(0)),
    queue: Mutex::new(RefCell::new(Queue::new())),
});

/// Starts timer 0 free-running and leaves timer 1 stopped.
pub fn init() {
    write(TIMER0 + CTRL, 0);
    write(TIMER0 + RELOAD, u32::MAX);
    write(TIMER0 + VALUE, u32::MAX);
    write(TIMER0 + INTSTATUS, INT_FIRED);
    write(TIMER0 + CTRL, CTRL_ENABLE | CTRL_IRQ_ENABLE);
    write(TIMER1 + CTRL, 0);
    write(TIMER1 + INTSTATUS, INT_FIRED);
}

/// Timer 0's count since start, wrapping at 2^32 (one count per 40 ns of virtual time).
pub fn raw_count() -> u32 {
    u32::MAX - read(TIMER0 + VALUE)
}

impl CmsdkTimeDriver {
    /// Counts since start, 64-bit.
    fn counts(&self, cs: CriticalSection<'_>) -> u64 {
        // A wrap not yet accounted for shows as a pending interrupt; read the count on both
        // sides of it so the pair is consistent.
        let before = raw_count();
        let pending = read(TIMER0 + INTSTATUS) & INT_FIRED != 0;
        let after = raw_count();
        let mut wraps = u64::from(self.wraps.borrow(cs).get());
        let count = if pending {
            wraps += 1;
            // The wrap happened before `after` was read; if `after` still looks pre-wrap the
            // interrupt was already pending before, and `after` is post-wrap anyway.
            after
        } else {
            before.max(after)
        };
        (wraps << 32) | u64::from(count)
    }

    /// Arms timer 1 for tick `at`; false if `at` is already past (the caller then services
    /// the queue again).
    fn set_alarm(&self, cs: CriticalSection<'_>, at: u64) -> bool {
        write(TIMER1 + CTRL, 0);
        write(TIMER1 + INTSTATUS, INT_FIRED);
        if at == u64::MAX {
            return true;
        }
        let now = self.counts(cs);
        let target = at.saturating_mul(COUNTS_PER_TICK);
        if target <= now {
            return false;
        }
        // A far alarm is cut to one timer period; its interrupt then re-arms for the rest.
        let delta = (target - now).min(u64::from(u32::MAX)) as u32;
        write(TIMER1 + RELOAD, delta);
        write(TIMER1 + CTRL, CTRL_ENABLE | CTRL_IRQ_ENABLE);
        true
    }

    fn service_queue(&self, cs: CriticalSection<'_>) {
        let mut queue = self.queue.borrow(cs).borrow_mut();
        let mut next = queue.next_expiration(self.counts(cs) / COUNTS_PER_TICK);
        while !self.set_alarm(cs, next) {
            next = queue.next_expiration(self.counts(cs) / COUNTS_PER_TICK);
        }
    }
}

impl Driver for CmsdkTimeDriver {
    fn now(&self) -> u64 {
        critical_section::with(|cs| self.counts(cs) / COUNTS_PER_TICK)
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        critical_section::with(|cs| {
            let changed = self.queue.borrow(cs).borrow_mut().schedule_wake(at, waker);
            if changed {
                self.service_queue(cs);
            }
        });
    }
}

/// Timer 0 wrapped: one more period of 2^32 counts.
pub extern "C" fn on_timer0_interrupt() {
    critical_section::with(|cs| {
        if read(TIMER0 + INTSTATUS) & INT_FIRED != 0 {
            write(TIMER0 + INTSTATUS, INT_FIRED);
            let wraps = DRIVER.wraps.borrow(cs);
            wraps.set(wraps.get().wrapping_add(1));
        }
    });
}

/// Timer 1 reached the alarm: wake what is due and arm the next one.
pub extern "C" fn on_timer1_interrupt() {
    critical_section::with(|cs| {
        write(TIMER1 + CTRL, 0);
        write(TIMER1 + INTSTATUS, INT_FIRED);
        DRIVER.service_queue(cs);
    });
}
