//! The three firmware targets behind one trait: in-process, QEMU, a flashed board on a serial port.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

use estimator_core::Estimator;
use estimator_core::wire::MAX_FRAME;
use estimator_core::wire::estimate::TickSource;
use firmware::{App, Clock, Config};

use super::RunError;

/// A firmware that takes bytes and answers with bytes.
pub trait Target {
    fn name(&self) -> &'static str;
    /// Writes bytes to the firmware's receive line.
    fn send(&mut self, bytes: &[u8]) -> Result<(), RunError>;
    /// Appends what the firmware has sent, waiting at most `timeout` for the first bytes.
    fn recv(&mut self, timeout: Duration, out: &mut Vec<u8>) -> Result<(), RunError>;
    /// Whether replies are complete as soon as `send` returns (no waiting needed).
    fn synchronous(&self) -> bool {
        false
    }
}

/// Host time in nanoseconds (wrapping u32: steps are far shorter than the 4.3 s wrap).
pub struct HostClock(Instant);

impl Clock for HostClock {
    fn now(&mut self) -> u32 {
        self.0.elapsed().as_nanos() as u32
    }
    fn source(&self) -> TickSource {
        TickSource::HostNanos
    }
}

/// The firmware's `App` in this process, with the host clock (50 ms budget in ns).
pub struct InProcess {
    app: App<'static, HostClock>,
    pending: Vec<u8>,
}

impl Default for InProcess {
    fn default() -> Self {
        Self::new()
    }
}

impl InProcess {
    pub fn new() -> InProcess {
        InProcess {
            app: App::new(
                Estimator::shipped(),
                HostClock(Instant::now()),
                Config::fifty_ms_at(1_000_000_000),
            ),
            pending: Vec::new(),
        }
    }
}

impl Target for InProcess {
    fn name(&self) -> &'static str {
        "host"
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), RunError> {
        let mut out = [0u8; MAX_FRAME];
        for b in bytes {
            if let Some(n) = self.app.push(*b, &mut out) {
                self.pending.extend_from_slice(out.get(..n).unwrap_or(&[]));
            }
        }
        Ok(())
    }
    fn recv(&mut self, _timeout: Duration, out: &mut Vec<u8>) -> Result<(), RunError> {
        out.append(&mut self.pending);
        Ok(())
    }
    fn synchronous(&self) -> bool {
        true
    }
}

/// Reads a byte stream on a thread, so waiting with a timeout works the same for sockets and ttys.
struct Reader {
    rx: Receiver<Vec<u8>>,
}

impl Reader {
    fn spawn(mut r: impl Read + Send + 'static) -> Reader {
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            loop {
                match r.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        if tx.send(buf[..n].to_vec()).is_err() {
                            break;
                        }
                    }
                }
            }
        });
        Reader { rx }
    }

    /// Appends what arrived within `timeout`; `RunError::Closed(what)` once the stream has ended.
    fn recv(&mut self, timeout: Duration, out: &mut Vec<u8>, what: &str) -> Result<(), RunError> {
        match self.rx.recv_timeout(timeout) {
            Ok(chunk) => out.extend_from_slice(&chunk),
            Err(RecvTimeoutError::Timeout) => return Ok(()),
            Err(RecvTimeoutError::Disconnected) => return Err(RunError::Closed(what.into())),
        }
        while let Ok(chunk) = self.rx.try_recv() {
            out.extend_from_slice(&chunk);
        }
        Ok(())
    }
}

/// Where `cargo fw` of this build (its target directory, so its aircraft) puts the image.
pub fn default_elf() -> PathBuf {
    Path::new(env!("HIL_TARGET_DIR")).join("thumbv7em-none-eabihf/firmware/firmware")
}

/// How hil-sim talks to the flight image in QEMU (`firmware::transport`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum QemuLink {
    /// QEMU's stdin and stdout through Arm semihosting, whole frames per call (the fast path).
    #[default]
    Semihost,
    /// USART1 on a local TCP socket, the path a board uses (one byte per QEMU main-loop round trip).
    Usart,
}

