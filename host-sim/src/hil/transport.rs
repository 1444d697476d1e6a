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
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, SyncSender, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::{self, JoinHandle};
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
    /// The datagrams from the firmware the host dropped, when the link can tell
    /// ([`Self::host_drops`]).
    host_drops: Option<HostDrops>,
}

/// Reads how many datagrams the host dropped for the link's socket.
type HostDrops = Box<dyn Fn() -> Option<u64> + Send>;

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
        ask_receive_buffer(&socket, RECEIVE_BUFFER);
        let writer = FrameWriter {
            socket: socket.try_clone().context("cannot share the UDP socket")?,
            pending: Vec::with_capacity(MAX_PAYLOAD),
        };
        let drops = socket_drops(&socket);
        let reader = FrameReader::start(socket).context("cannot start the link's reader")?;
        let mut link = Self::new(Box::new(reader), Box::new(writer));
        link.host_drops = drops;
        Ok(link)
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
            host_drops: None,
        }
    }

    /// Bytes written and read so far.
    pub fn counts(&self) -> ByteCounts {
        self.counts
    }

    /// Datagrams from the firmware this machine dropped so far (its socket's buffer was
    /// full), for a link of datagrams on Linux; `None` where it cannot be told.
    pub fn host_drops(&self) -> Option<u64> {
        self.host_drops.as_ref().and_then(|drops| drops())
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

/// Ethernet frames the drain thread holds for the session at most (then it waits, and the
/// socket's own buffer fills): far more than a flood puts out while the session is busy.
const DRAINED_FRAMES: usize = 1 << 16;

/// The receive buffer asked of the kernel for the socket from QEMU, bytes (granted up to
/// `net.core.rmem_max`): room for the frames that come while the drain thread waits for a
/// core.
const RECEIVE_BUFFER: usize = 4 << 20;

/// One Ethernet frame's MAVLink bytes, or why the socket failed.
type Drained = io::Result<Vec<u8>>;

/// Reads the MAVLink bytes of the Ethernet frames QEMU sends as datagrams.
///
/// A thread of its own drains the socket into a queue as each datagram comes: QEMU has no
/// flow control towards this process, and the firmware sends each message group as one
/// datagram, so a flood's answers (a parameter list restarted 200 times a second, one
/// `PARAM_VALUE` a datagram) fill the kernel's buffer (about 200 small datagrams by default)
/// in a few milliseconds whenever the session does not read: while it paces the run
/// (`--speed`), forwards frames to a ground station, or waits for a core on a loaded machine.
/// The kernel then drops what comes, the step's `HIL_ACTUATOR_CONTROLS` among the rest, and
/// the lockstep waited for a reply the firmware had sent.
struct FrameReader {
    frames: Receiver<Drained>,
    /// The current frame's MAVLink bytes, and the next of them to read.
    frame: Vec<u8>,
    at: usize,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FrameReader {
    /// Starts draining `socket` (its read timeout set: the thread looks at its stop flag
    /// between reads).
    fn start(socket: UdpSocket) -> io::Result<Self> {
        let (to_session, frames) = mpsc::sync_channel(DRAINED_FRAMES);
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = Arc::clone(&stop);
            thread::Builder::new()
                .name("hil-link-rx".into())
                .spawn(move || drain(&socket, &to_session, &stop))?
        };
        Ok(Self {
            frames,
            frame: Vec::new(),
            at: 0,
            stop,
            thread: Some(thread),
        })
    }
}

/// Moves every HIL frame's MAVLink bytes from `socket` to `to_session` until `stop` or the
/// session is gone; a socket error goes to the session and ends it.
fn drain(socket: &UdpSocket, to_session: &SyncSender<Drained>, stop: &AtomicBool) {
    let mut datagram = vec![0u8; 65_536];
    while !stop.load(Ordering::Relaxed) {
        let n = match socket.recv(&mut datagram) {
            Ok(n) => n,
            // Nothing yet; or a datagram sent before QEMU opened its socket came back
            // refused: nothing to read yet either.
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock
                        | io::ErrorKind::TimedOut
                        | io::ErrorKind::Interrupted
                        | io::ErrorKind::ConnectionRefused
                ) =>
            {
                continue;
            }
            Err(e) => {
                let _ = to_session.send(Err(e));
                return;
            }
        };
        // A frame that is not the firmware's HIL frame (QEMU's NIC sends nothing else;
        // anything else on the port) carries nothing for us.
        let Ok(payload) = hil_ethernet::payload(&datagram[..n]) else {
            continue;
        };
        if to_session.send(Ok(payload.to_vec())).is_err() {
            return;
        }
    }
}

