//! The robots' steppers on the Pixhawk 6C: TMC2209 drivers on four single-wire UART buses,
//! TELEM2 (UART5, TX PC12, RX PD2) for robots 1-4, TELEM3 (USART2, TX PD5, RX PA3) for robots
//! 5-8, GPS1 (USART1, TX PB6, RX PA10) for robots 9-12 and the debug port (USART3, TX PD8,
//! RX PD9) for robots 13-16, node addresses 0-3 on each (MS1/MS2), at [`BAUD`]. The first two
//! move their bytes by DMA; the DMA streams left over are too few for the other two, which
//! move theirs by interrupt ([`StepperPort`]). The wiring is the
//! datasheet's for a standard UART: TX through 1 kOhm and RX directly to the drivers' PDN_UART
//! line (docs/hardware.md#the-pixhawk-6cs-wiring), so every request comes back as an echo before the
//! reply; the echo is checked. The driver core is [`drivers::tmc2209`] and
//! [`drivers::stepper`]; this task is its glue.
//!
//! Start-up (and again whenever the stepper parameters change while disarmed): each driver's
//! version is read, then `GCONF`, `CHOPCONF` (microsteps, current range), `IHOLD_IRUN`,
//! `TCOOLTHRS` and `SGTHRS` are written and confirmed by `IFCNT` and by reading `GCONF` and
//! `CHOPCONF` back. Then at [`UPDATE_HZ`] each robot's axis moves by `VACTUAL` towards the
//! position the control step commands (`shared`'s trapezoidal profiles) and its arc length is
//! kept from the velocities commanded; `SG_RESULT` is read, and a stalled robot is stopped,
//! reported to the ground and to the mission ([`STALLED`]: on the ground it stops, in flight
//! it lands).

use core::cell::Cell;
use core::sync::atomic::{AtomicU16, Ordering};

use drivers::stepper::{AxisConfig, RailAxis, StallMonitor};
use drivers::tmc2209::{self, reg};
use embassy_stm32::mode::Async;
use embassy_stm32::usart::{BufferedUart, RingBufferedUartRx, UartTx};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_time::{Duration, Ticker, with_timeout};
use embedded_io_async::Read;
use shared::mission::HardwareConfig;
use shared::rail::stepper::DriveConfig;

use crate::app::autonomy::Severity;
use crate::app::comms::report;
use crate::app::{MISSION_CONFIG, OUTBOX};

/// Baud rate of the stepper buses (the TMC2209 detects it).
pub const BAUD: u32 = 115_200;
/// Axis updates per second.
pub const UPDATE_HZ: u64 = 50;
/// Drivers per bus.
const NODES: usize = 4;
/// Buses, and the robots they drive.
pub const BUSES: usize = 4;
/// Robots the buses drive.
const ROBOTS: usize = NODES * BUSES;
/// Longest wait for a reply (8 bytes take 0.7 ms at 115,200 baud).
const REPLY_TIMEOUT: Duration = Duration::from_millis(3);
/// Low `SG_RESULT` readings in a row that make a stall (0.1 s).
const STALL_READINGS: u8 = 5;
/// StallGuard is trusted above this speed, microsteps/s.
const STALL_MIN_SPEED: f32 = 400.0;

/// The drivers' settings: the part of the hardware parameters the steppers take (a change of
/// any other parameter leaves the drivers alone).
#[derive(Clone, Copy, PartialEq)]
struct StepperSettings {
    drive: DriveConfig,
    stepper_current: f32,
    stepper_r_sense: f32,
    stall_threshold: u8,
}

impl StepperSettings {
    fn of(hw: &HardwareConfig) -> Self {
        Self {
            drive: hw.drive,
            stepper_current: hw.stepper_current,
            stepper_r_sense: hw.stepper_r_sense,
            stall_threshold: hw.stall_threshold,
        }
    }
}

/// Where the control step wants the robots, m of arc, and how many there are.
#[derive(Clone, Copy)]
struct RailTargets {
    positions: [f32; ROBOTS],
    robots: usize,
}

/// Robots whose steppers stalled, bit `j` for robot `j` (the control step reads it; cleared
/// when the drivers are configured again).
pub static STALLED: AtomicU16 = AtomicU16::new(0);

static TARGETS: Mutex<CriticalSectionRawMutex, Cell<Option<RailTargets>>> =
    Mutex::new(Cell::new(None));

/// Hands one control step's rail positions (m, one per robot) to the steppers.
pub fn command(rail: &[f32]) {
    let mut positions = [0.0; ROBOTS];
    for (p, &r) in positions.iter_mut().zip(rail) {
        *p = r;
    }
    let robots = rail.len().min(ROBOTS);
    TARGETS.lock(|t| t.set(Some(RailTargets { positions, robots })));
}

