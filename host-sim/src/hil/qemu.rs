//! Runs the firmware's QEMU image (`cargo fw-qemu`) under `qemu-system-arm -M mps2-an500`
//! (docs/firmware.md#hil-transports): its link to this process over the board's Ethernet
//! controller, each frame a UDP datagram on this machine (QEMU's `socket` back end; the
//! fast default), or over its UART bridged to a local TCP socket this process listens on (or
//! to a pseudo-terminal, as a serial device would be); `-icount shift=0` so one instruction
//! is one virtual nanosecond (the firmware measures its control step in instructions), and
//! semihosting so a panic prints and stops QEMU, the firmware learns its link from the
//! command line and keeps its parameter flash in a host file ([`PARAM_FLASH_FILE`], in
//! QEMU's working directory).
//!
//! The QEMU process never outlives this one: it is killed when [`Qemu`] is dropped, and on
//! Linux also when this process dies (parent-death signal).

use std::io::{BufRead, BufReader, Read};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};

use super::transport::Link;

/// The emulator binary.
pub const QEMU: &str = "qemu-system-arm";
/// Environment variable whose words are added to QEMU's command line.
pub const EXTRA_ARGS_VAR: &str = "HIL_QEMU_ARGS";
/// How long QEMU may take to connect or to open its terminal.
const START_TIMEOUT: Duration = Duration::from_secs(20);

/// A running QEMU with the firmware.
pub struct Qemu {
    child: Child,
    output: Arc<Mutex<String>>,
    /// The plant's end of the board's RC receiver UART (UART 1), when asked for
    /// ([`Guest::rc`]), until taken ([`Self::take_rc`]).
    rc: Option<super::rc_link::RcLink>,
    /// QEMU's working directory when it is this run's own (removed at the end).
    scratch: Option<PathBuf>,
}

/// Name of the firmware's parameter flash in QEMU's working directory (semihosting file I/O;
/// `firmware/src/board/qemu/flash.rs`).
pub const PARAM_FLASH_FILE: &str = "firmware-params.bin";

/// Where QEMU runs: the firmware's semihosting files (its parameter flash) live there.
fn working_dir(storage: Option<&Path>) -> Result<(PathBuf, bool)> {
    if let Some(dir) = storage {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the storage directory {}", dir.display()))?;
        return Ok((dir.to_path_buf(), false));
    }
    static RUNS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("host-sim-qemu-{}-{n}", std::process::id()));
    // A directory left by an earlier process of the same id holds nothing of this run's.
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create QEMU's directory {}", dir.display()))?;
    Ok((dir, true))
}

/// Which of the board's links carries MAVLink to the plant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum QemuLink {
    /// The LAN9118 Ethernet controller, frames as UDP datagrams (fast: whole frames).
    Ethernet,
    /// CMSDK UART 0 over a TCP socket (QEMU moves one byte per pass of its main loop).
    Uart,
}

impl QemuLink {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ethernet => "ethernet",
            Self::Uart => "uart",
        }
    }
}

/// How the firmware's link is brought out.
enum Serial {
    /// The UART: QEMU connects to this local TCP port.
    Tcp(u16),
    /// The UART: QEMU opens a pseudo-terminal and names it.
    Pty,
    /// The Ethernet controller: QEMU sends its frames to `plant` and takes frames at `qemu`.
    Udp {
        /// This process's socket's address.
        plant: SocketAddr,
        /// QEMU's socket's address.
        qemu: SocketAddr,
    },
}

/// Where `cargo fw-qemu` puts the image, for the workspace at `workspace` (honouring
/// `CARGO_TARGET_DIR`).
pub fn image_path(workspace: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace.join("target"))
        .join("thumbv7em-none-eabihf/release/firmware-qemu")
}

/// The firmware's QEMU image for the tests: `FIRMWARE_QEMU_ELF` when set, otherwise the
/// workspace's own, built (or brought up to date) first with the command `cargo fw-qemu`
/// stands for, so `cargo test` flies the firmware as it is in the tree with no step before it.
/// The build runs once per process; its failure is an error with cargo's last lines.
pub fn test_image(workspace: &Path) -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("FIRMWARE_QEMU_ELF") {
        return Ok(PathBuf::from(p));
    }
    static BUILT: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    BUILT
        .get_or_init(|| {
            ensure_target(workspace);
            let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
            let output = Command::new(cargo)
                .current_dir(workspace)
                .args([
                    "build",
                    "-p",
                    "firmware",
                    "--release",
                    "--target",
                    "thumbv7em-none-eabihf",
                    "--features",
                    "qemu",
                    "--bin",
                    "firmware-qemu",
                ])
                .output()
                .map_err(|e| format!("cargo could not be run to build the firmware image ({e})"))?;
            if !output.status.success() {
                let stderr = String::from_utf8_lossy(&output.stderr);
                let tail: Vec<&str> = stderr.lines().rev().take(6).collect();
                return Err(format!(
                    "the firmware image did not build (cargo fw-qemu): {}",
                    tail.into_iter().rev().collect::<Vec<_>>().join(" / ")
                ));
            }
            Ok(image_path(workspace))
        })
        .clone()
}

