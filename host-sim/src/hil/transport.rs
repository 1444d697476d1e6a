//! The byte link to the firmware, whatever carries it (docs/firmware.md#hil-transports):
//! QEMU's emulated Ethernet controller, each frame a UDP datagram on this machine
//! (`--qemu`, the fast default), QEMU's UART bridged to a local TCP socket (`--qemu
//! --qemu-link uart`, `--connect tcp:HOST:PORT`) or a serial device (`--serial DEV`: a real
//! board on USB or a UART adapter, or QEMU's `-serial pty`).
//!
//! [`Link`] frames it with the `link` crate's parser and encoder (the same code the firmware
//! runs), reads with a deadline, and lets a second thread (the ground-station bridge) write
//! whole frames in between. What one call writes goes out together: on Ethernet as one frame.

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream, UdpSocket};
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use link::MessageData;
use link::frame::{Encoder, Frame, Integrity, Parser};
use link::hil_ethernet::{self, MAX_PAYLOAD, PLANT_MAC, VEHICLE_MAC};
use link::msg::STATUSTEXT_DATA;
use link::signing::Signing;
use link::status::StatusChunk;
use link::vehicle::crc_extra;

/// Where the firmware is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Endpoint {
    /// A TCP server (QEMU's UART bridged to a socket): `tcp:HOST:PORT`.
    Tcp(String),
    /// A serial device at a baud rate.
    Serial {
        /// Device path (`/dev/ttyACM0`, `/dev/pts/3`).
        path: String,
        /// Baud rate (ignored by USB CDC-ACM and ptys).
        baud: u32,
    },
}

impl Endpoint {
    /// Parses `tcp:HOST:PORT`.
    pub fn parse_tcp(text: &str) -> Result<Self, String> {
        let Some(addr) = text.strip_prefix("tcp:") else {
            return Err(format!("`{text}` is not tcp:HOST:PORT"));
        };
        match addr.rsplit_once(':') {
            Some((host, port)) if !host.is_empty() && port.parse::<u16>().is_ok() => {
                Ok(Self::Tcp(addr.to_string()))
            }
            _ => Err(format!("`{text}` is not tcp:HOST:PORT")),
        }
    }
}

/// Writes whole frames; shared with the ground-station bridge.
pub type SharedWriter = Arc<Mutex<Box<dyn Write + Send>>>;

/// A framed MAVLink link to the firmware.
pub struct Link {
    reader: Box<dyn Read + Send>,
    writer: SharedWriter,
    parser: Parser,
    encoder: Encoder,
    frame: Frame,
    buf: [u8; 512],
    pending: (usize, usize),
    /// Signs what is sent, with the time signing began.
    signing: Option<(Signing, Instant)>,
    /// Frames encoded by [`Self::batch`] and not yet written.
    batch: Vec<u8>,
    /// Bytes this side has written and read (the ground-station bridge's not counted).
    counts: ByteCounts,
}

/// Bytes that crossed the link.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ByteCounts {
    /// Written to the firmware.
    pub to_firmware: u64,
    /// Read from the firmware.
    pub from_firmware: u64,
}

/// The plant's signing link id. It sends as system 255, component 190, as ground stations
/// do; a signature stream is (system, component, link id), so the plant takes a link id ground
/// stations do not (they count up from 0) and its timestamps never interleave with theirs.
pub const SIGNING_LINK_ID: u8 = 200;

/// How long one read may block before the deadline is checked again.
const READ_SLICE: Duration = Duration::from_millis(50);

impl Link {
    /// Opens `endpoint`.
    pub fn open(endpoint: &Endpoint) -> Result<Self> {
        match endpoint {
            Endpoint::Tcp(addr) => {
                let stream = TcpStream::connect(addr)
                    .with_context(|| format!("cannot connect to the firmware at tcp:{addr}"))?;
                Self::over_tcp(stream)
            }
            Endpoint::Serial { path, baud } => Self::over_serial(Path::new(path), *baud),
        }
    }

    /// A link over an open TCP stream.
    pub fn over_tcp(stream: TcpStream) -> Result<Self> {
        stream.set_nodelay(true)?;
        stream.set_read_timeout(Some(READ_SLICE))?;
        let writer = stream.try_clone().context("cannot share the TCP stream")?;
        Ok(Self::new(Box::new(stream), Box::new(writer)))
    }

    /// A link over a serial device (raw mode, 8N1, no flow control).
    pub fn over_serial(path: &Path, baud: u32) -> Result<Self> {
        let name = path.to_string_lossy().into_owned();
        let port = serialport::new(&name, baud)
            .timeout(READ_SLICE)
            .open_native()
            .with_context(|| format!("cannot open serial device {name}"))?;
        let writer = port
            .try_clone_native()
            .with_context(|| format!("cannot share serial device {name}"))?;
        Ok(Self::new(Box::new(port), Box::new(writer)))
    }