/// How a bus's UART moves its bytes.
pub enum StepperPort {
    /// By DMA: sending, and receiving into a ring (the echo arrives while sending).
    Dma {
        /// The sending half.
        tx: UartTx<'static, Async>,
        /// The receiving half, on a DMA ring.
        rx: RingBufferedUartRx<'static>,
    },
    /// By interrupt, through the driver's buffers.
    Buffered(BufferedUart<'static>),
}

impl StepperPort {
    /// Drops whatever was received and not read.
    fn drain(&mut self) {
        match self {
            Self::Dma { rx, .. } => while embedded_hal_nb::serial::Read::read(rx).is_ok() {},
            Self::Buffered(uart) => while embedded_hal_nb::serial::Read::read(uart).is_ok() {},
        }
    }

    async fn send(&mut self, bytes: &[u8]) -> Result<(), ()> {
        match self {
            Self::Dma { tx, .. } => tx.write(bytes).await.map_err(|_| ()),
            Self::Buffered(uart) => embedded_io_async::Write::write_all(uart, bytes)
                .await
                .map_err(|_| ()),
        }
    }

    async fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), ()> {
        match self {
            Self::Dma { rx, .. } => rx.read_exact(buf).await.map_err(|_| ()),
            Self::Buffered(uart) => uart.read_exact(buf).await.map_err(|_| ()),
        }
    }
}

/// One stepper bus: its UART and the robot its node 0 drives.
pub struct StepperBus {
    /// The UART.
    pub port: StepperPort,
    /// Robot (0-based) of node 0; nodes 1-3 drive the next three.
    pub first_robot: usize,
    /// The bus's name for reports (`TELEM2`).
    pub name: &'static str,
}

impl StepperBus {
    /// Sends `request`, reads its echo and then `reply` (if any); the bus is resynchronised
    /// (stale bytes dropped) first.
    async fn exchange(&mut self, request: &[u8], reply: &mut [u8]) -> Result<(), &'static str> {
        self.port.drain();
        self.port.send(request).await.map_err(|_| "UART error")?;
        let mut echo = [0u8; 8];
        let echo = &mut echo[..request.len().min(8)];
        let port = &mut self.port;
        let received = async {
            port.read_exact(echo).await?;
            port.read_exact(reply).await
        };
        match with_timeout(REPLY_TIMEOUT, received).await {
            Err(_) => Err("no answer"),
            Ok(Err(())) => Err("UART error"),
            Ok(Ok(())) if echo != &request[..echo.len()] => {
                Err("echo garbled: check the 1 kOhm TX resistor")
            }
            Ok(Ok(())) => Ok(()),
        }
    }

    async fn write(&mut self, node: u8, register: u8, value: u32) -> bool {
        let datagram = tmc2209::write_datagram(node, register, value);
        self.exchange(&datagram, &mut []).await.is_ok()
    }

    async fn read(&mut self, node: u8, register: u8) -> Result<u32, &'static str> {
        let mut reply = [0u8; 8];
        self.exchange(&tmc2209::read_request(node, register), &mut reply)
            .await?;
        tmc2209::parse_reply(&reply, register).map_err(|e| match e {
            tmc2209::ReplyError::Crc => "bad CRC",
            _ => "garbled reply",
        })
    }

    /// Configures driver `node`; why not, if it cannot be.
    async fn configure(&mut self, node: u8, hw: &StepperSettings) -> Result<(), &'static str> {
        let version = (self.read(node, reg::IOIN).await? >> 24) as u8;
        if version != tmc2209::VERSION {
            return Err("not a TMC2209");
        }
        let microsteps = u16::try_from(hw.drive.microsteps).unwrap_or(0);
        let writes = tmc2209::settings(
            hw.stepper_current,
            hw.stepper_r_sense,
            microsteps,
            hw.stall_threshold,
        )
        .map_err(|e| match e {
            tmc2209::SettingsError::Current(_) => "current outside the sense resistors' range",
            tmc2209::SettingsError::Microsteps(_) => "microsteps not a power of two up to 256",
        })?;
        let before = self.read(node, reg::IFCNT).await?;
        for (register, value) in writes {
            if !self.write(node, register, value).await {
                return Err("UART error");
            }
        }
        let after = self.read(node, reg::IFCNT).await?;
        if !tmc2209::writes_counted(before, after, writes.len()) {
            return Err("writes not all taken (IFCNT)");
        }
        if self.read(node, reg::GCONF).await? & 0x3FF != writes[0].1
            || self.read(node, reg::CHOPCONF).await? != writes[1].1
        {
            return Err("settings did not read back");
        }
        Ok(())
    }
}