/// Adds the Cortex-M7 target to the toolchain in force when rustup lacks it: the toolchain
/// file names it, but a rustup whose toolchain was already installed before the file asked
/// for it does not add it by itself. Without rustup, or when adding fails (no network), the
/// build below says what is missing.
fn ensure_target(workspace: &Path) {
    const TARGET: &str = "thumbv7em-none-eabihf";
    let installed = Command::new("rustup")
        .current_dir(workspace)
        .args(["target", "list", "--installed"])
        .output();
    let Ok(installed) = installed else {
        return;
    };
    if String::from_utf8_lossy(&installed.stdout)
        .lines()
        .any(|l| l.trim() == TARGET)
    {
        return;
    }
    eprintln!("adding the {TARGET} target to the toolchain (rustup target add {TARGET})");
    let _ = Command::new("rustup")
        .current_dir(workspace)
        .args(["target", "add", TARGET])
        .status();
}

/// Tests of this process skipped because QEMU is missing, and those skipped for another
/// reason (said as each was skipped).
static SKIPPED: [std::sync::atomic::AtomicU32; 2] = [
    std::sync::atomic::AtomicU32::new(0),
    std::sync::atomic::AtomicU32::new(0),
];

/// Counts a test skipped for want of QEMU (`no_qemu`) or for another reason; when the test
/// process ends it prints one line with the count and, when QEMU was missing, the one command
/// that installs it.
pub fn note_skipped(no_qemu: bool) {
    static AT_EXIT: std::sync::Once = std::sync::Once::new();
    SKIPPED[usize::from(!no_qemu)].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    AT_EXIT.call_once(|| {
        // SAFETY: registers a plain function with no arguments, run once at exit.
        unsafe {
            libc::atexit(say_skipped);
        }
    });
}

extern "C" fn say_skipped() {
    use std::io::Write;
    let load = |i: usize| SKIPPED[i].load(std::sync::atomic::Ordering::Relaxed);
    let (no_qemu, other) = (load(0), load(1));
    let mut err = std::io::stderr();
    if no_qemu > 0 {
        let _ = writeln!(
            err,
            "{no_qemu} firmware-in-the-loop test(s) SKIPPED: qemu-system-arm is not installed; install it with: sudo apt-get install qemu-system-arm"
        );
    }
    if other > 0 {
        let _ = writeln!(
            err,
            "{other} firmware-in-the-loop test(s) SKIPPED for the reasons printed above"
        );
    }
}

/// Whether `qemu-system-arm` can be run here.
pub fn available() -> bool {
    Command::new(QEMU)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// How the guest is started, besides its link.
#[derive(Clone, Copy, Debug, Default)]
pub struct Guest<'a> {
    /// The firmware's parameter flash and flight logs kept in this directory (the file
    /// [`PARAM_FLASH_FILE`] there outlives QEMU); `None`: in a directory of this run's own,
    /// removed at the end, and no flight logs.
    pub storage: Option<&'a Path>,
    /// The board drives at most this many robots (`max-robots=N` on the guest's command
    /// line; `None`: every robot the link carries).
    pub max_robots: Option<u8>,
    /// Bring the board's RC receiver UART (CMSDK UART 1, QEMU's second `-serial`) out to this
    /// process over a Unix socket ([`Qemu::take_rc`]), for `hil --rc` (docs/hil.md).
    pub rc: bool,
}

impl Qemu {
    /// Starts the firmware `elf` with an empty parameter flash, its MAVLink on `link`;
    /// returns QEMU and the plant's end of the link.
    pub fn start(elf: &Path, link: QemuLink) -> Result<(Self, Link)> {
        Self::start_guest(elf, &Guest::default(), link)
    }