/// The flight image in QEMU's netduinoplus2 with `-icount shift=0`, so that TIM2 counts
/// instructions. QEMU is killed when this is dropped.
///
/// [`QemuLink::Usart`]: USART1 on a local TCP socket with `nodelay=on` (TCP_NODELAY on QEMU's side).
/// QEMU's USART writes every byte the firmware puts in DR as its own `send`; with Nagle's algorithm
/// on, the kernel holds the rest of an estimate frame until the first byte is acknowledged, and this
/// side delays that ACK by up to 40 ms. That stall, once per frame, was nearly all of a run's wall
/// time (a 30-s flight: 27.8 s with Nagle, 1.8 s without). What remains is QEMU's USART model taking
/// one byte per main-loop round trip.
///
/// [`QemuLink::Semihost`]: the same bytes over QEMU's stdin and stdout, the firmware reading and
/// writing them with semihosting calls. The host opts the image in by writing
/// `firmware::transport::SEMIHOST_MAGIC` into its mailbox with QEMU's generic loader; USART1 is then
/// left unconnected (`-serial null`).
pub struct Qemu {
    child: Child,
    writer: Box<dyn Write + Send>,
    reader: Reader,
}

impl Qemu {
    pub fn start(qemu: &str, elf: &Path, link: QemuLink) -> Result<Qemu, RunError> {
        if !elf.is_file() {
            return Err(RunError::NoElf(elf.to_path_buf()));
        }
        let mut cmd = Command::new(qemu);
        cmd.args([
            "-M",
            "netduinoplus2",
            "-display",
            "none",
            "-monitor",
            "none",
        ])
        .args(["-icount", "shift=0", "-kernel"])
        .arg(elf)
        .stderr(Stdio::piped());
        let (child, writer, reader) = match link {
            QemuLink::Usart => Self::spawn_usart(cmd)?,
            QemuLink::Semihost => Self::spawn_semihost(cmd)?,
        };
        let mut q = Qemu {
            child,
            writer,
            reader,
        };
        // The firmware sends one delimiter once its link is up; bytes sent before that are lost.
        let mut ready = Vec::new();
        let until = Instant::now() + Duration::from_secs(15);
        while ready.is_empty() && Instant::now() < until {
            if let Err(e) = q.recv(Duration::from_millis(100), &mut ready) {
                return Err(q.exited().unwrap_or(e));
            }
        }
        if ready.is_empty() {
            return Err(q
                .exited()
                .unwrap_or_else(|| RunError::NotReady(elf.to_path_buf())));
        }
        Ok(q)
    }

    fn spawn_usart(mut cmd: Command) -> Result<(Child, Box<dyn Write + Send>, Reader), RunError> {
        let port = TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map_err(|e| RunError::Io("find a free TCP port for QEMU".into(), e))?
            .port();
        let mut child = cmd
            .arg("-serial")
            .arg(format!("tcp:127.0.0.1:{port},server=on,wait=on,nodelay=on"))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .spawn()
            .map_err(|e| RunError::Spawn(qemu_name(&cmd), e))?;
        let started = Instant::now();
        let stream = loop {
            if let Ok(Some(status)) = child.try_wait() {
                return Err(RunError::QemuExited(
                    status.to_string(),
                    stderr_of(&mut child),
                ));
            }
            match TcpStream::connect(("127.0.0.1", port)) {
                Ok(s) => break s,
                Err(_) if started.elapsed() < Duration::from_secs(15) => {
                    std::thread::sleep(Duration::from_millis(20));
                }
                Err(e) => {
                    let _ = child.kill();
                    return Err(RunError::Io(
                        format!("connect to QEMU's serial on port {port}"),
                        e,
                    ));
                }
            }
        };
        let _ = stream.set_nodelay(true);
        let read_half = stream
            .try_clone()
            .map_err(|e| RunError::Io("clone the QEMU socket".into(), e))?;
        Ok((child, Box::new(stream), Reader::spawn(read_half)))
    }

