//! The firmware on a Pixhawk 6C (`cargo fw`, flashed with `cargo fw-run` or the PX4
//! bootloader).
#![no_std]
#![no_main]

use cortex_m_rt::entry;

#[entry]
fn main() -> ! {
    let (parts, board) = firmware::board::pixhawk6c::init();
    let firmware::board::pixhawk6c::BoardParts {
        leds,
        control_tasks,
    } = board;
    firmware::app::run(
        parts,
        move |control, link| {
            firmware::board::pixhawk6c::spawn_control_tasks(control, link, control_tasks)
        },
        move |spawner| firmware::board::pixhawk6c::spawn_tasks(spawner, leds),
    )
}