    /// As [`Self::start`], the guest started as `guest` says.
    pub fn start_guest(elf: &Path, guest: &Guest<'_>, link: QemuLink) -> Result<(Self, Link)> {
        match link {
            QemuLink::Uart => {
                let (qemu, stream) = Self::launch_guest(elf, guest)?;
                Ok((qemu, Link::over_tcp(stream)?))
            }
            QemuLink::Ethernet => {
                let localhost = SocketAddr::from((Ipv4Addr::LOCALHOST, 0));
                let socket =
                    UdpSocket::bind(localhost).context("cannot open a UDP socket for QEMU")?;
                let plant = socket.local_addr()?;
                // A port for QEMU's end: free now, taken by QEMU at once.
                let qemu_addr = UdpSocket::bind(localhost)
                    .and_then(|s| s.local_addr())
                    .context("cannot find a free UDP port for QEMU")?;
                let qemu = Self::spawn(
                    elf,
                    Serial::Udp {
                        plant,
                        qemu: qemu_addr,
                    },
                    guest,
                )?;
                Ok((qemu, Link::over_udp(socket, qemu_addr)?))
            }
        }
    }

    /// Starts the firmware `elf` with its UART connected to a TCP socket and an empty
    /// parameter flash; returns QEMU and the socket.
    pub fn launch(elf: &Path) -> Result<(Self, TcpStream)> {
        Self::launch_guest(elf, &Guest::default())
    }

