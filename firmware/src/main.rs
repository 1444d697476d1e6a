//! Flight-controller firmware for a payload carried by rail-riding rotor robots, on a
//! Pixhawk 6C-class board (STM32H743).
//!
//! A thin layer: the board (clocks, pins), drivers and tasks with their timing. Every
//! algorithm lives in the `shared` crate, which the simulator runs unchanged.
#![no_std]
#![no_main]

mod board;
mod tasks;

use defmt_rtt as _;
use embassy_executor::Spawner;
use panic_probe as _;

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let board = board::Board::init();
    defmt::info!(
        "flight controller up: core {} MHz from a {} MHz crystal",
        board::CORE_HZ / 1_000_000,
        board::HSE_HZ / 1_000_000
    );
    let board::Leds { red: _red, blue } = board.leds;
    match tasks::heartbeat::heartbeat(blue) {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("heartbeat task not spawned: {}", e),
    }
    match tasks::control::control_loop() {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("control task not spawned: {}", e),
    }
}