    /// A link over Ethernet frames carried as UDP datagrams (QEMU's `socket` network back
    /// end): `socket` is bound on this machine and `peer` is where QEMU's end listens.
    pub fn over_udp(socket: UdpSocket, peer: SocketAddr) -> Result<Self> {
        socket
            .connect(peer)
            .with_context(|| format!("cannot address the firmware's Ethernet at {peer}"))?;
        socket.set_read_timeout(Some(READ_SLICE))?;
        let writer = FrameWriter {
            socket: socket.try_clone().context("cannot share the UDP socket")?,
            pending: Vec::with_capacity(MAX_PAYLOAD),
        };
        let reader = FrameReader {
            socket,
            datagram: vec![0; 65_536],
            at: 0,
            end: 0,
        };
        Ok(Self::new(Box::new(reader), Box::new(writer)))
    }

    fn new(reader: Box<dyn Read + Send>, writer: Box<dyn Write + Send>) -> Self {
        Self {
            reader,
            writer: Arc::new(Mutex::new(writer)),
            parser: Parser::new(crc_extra),
            encoder: Encoder::new(link::PLANT_SYSTEM_ID, link::PLANT_COMPONENT_ID),
            frame: Frame::default(),
            buf: [0; 512],
            pending: (0, 0),
            signing: None,
            batch: Vec::new(),
            counts: ByteCounts::default(),
        }
    }

    /// Bytes written and read so far.
    pub fn counts(&self) -> ByteCounts {
        self.counts
    }

    /// Signs every frame sent from now on with `key` (MAVLink 2 signing, link id
    /// [`SIGNING_LINK_ID`]), its timestamp the wall clock's.
    pub fn sign_with(&mut self, key: [u8; link::signing::KEY_LEN]) {
        // 10 us units since 2015-01-01 (1,420,070,400 s after the Unix epoch).
        let since_2015 = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_micros().saturating_sub(1_420_070_400_000_000) / 10)
            .unwrap_or(0);
        let mut signing = Signing::new();
        signing.set_key(key, since_2015 as u64, 0, SIGNING_LINK_ID);
        self.signing = Some((signing, Instant::now()));
    }

    fn sign(&mut self, crc_extra: u8) {
        if let Some((signing, since)) = &mut self.signing {
            let uptime_us = since.elapsed().as_micros() as u64;
            signing.sign(&mut self.frame, crc_extra, uptime_us);
        }
    }

    /// The writing half, for the ground-station bridge.
    pub fn writer(&self) -> SharedWriter {
        Arc::clone(&self.writer)
    }

    /// Sends one message.
    pub fn send<M: MessageData>(&mut self, message: &M) -> Result<()> {
        self.encoder.encode(message, &mut self.frame);
        self.sign(M::EXTRA_CRC);
        self.counts.to_firmware += self.frame.bytes().len() as u64;
        write_frame(&self.writer, self.frame.bytes())
    }

    /// Encodes one message into the batch that [`Self::send_batch`] writes.
    pub fn batch<M: MessageData>(&mut self, message: &M) {
        self.encoder.encode(message, &mut self.frame);
        self.sign(M::EXTRA_CRC);
        self.batch.extend_from_slice(self.frame.bytes());
    }

    /// Writes the batched messages in one go (one Ethernet frame), if there are any.
    pub fn send_batch(&mut self) -> Result<()> {
        if self.batch.is_empty() {
            return Ok(());
        }
        self.counts.to_firmware += self.batch.len() as u64;
        let sent = write_frame(&self.writer, &self.batch);
        self.batch.clear();
        sent
    }

    /// Sends one `STATUSTEXT` chunk (with its extension fields).
    pub fn send_text_chunk(&mut self, chunk: &StatusChunk) -> Result<()> {
        chunk.encode(&mut self.encoder, &mut self.frame);
        self.sign(STATUSTEXT_DATA::EXTRA_CRC);
        write_frame(&self.writer, self.frame.bytes())
    }

    /// The next frame, or `None` once `deadline` has passed.
    pub fn receive(&mut self, deadline: Instant) -> Result<Option<(Frame, Integrity)>> {
        loop {
            while self.pending.0 < self.pending.1 {
                let byte = self.buf[self.pending.0];
                self.pending.0 += 1;
                if let Some((frame, integrity)) = self.parser.push(byte) {
                    return Ok(Some((frame.clone(), integrity)));
                }
            }
            if Instant::now() >= deadline {
                return Ok(None);
            }
            match self.reader.read(&mut self.buf) {
                Ok(0) => bail!("the firmware closed the link"),
                Ok(n) => {
                    self.counts.from_firmware += n as u64;
                    self.pending = (0, n);
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                    ) => {}
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(anyhow!(e).context("reading from the firmware")),
            }
        }
    }
}