impl Read for FrameReader {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let gone = || io::Error::new(io::ErrorKind::BrokenPipe, "the link's reader stopped");
        while self.at >= self.frame.len() {
            // The firmware answers a step within a fraction of a millisecond: look for the
            // answer without sleeping for that long, which spares the wake-up of a blocked
            // read (a context switch) on each step; then block as usual.
            let spin_until = Instant::now() + SPIN;
            let mut got = None;
            while got.is_none() && Instant::now() < spin_until {
                match self.frames.try_recv() {
                    Ok(frame) => got = Some(frame),
                    Err(TryRecvError::Empty) => std::hint::spin_loop(),
                    Err(TryRecvError::Disconnected) => return Err(gone()),
                }
            }
            let frame = match got {
                Some(frame) => frame,
                None => match self.frames.recv_timeout(READ_SLICE) {
                    Ok(frame) => frame,
                    Err(RecvTimeoutError::Timeout) => return Err(io::ErrorKind::WouldBlock.into()),
                    Err(RecvTimeoutError::Disconnected) => return Err(gone()),
                },
            };
            self.frame = frame?;
            self.at = 0;
        }
        let n = buf.len().min(self.frame.len() - self.at);
        buf[..n].copy_from_slice(&self.frame[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

impl Drop for FrameReader {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// Asks the kernel for a receive buffer of `bytes` for `socket`; what it grants (at most
/// `net.core.rmem_max`) is what it grants.
#[cfg(unix)]
fn ask_receive_buffer(socket: &UdpSocket, bytes: usize) {
    use std::os::fd::AsRawFd;
    let bytes = libc::c_int::try_from(bytes).unwrap_or(libc::c_int::MAX);
    // SAFETY: `bytes` lives for the call and its size is given; the descriptor is the open
    // socket's.
    unsafe {
        libc::setsockopt(
            socket.as_raw_fd(),
            libc::SOL_SOCKET,
            libc::SO_RCVBUF,
            (&raw const bytes).cast(),
            std::mem::size_of::<libc::c_int>() as libc::socklen_t,
        );
    }
}

/// Elsewhere the system's default stands.
#[cfg(not(unix))]
fn ask_receive_buffer(_socket: &UdpSocket, _bytes: usize) {}

/// How to read the datagrams the kernel dropped for `socket` (its receive buffer full): the
/// `drops` column of its line in `/proc/net/udp` (or `udp6`), found by its inode.
#[cfg(target_os = "linux")]
fn socket_drops(socket: &UdpSocket) -> Option<HostDrops> {
    use std::os::fd::AsRawFd;
    // SAFETY: `stat` is written by the call; the descriptor is the open socket's.
    let inode = unsafe {
        let mut stat: libc::stat = std::mem::zeroed();
        (libc::fstat(socket.as_raw_fd(), &mut stat) == 0).then_some(stat.st_ino)
    }?
    .to_string();
    Some(Box::new(move || {
        ["/proc/net/udp", "/proc/net/udp6"]
            .iter()
            .find_map(|table| {
                let text = std::fs::read_to_string(table).ok()?;
                text.lines().skip(1).find_map(|line| {
                    let fields: Vec<&str> = line.split_whitespace().collect();
                    // sl, local, remote, st, queues, tr, retrnsmt, uid, timeout, inode, ref,
                    // pointer, drops.
                    (fields.get(9) == Some(&inode.as_str()))
                        .then(|| fields.get(12)?.parse().ok())
                        .flatten()
                })
            })
    }))
}

/// Elsewhere the drops are not told.
#[cfg(not(target_os = "linux"))]
fn socket_drops(_socket: &UdpSocket) -> Option<HostDrops> {
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
