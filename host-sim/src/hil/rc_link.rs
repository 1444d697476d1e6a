//! The plant's end of the emulated board's RC receiver UART (`hil --rc`, docs/hil.md): QEMU's
//! second `-serial` (CMSDK UART 1) on a Unix socket this process listens on. Each stick-script
//! frame goes in as the CRSF `RC_CHANNELS_PACKED` frame a receiver would send
//! (`drivers::crsf::encode_channels`), which the firmware's own receiver task parses.
//!
//! QEMU hands the UART one byte per pass of its main loop, so a 26-byte frame takes some
//! 30 passes to go in, several lockstep steps' worth of wall time. [`RcLink::send`] therefore
//! waits until QEMU has taken the whole frame off the socket (Linux's `SIOCOUTQ` on a Unix
//! socket counts what the peer has not yet read) before the step's sample goes: a frame sent
//! with step `k` is in the firmware's UART by then, as a real receiver's frame (0.6 ms on the
//! wire at 420,000 baud) is by the next IMU sample.

use std::io::Write;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};

/// Longest wait for QEMU to take a frame off the socket.
const TAKE_TIMEOUT: Duration = Duration::from_secs(5);

/// The socket QEMU's RC UART connects to, until it does.
pub struct RcSocket {
    listener: UnixListener,
    path: PathBuf,
}

impl RcSocket {
    /// Listens on a fresh path in the temporary directory.
    pub fn bind() -> Result<Self> {
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!("host-sim-rc-{}-{n}.sock", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let listener = UnixListener::bind(&path)
            .with_context(|| format!("cannot listen on {} for QEMU's RC UART", path.display()))?;
        listener.set_nonblocking(true)?;
        Ok(Self { listener, path })
    }

    /// Where QEMU connects.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// QEMU's connection, if it has come.
    pub fn accept(&self) -> Result<Option<RcLink>> {
        match self.listener.accept() {
            Ok((stream, _)) => {
                stream.set_nonblocking(false)?;
                Ok(Some(RcLink {
                    stream,
                    frames: 0,
                    waited: Duration::ZERO,
                }))
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => Ok(None),
            Err(e) => Err(e).context("accepting QEMU's RC UART connection"),
        }
    }
}

impl Drop for RcSocket {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The board's RC receiver UART, connected.
pub struct RcLink {
    stream: UnixStream,
    frames: u64,
    waited: Duration,
}

impl RcLink {
    /// Writes the CRSF channel frame of `channels_us` and waits until QEMU has read it all.
    pub fn send(&mut self, channels_us: &[u16; drivers::rc::CHANNELS]) -> Result<()> {
        let frame = drivers::crsf::encode_channels(channels_us);
        self.stream
            .write_all(&frame)
            .context("writing to the board's RC UART")?;
        let start = Instant::now();
        while unread(&self.stream)? > 0 {
            if start.elapsed() > TAKE_TIMEOUT {
                bail!(
                    "QEMU did not take an RC frame within {} s",
                    TAKE_TIMEOUT.as_secs()
                );
            }
            std::thread::yield_now();
        }
        self.frames += 1;
        self.waited += start.elapsed();
        Ok(())
    }

    /// Frames sent, and the wall time spent waiting for QEMU to take them.
    pub fn sent(&self) -> (u64, Duration) {
        (self.frames, self.waited)
    }
}

/// Bytes written to `stream` that its peer has not read yet (0 where the system cannot say).
#[cfg(target_os = "linux")]
fn unread(stream: &UnixStream) -> Result<i32> {
    use std::os::fd::AsRawFd;
    let mut pending: libc::c_int = 0;
    // SAFETY: SIOCOUTQ (TIOCOUTQ) writes one int to the pointer, which lives for the call.
    let r = unsafe { libc::ioctl(stream.as_raw_fd(), libc::TIOCOUTQ, &mut pending) };
    if r != 0 {
        return Err(std::io::Error::last_os_error()).context("SIOCOUTQ on the RC UART's socket");
    }
    Ok(pending)
}

#[cfg(not(target_os = "linux"))]
fn unread(_: &UnixStream) -> Result<i32> {
    Ok(0)
}