    /// As [`Self::launch`], the guest started as `guest` says.
    pub fn launch_guest(elf: &Path, guest: &Guest<'_>) -> Result<(Self, TcpStream)> {
        let listener = TcpListener::bind("127.0.0.1:0").context("cannot listen for QEMU's UART")?;
        let port = listener.local_addr()?.port();
        let mut qemu = Self::spawn(elf, Serial::Tcp(port), guest)?;
        listener.set_nonblocking(true)?;
        let start = Instant::now();
        loop {
            match listener.accept() {
                Ok((stream, _)) => {
                    stream.set_nonblocking(false)?;
                    return Ok((qemu, stream));
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(e) => return Err(anyhow!(e).context("accepting QEMU's UART connection")),
            }
            qemu.check_running()?;
            if start.elapsed() > START_TIMEOUT {
                bail!(
                    "QEMU did not connect its UART within {} s{}",
                    START_TIMEOUT.as_secs(),
                    qemu.output_note()
                );
            }
            thread::sleep(Duration::from_millis(20));
        }
    }

    /// Starts the firmware `elf` with its UART on a pseudo-terminal; returns QEMU and the
    /// terminal's path (a serial device for `--serial`).
    pub fn launch_pty(elf: &Path) -> Result<(Self, PathBuf)> {
        let mut qemu = Self::spawn(elf, Serial::Pty, &Guest::default())?;
        let start = Instant::now();
        loop {
            let found = {
                let out = qemu
                    .output
                    .lock()
                    .map_err(|_| anyhow!("QEMU output reader failed"))?;
                out.lines().find_map(|l| {
                    let at = l.find("/dev/pts/")?;
                    let path: String = l[at..]
                        .chars()
                        .take_while(|c| !c.is_whitespace() && *c != ')')
                        .collect();
                    Some(PathBuf::from(path))
                })
            };
            if let Some(path) = found {
                return Ok((qemu, path));
            }
            qemu.check_running()?;
            if start.elapsed() > START_TIMEOUT {
                bail!(
                    "QEMU did not report its pseudo-terminal{}",
                    qemu.output_note()
                );
            }
            thread::sleep(Duration::from_millis(20));
        }
    }

    fn spawn(elf: &Path, serial: Serial, guest: &Guest<'_>) -> Result<Self> {
        let storage = guest.storage;
        if !elf.is_file() {
            bail!(
                "firmware image {} not found (build it with `cargo fw-qemu`)",
                elf.display()
            );
        }
        // QEMU runs in its working directory, so the image's path must not be relative.
        let elf = elf
            .canonicalize()
            .with_context(|| format!("cannot resolve {}", elf.display()))?;
        let (dir, scratch) = working_dir(storage)?;
        // The RC receiver's UART: QEMU connects to this socket (bound before it starts).
        let rc_socket = guest.rc.then(super::rc_link::RcSocket::bind).transpose()?;
        let mut cmd = Command::new(QEMU);
        cmd.current_dir(&dir);
        cmd.args(["-M", "mps2-an500", "-nographic", "-monitor", "none"])
            .args(["-icount", "shift=0"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-kernel")
            .arg(&elf);
        // The image's command line (`-append`): words the firmware reads through semihosting.
        let mut words: Vec<&str> = Vec::new();
        match serial {
            Serial::Tcp(port) => {
                cmd.args([
                    "-chardev",
                    &format!("socket,id=link,host=127.0.0.1,port={port},server=off,nodelay=on"),
                    "-serial",
                    "chardev:link",
                    "-nic",
                    "none",
                ]);
            }
            Serial::Pty => {
                cmd.args(["-serial", "pty", "-nic", "none"]);
            }
            Serial::Udp { plant, qemu } => {
                // The firmware reads its link from the command line (semihosting).
                words.push("hil-link=ethernet");
                cmd.args(["-serial", "null", "-nic"])
                    .arg(format!("socket,udp={plant},localaddr={qemu}"));
            }
        }
        // UART 1, the RC receiver's, after UART 0's `-serial` (each branch above gives one).
        if let Some(socket) = &rc_socket {
            cmd.args(["-chardev"])
                .arg(format!(
                    "socket,id=rc,path={},server=off",
                    socket.path().display()
                ))
                .args(["-serial", "chardev:rc"]);
        }
        // With storage the firmware keeps its flight logs there (docs/formats.md#flight-logs).
        if storage.is_some() {
            words.push("flight-log=on");
        }
        // A board that drives fewer robots than the link carries (docs/hardware.md).
        let max_robots = guest.max_robots.map(|n| format!("max-robots={n}"));
        words.extend(max_robots.as_deref());
        if !words.is_empty() {
            cmd.arg("-append").arg(words.join(" "));
        }
        // For debugging the firmware in the loop: more of QEMU's options, e.g. `-s` for a gdb
        // server on port 1234 or `-d guest_errors` (docs/firmware.md#hil-transports).
        if let Some(extra) = std::env::var_os(EXTRA_ARGS_VAR) {
            cmd.args(extra.to_string_lossy().split_whitespace());
        }
        cmd.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        #[cfg(target_os = "linux")]
        {
            use std::os::unix::process::CommandExt;
            // SAFETY: prctl is async-signal-safe; it only asks the kernel to kill the child
            // when this process dies.
            unsafe {
                cmd.pre_exec(|| {
                    libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
                    Ok(())
                });
            }
        }
        let mut child = cmd.spawn().with_context(|| {
            format!("cannot run {QEMU} (install it: apt-get install qemu-system-arm)")
        })?;
        let output = Arc::new(Mutex::new(String::new()));
        for stream in [
            child
                .stdout
                .take()
                .map(|s| Box::new(s) as Box<dyn Read + Send>),
            child
                .stderr
                .take()
                .map(|s| Box::new(s) as Box<dyn Read + Send>),
        ]
        .into_iter()
        .flatten()
        {
            let sink = Arc::clone(&output);
            thread::spawn(move || {
                for line in BufReader::new(stream).lines().map_while(Result::ok) {
                    if let Ok(mut out) = sink.lock() {
                        out.push_str(&line);
                        out.push('\n');
                    }
                }
            });
        }
        let mut qemu = Self {
            child,
            output,
            rc: None,
            scratch: scratch.then_some(dir),
        };
        if let Some(socket) = rc_socket {
            let start = Instant::now();
            qemu.rc = Some(loop {
                if let Some(link) = socket.accept()? {
                    break link;
                }
                qemu.check_running()?;
                if start.elapsed() > START_TIMEOUT {
                    bail!(
                        "QEMU did not connect its RC receiver UART within {} s{}",
                        START_TIMEOUT.as_secs(),
                        qemu.output_note()
                    );
                }
                thread::sleep(Duration::from_millis(5));
            });
        }
        Ok(qemu)
    }

    /// The plant's end of the board's RC receiver UART, if the guest was started with one
    /// ([`Guest::rc`]) and it was not taken yet.
    pub fn take_rc(&mut self) -> Option<super::rc_link::RcLink> {
        self.rc.take()
    }

    /// The QEMU process id (tests stop and resume it to simulate a stalled firmware).
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Fails if QEMU has exited (a firmware panic exits it), with what it printed.
    pub fn check_running(&mut self) -> Result<()> {
        if let Some(status) = self.child.try_wait()? {
            // Give the output readers a moment to collect the last lines.
            thread::sleep(Duration::from_millis(100));
            bail!("QEMU exited ({status}){}", self.output_note());
        }
        Ok(())
    }

    /// What QEMU printed (semihosting output, QEMU's own errors).
    pub fn output(&self) -> String {
        self.output.lock().map(|o| o.clone()).unwrap_or_default()
    }

    fn output_note(&self) -> String {
        let out = self.output();
        let out = out.trim();
        if out.is_empty() {
            String::new()
        } else {
            format!(": {}", out.lines().collect::<Vec<_>>().join(" / "))
        }
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        if let Some(dir) = &self.scratch {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}
