//! The Pixhawk 6C's RC receiver port (docs/hardware.md#rc-receivers): GPS2's UART8, receive
//! only (RX PE0, DMA2 stream 5), reconfigured for the protocol's line (CRSF 420,000 baud 8N1;
//! SBUS 100,000 baud 8E2 with the RX pin inverted by the UART itself, `USART_CR2.RXINV`), read
//! until the line goes idle. TELEM3 (USART2) is the stepper bus of robots 5-8 in this firmware
//! and is not handed to the receiver: a receiver there is refused with the reason.

use embassy_stm32::mode::Async;
use embassy_stm32::usart::{self, Parity, StopBits, UartRx};

use super::{RcRead, RcSerial};
use drivers::rc_receiver::{LineSettings, RcPort};

/// The receiver's UART (GPS2's UART8), `None` if it refused its first configuration.
pub struct RcUart {
    rx: Option<UartRx<'static, Async>>,
}

/// The UART settings for a receiver's line.
pub fn config(line: LineSettings) -> usart::Config {
    let mut config = usart::Config::default();
    config.baudrate = line.baud;
    config.parity = if line.even_parity {
        Parity::ParityEven
    } else {
        Parity::ParityNone
    };
    config.stop_bits = if line.two_stop_bits {
        StopBits::STOP2
    } else {
        StopBits::STOP1
    };
    config.invert_rx = line.inverted;
    config
}

impl RcUart {
    /// The port over UART8's receiver (`None`: it refused its configuration at start).
    pub fn new(rx: Option<UartRx<'static, Async>>) -> Self {
        Self { rx }
    }
}

impl RcSerial for RcUart {
    fn open(&mut self, port: RcPort, line: LineSettings) -> Result<(), &'static str> {
        match port {
            RcPort::Gps2 => {
                let rx = self
                    .rx
                    .as_mut()
                    .ok_or("GPS2's UART8 refused its configuration at start")?;
                rx.set_config(&config(line))
                    .map_err(|_| "UART8 refused the line settings")
            }
            RcPort::Telem3 => Err(
                "TELEM3's USART2 drives the steppers of robots 5-8 in this firmware; wire the receiver to GPS2 (RC_PORT_CONFIG 202)",
            ),
            RcPort::None => Err("no port"),
        }
    }

    async fn read(&mut self, buf: &mut [u8]) -> RcRead {
        let Some(rx) = self.rx.as_mut() else {
            return core::future::pending().await;
        };
        match rx.read_until_idle(buf).await {
            Ok(len) => RcRead {
                len,
                line_error: false,
                idle: true,
            },
            // The bytes of a read that failed are not given: what was cut is dropped whole.
            Err(_) => RcRead {
                len: 0,
                line_error: true,
                idle: true,
            },
        }
    }
}