/// Writes one whole frame under the writer's lock (frames from two threads never interleave).
pub fn write_frame(writer: &SharedWriter, bytes: &[u8]) -> Result<()> {
    let mut w = writer
        .lock()
        .map_err(|_| anyhow!("the link writer was poisoned by a failed thread"))?;
    w.write_all(bytes).context("writing to the firmware")?;
    w.flush().context("writing to the firmware")
}

/// How long a read looks for a datagram before it blocks.
const SPIN: Duration = Duration::from_micros(500);

/// Reads the MAVLink bytes of the Ethernet frames QEMU sends as datagrams.
struct FrameReader {
    socket: UdpSocket,
    datagram: Vec<u8>,
    /// The current frame's MAVLink bytes not yet read, as a range of `datagram`.
    at: usize,
    end: usize,
}

impl Read for FrameReader {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        while self.at >= self.end {
            // The firmware answers a step within a fraction of a millisecond: look for the
            // answer without sleeping for that long, which spares the wake-up of a blocked
            // read (a context switch) on each step; then block as usual.
            let spin_until = Instant::now() + SPIN;
            let mut got = None;
            while got.is_none() && Instant::now() < spin_until {
                got = recv_now(&self.socket, &mut self.datagram);
                std::hint::spin_loop();
            }
            let received = match got {
                Some(n) => Ok(n),
                None => self.socket.recv(&mut self.datagram),
            };
            let n = match received {
                Ok(n) => n,
                // A datagram sent before QEMU opened its socket came back refused: nothing to
                // read yet.
                Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => {
                    return Err(io::ErrorKind::WouldBlock.into());
                }
                Err(e) => return Err(e),
            };
            // A frame that is not the firmware's HIL frame (QEMU's NIC sends nothing else;
            // anything else on the port) carries nothing for us.
            if let Ok(payload) = hil_ethernet::payload(&self.datagram[..n]) {
                self.at = hil_ethernet::HEADER_LEN;
                self.end = self.at + payload.len();
            }
        }
        let n = buf.len().min(self.end - self.at);
        buf[..n].copy_from_slice(&self.datagram[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

/// A datagram already waiting on `socket`, without blocking (`MSG_DONTWAIT`); `None` when
/// there is none (or the socket reports an error, which the blocking read then returns).
#[cfg(unix)]
fn recv_now(socket: &UdpSocket, buf: &mut [u8]) -> Option<usize> {
    use std::os::fd::AsRawFd;
    // SAFETY: `buf` is valid for `buf.len()` bytes for the call; the descriptor is the open
    // socket's.
    let n = unsafe {
        libc::recv(
            socket.as_raw_fd(),
            buf.as_mut_ptr().cast(),
            buf.len(),
            libc::MSG_DONTWAIT,
        )
    };
    usize::try_from(n).ok()
}

/// Elsewhere the read blocks at once.
#[cfg(not(unix))]
fn recv_now(_socket: &UdpSocket, _buf: &mut [u8]) -> Option<usize> {
    None
}

/// Gathers written bytes and sends them on `flush` as Ethernet frames, one datagram each.
struct FrameWriter {
    socket: UdpSocket,
    pending: Vec<u8>,
}

impl Write for FrameWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.pending.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        let mut frame = Vec::with_capacity(hil_ethernet::MAX_FRAME);
        for chunk in self.pending.chunks(MAX_PAYLOAD) {
            frame.clear();
            frame.extend_from_slice(&hil_ethernet::header(VEHICLE_MAC, PLANT_MAC, chunk.len()));
            frame.extend_from_slice(chunk);
            match self.socket.send(&frame) {
                // An earlier datagram, sent before QEMU opened its socket, was refused; that
                // error comes back here and this one was not sent: send it again. (The
                // requests sent before the firmware is up are repeated until it answers.)
                Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => {
                    let _ = self.socket.send(&frame);
                }
                sent => {
                    sent?;
                }
            }
        }
        self.pending.clear();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tcp_endpoints_are_parsed_and_bad_ones_named() {
        assert_eq!(
            Endpoint::parse_tcp("tcp:127.0.0.1:5760"),
            Ok(Endpoint::Tcp("127.0.0.1:5760".into()))
        );
        assert!(Endpoint::parse_tcp("udp:127.0.0.1:5760").is_err());
        assert!(Endpoint::parse_tcp("tcp:127.0.0.1").is_err());
        assert!(Endpoint::parse_tcp("tcp::5760").is_err());
    }
}
