//! The Pixhawk 6C's ICM-42688-P on SPI1: SCK PA5, MISO PA6, MOSI PA7, chip select
//! PC13, data ready (INT1) PE6, as PX4's `fmu-v6c/src/spi.cpp` wires it; mounted yaw 270 deg
//! (`init/rc.board_sensors`: `icm42688p -R 6`). The driver core is [`drivers::icm42688`] and
//! [`drivers::imu`]; this task is its glue.
//!
//! Start-up: soft reset, `WHO_AM_I`, the start-up writes each read back. Then, at the control
//! priority: on each data-ready interrupt (two FIFO records, 1 ms at 2 kHz) the FIFO is read
//! in one DMA burst, filtered and notched at each rotor's rotation and blade-pass frequencies
//! from the ESCs' RPM ([`drivers::rotor_notch`]); every 2.5 ms the latest filtered sample goes to the control
//! step (until a HIL plant drives it instead). A stalled, saturated or wrong IMU goes to the
//! ground as an error, once a second while it lasts, and to the mission ([`FAULTED`]), which
//! stops on the ground and lands in flight; the step goes on with the last sample meanwhile.

use core::sync::atomic::{AtomicBool, Ordering};

use drivers::icm42688::{self, PACKET_LEN, READ, START, reg};
use drivers::imu::{ImuFault, ImuFrontEnd, Mounting};
use embassy_futures::select::{Either, select};
use embassy_stm32::exti::ExtiInput;
use embassy_stm32::gpio::Output;
use embassy_stm32::mode::Async;
use embassy_stm32::spi::Spi;
use embassy_stm32::spi::mode::Master;
use embassy_time::{Duration, Instant, Ticker, Timer};
use link::hil::ImuSample;
use shared::control::vector::Vec3;

use crate::app::autonomy::Severity;
use crate::app::comms::{SensorSample, report};
use crate::app::{ESC_RPM, IN_HIL, OUTBOX, SENSOR};

/// Whether the IMU is faulted now (stalled, saturated): the control step tells the mission.
pub static FAULTED: AtomicBool = AtomicBool::new(false);

/// Cut-off of the anti-alias filter before decimation to 400 Hz, Hz.
pub const CUTOFF_HZ: f32 = 80.0;
/// Records read in one burst at most (the rest wait for the next interrupt).
const MAX_RECORDS: usize = 8;
/// The control step's period.
const TICK: Duration = Duration::from_micros(2500);

/// The IMU's bus and pins.
pub struct ImuBus {
    /// SPI1, with DMA.
    pub spi: Spi<'static, Async, Master>,
    /// Chip select (PC13), active low.
    pub cs: Output<'static>,
    /// INT1 (PE6).
    pub drdy: ExtiInput<'static, Async>,
}

impl ImuBus {
    async fn transfer(&mut self, buf: &mut [u8]) -> bool {
        self.cs.set_low();
        let ok = self.spi.transfer_in_place(buf).await.is_ok();
        self.cs.set_high();
        ok
    }

    async fn read(&mut self, register: u8) -> Option<u8> {
        let mut buf = [register | READ, 0];
        self.transfer(&mut buf).await.then_some(buf[1])
    }

    async fn write(&mut self, register: u8, value: u8) -> bool {
        self.transfer(&mut [register, value]).await
    }

    /// Resets and configures the IMU; the fault if it is not there or refuses a setting.
    async fn start(&mut self) -> Result<(), ImuFault> {
        self.write(reg::REG_BANK_SEL, 0).await;
        self.write(reg::DEVICE_CONFIG, icm42688::SOFT_RESET).await;
        Timer::after_millis(2).await;
        let id = self.read(reg::WHO_AM_I).await.unwrap_or(0);
        if id != icm42688::WHO_AM_I_VALUE {
            return Err(ImuFault::WrongDevice(id));
        }
        for (register, value) in START {
            self.write(register, value).await;
            if self.read(register).await != Some(value) {
                return Err(ImuFault::WrongDevice(id));
            }
        }
        // The gyro needs 30 ms in low-noise mode; then start from an empty FIFO.
        Timer::after_millis(50).await;
        self.write(reg::SIGNAL_PATH_RESET, icm42688::FIFO_FLUSH)
            .await;
        Ok(())
    }

    /// Reads the waiting FIFO records into `front`.
    async fn drain(&mut self, front: &mut ImuFrontEnd) {
        let mut count = [reg::FIFO_COUNTH | READ, 0, 0];
        if !self.transfer(&mut count).await {
            return;
        }
        let records = usize::from(icm42688::fifo_records(count[1], count[2])).min(MAX_RECORDS);
        if records == 0 {
            return;
        }
        let mut buf = [0u8; 1 + MAX_RECORDS * PACKET_LEN];
        buf[0] = reg::FIFO_DATA | READ;
        let len = 1 + records * PACKET_LEN;
        if !self.transfer(&mut buf[..len]).await {
            return;
        }
        for packet in buf[1..len].chunks_exact(PACKET_LEN) {
            let Ok(packet) = <&[u8; PACKET_LEN]>::try_from(packet) else {
                continue;
            };
            if let Ok(sample) = icm42688::parse_packet(packet) {
                front.push(sample.gyro_rad_s(), sample.accel_m_s2(), sample.saturated());
            }
        }
    }
}

/// Runs the IMU forever.
#[embassy_executor::task]
pub async fn imu(mut bus: ImuBus) {
    while let Err(fault) = bus.start().await {
        let _ = OUTBOX.try_send(report(Severity::Critical, format_args!("{fault}")));
        Timer::after_secs(1).await;
    }
    let mut front = ImuFrontEnd::new(Mounting::Yaw270, icm42688::ODR_HZ, CUTOFF_HZ);
    let mut ticker = Ticker::every(TICK);
    let mut last_fault_report: Option<Instant> = None;
    loop {
        match select(bus.drdy.wait_for_rising_edge(), ticker.next()).await {
            Either::First(()) => bus.drain(&mut front).await,
            Either::Second(()) => {
                // The notches follow the rotors' speeds of the last control step that had
                // them (bidirectional DShot); without telemetry nothing is notched.
                match ESC_RPM.lock(|r| r.get()) {
                    Some(rpm) => front.follow_rotors(&rpm),
                    None => front.follow_rotors(&[]),
                }
                // Whatever the interrupt left (it re-fires each sample above the watermark,
                // so a missed edge only delays a read to here).
                bus.drain(&mut front).await;
                let reading = front.tick();
                if IN_HIL.load(Ordering::Relaxed) {
                    continue;
                }
                FAULTED.store(reading.is_err(), Ordering::Relaxed);
                // On a fault the step still runs (on the last sample): the mission sees the
                // fault and lands, and the watchdog stays fed.
                if let Some(tick) = front.latest() {
                    let [gx, gy, gz] = tick.gyro;
                    let [ax, ay, az] = tick.accel;
                    let sample = SensorSample {
                        time_us: Instant::now().as_micros(),
                        imu: ImuSample {
                            gyro: Vec3::new(gx, gy, gz),
                            accel: Vec3::new(ax, ay, az),
                        },
                        hil: false,
                    };
                    let _ = SENSOR.try_send(sample);
                }
                if let Err(fault) = reading {
                    let now = Instant::now();
                    if last_fault_report
                        .is_none_or(|t| now.duration_since(t) >= Duration::from_secs(1))
                    {
                        last_fault_report = Some(now);
                        let _ =
                            OUTBOX.try_send(report(Severity::Critical, format_args!("{fault}")));
                    }
                }
            }
        }
    }
}