fn axis_config(hw: &StepperSettings) -> AxisConfig {
    let limits = MISSION_CONFIG.lock(|c| c.get().rail_limits);
    AxisConfig {
        drive: hw.drive,
        // A margin over the profiles' top speed, so the axis catches up.
        max_speed_m_s: 1.5 * limits.max_speed,
    }
}

/// What the task keeps of one bus's drivers.
struct BusDrivers {
    ready: [bool; NODES],
    axes: [Option<RailAxis>; NODES],
    stalls: [StallMonitor; NODES],
    stalled: [bool; NODES],
}

impl BusDrivers {
    const NONE: Self = Self {
        ready: [false; NODES],
        axes: [None; NODES],
        stalls: [StallMonitor::new(0, STALL_READINGS, STALL_MIN_SPEED); NODES],
        stalled: [false; NODES],
    };

    /// Configures every driver on `bus` with `settings`, reporting those that fail.
    async fn configure(&mut self, bus: &mut StepperBus, settings: &StepperSettings) {
        for node in 0..NODES {
            let robot = bus.first_robot + node + 1;
            self.ready[node] = match bus.configure(node as u8, settings).await {
                Ok(()) => true,
                Err(why) => {
                    let _ = OUTBOX.try_send(report(
                        Severity::Warning,
                        format_args!("stepper of robot {robot} ({} node {node}): {why}", bus.name),
                    ));
                    false
                }
            };
            self.axes[node] = None;
            self.stalled[node] = false;
            STALLED.fetch_and(!(1u16 << (bus.first_robot + node)), Ordering::Relaxed);
            self.stalls[node] =
                StallMonitor::new(settings.stall_threshold, STALL_READINGS, STALL_MIN_SPEED);
        }
    }

    /// Moves each robot on `bus` one update towards `targets`, watching for stalls.
    async fn update(
        &mut self,
        bus: &mut StepperBus,
        settings: &StepperSettings,
        targets: &RailTargets,
        dt: f32,
    ) {
        for node in 0..NODES {
            let robot = bus.first_robot + node;
            if !self.ready[node] || robot >= targets.robots {
                continue;
            }
            let target = targets.positions[robot];
            // The arc length starts at the first position commanded (the robots' start).
            let axis =
                self.axes[node].get_or_insert_with(|| RailAxis::new(axis_config(settings), target));
            let vactual = if self.stalled[node] {
                0
            } else {
                axis.update(target, dt)
            };
            bus.write(node as u8, reg::VACTUAL, tmc2209::vactual_register(vactual))
                .await;
            if settings.stall_threshold == 0 || self.stalled[node] {
                continue;
            }
            if let Ok(sg) = bus.read(node as u8, reg::SG_RESULT).await
                && self.stalls[node].update(sg, vactual)
            {
                self.stalled[node] = true;
                STALLED.fetch_or(1u16 << robot, Ordering::Relaxed);
                axis.stop();
                bus.write(node as u8, reg::VACTUAL, 0).await;
                let _ = OUTBOX.try_send(report(
                    Severity::Critical,
                    format_args!(
                        "robot {} stalled on the rail; its stepper stopped",
                        robot + 1
                    ),
                ));
            }
        }
    }
}

/// Runs two stepper buses forever, one after the other in each update: four drivers take
/// about 7 ms of a bus at [`BAUD`] (a write and a read each), so two fit the 20 ms of an
/// update, and the two tasks' memory is half of four's.
#[embassy_executor::task(pool_size = 2)]
pub async fn steppers(mut buses: [Option<StepperBus>; 2]) {
    let mut ticker = Ticker::every(Duration::from_micros(1_000_000 / UPDATE_HZ));
    let dt = 1.0 / UPDATE_HZ as f32;
    let mut hw: Option<StepperSettings> = None;
    let mut drivers = [BusDrivers::NONE, BusDrivers::NONE];
    loop {
        ticker.next().await;
        let armed = crate::app::ARMED.load(core::sync::atomic::Ordering::Relaxed);
        let settings = StepperSettings::of(&MISSION_CONFIG.lock(|c| c.get().hardware));
        if !armed && hw != Some(settings) {
            hw = Some(settings);
            for (bus, d) in buses.iter_mut().zip(&mut drivers) {
                if let Some(bus) = bus {
                    d.configure(bus, &settings).await;
                }
            }
        }
        let Some(settings) = hw else { continue };
        let Some(targets) = TARGETS.lock(|t| t.get()) else {
            continue;
        };
        for (bus, d) in buses.iter_mut().zip(&mut drivers) {
            if let Some(bus) = bus {
                d.update(bus, &settings, &targets, dt).await;
            }
        }
    }
}
