//! The firmware on QEMU's mps2-an500 (`cargo fw-qemu`): the hardware-in-the-loop target.
#![no_std]
#![no_main]

use cortex_m_rt::entry;

#[entry]
fn main() -> ! {
    let parts = firmware::board::qemu::init();
    firmware::app::run(parts, |_, _| {}, |_| {})
}