    fn spawn_semihost(
        mut cmd: Command,
    ) -> Result<(Child, Box<dyn Write + Send>, Reader), RunError> {
        use firmware::transport::{MAILBOX_ADDR, SEMIHOST_MAGIC};
        let mut child = cmd
            .args([
                "-serial",
                "null",
                "-semihosting-config",
                "enable=on,target=native",
            ])
            .arg("-device")
            .arg(format!(
                "loader,addr={MAILBOX_ADDR:#x},data={SEMIHOST_MAGIC:#x},data-len=8"
            ))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| RunError::Spawn(qemu_name(&cmd), e))?;
        let (Some(stdin), Some(stdout)) = (child.stdin.take(), child.stdout.take()) else {
            let _ = child.kill();
            return Err(RunError::Closed(
                "QEMU's stdin or stdout was not piped".into(),
            ));
        };
        Ok((child, Box::new(stdin), Reader::spawn(stdout)))
    }

    /// QEMU's exit status and stderr, if it has exited.
    fn exited(&mut self) -> Option<RunError> {
        let status = self.child.try_wait().ok().flatten()?;
        Some(RunError::QemuExited(
            status.to_string(),
            stderr_of(&mut self.child),
        ))
    }
}

fn qemu_name(cmd: &Command) -> String {
    cmd.get_program().to_string_lossy().into_owned()
}

fn stderr_of(child: &mut Child) -> String {
    let mut err = String::new();
    if let Some(mut s) = child.stderr.take() {
        let _ = s.read_to_string(&mut err);
    }
    err
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Target for Qemu {
    fn name(&self) -> &'static str {
        "qemu"
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), RunError> {
        self.writer
            .write_all(bytes)
            .and_then(|()| self.writer.flush())
            .map_err(|e| RunError::Io("write to QEMU's serial".into(), e))
    }
    fn recv(&mut self, timeout: Duration, out: &mut Vec<u8>) -> Result<(), RunError> {
        self.reader.recv(timeout, out, "QEMU's serial")
    }
}

/// A flashed board on a serial device. The line is set up with `stty` (coreutils; raw 8N1) rather
/// than a serial-port crate: that is all the configuration a USB-serial adapter needs here, and it
/// keeps udev/libc bindings out of the build.
pub struct Serial {
    port: std::fs::File,
    reader: Reader,
}

impl Serial {
    pub fn open(path: &Path, baud: u32) -> Result<Serial, RunError> {
        let status = Command::new("stty")
            .arg("-F")
            .arg(path)
            .arg(baud.to_string())
            .args([
                "raw", "-echo", "cs8", "-cstopb", "-parenb", "-crtscts", "min", "1", "time", "0",
            ])
            .status()
            .map_err(|e| RunError::Spawn("stty".into(), e))?;
        if !status.success() {
            return Err(RunError::Serial(
                path.to_path_buf(),
                format!("stty failed ({status})"),
            ));
        }
        let port = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| RunError::Serial(path.to_path_buf(), e.to_string()))?;
        let read_half = port
            .try_clone()
            .map_err(|e| RunError::Serial(path.to_path_buf(), e.to_string()))?;
        Ok(Serial {
            port,
            reader: Reader::spawn(read_half),
        })
    }
}

impl Target for Serial {
    fn name(&self) -> &'static str {
        "serial"
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), RunError> {
        self.port
            .write_all(bytes)
            .and_then(|()| self.port.flush())
            .map_err(|e| RunError::Io("write to the serial port".into(), e))
    }
    fn recv(&mut self, timeout: Duration, out: &mut Vec<u8>) -> Result<(), RunError> {
        self.reader.recv(timeout, out, "the serial port")
    }
}
