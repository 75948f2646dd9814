//! The virtual lens served on a pseudo-terminal (Unix only): a thread polls the pty's
//! master and answers through [`super::responder`], so that the real client talks to the
//! device through a real serial-port path.

use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use nix::poll::{poll, PollFd, PollFlags};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};

use super::{folders, responder, VirtualDevice, VirtualLensConfig};
use crate::error::{HwError, Result};

struct Pty {
    master: File,
    // Held open so that the master does not see a hangup while no client has the port open.
    _slave: OwnedFd,
}

/// What the handle asks of the serving thread.
#[derive(Default)]
struct Control {
    stop: bool,
    disconnect: bool,
    new_pty: Option<Pty>,
}

/// A running virtual lens on a pseudo-terminal: a [`VirtualDevice`] (whose methods it
/// derefs to: state, faults, heater, clock) served behind a serial-port path. Dropping it
/// stops the server and removes the port symlink.
///
/// Port path: [`VirtualLens::path`] is a symlink (in a private temporary directory) to the
/// pty's slave, like a udev symlink to `/dev/ttyACM0`. [`VirtualLens::disconnect`] closes
/// the pty (the client sees an I/O error, as when the USB cable is pulled) and
/// [`VirtualLens::reconnect`] opens a new one behind the same path; the lens keeps its
/// current and temperature.
///
/// ```
/// use etl_hw::virtual_lens::{VirtualLens, VirtualLensConfig};
/// use etl_core::lens::Lens;
/// let mut lens = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
/// lens.set_current_ma(120.0).unwrap(); // directly, without the serial port
/// let s = lens.state();
/// assert!((s.e_in_ma - 120.0).abs() < 0.04 && s.f_liq_mm > 50.0 && s.f_liq_mm < 121.0);
/// assert!(lens.path().exists());
/// ```
pub struct VirtualLens {
    device: VirtualDevice,
    control: Arc<Mutex<Control>>,
    dir: PathBuf,
    link: PathBuf,
    thread: Option<JoinHandle<()>>,
}

fn pty_err(step: &'static str) -> impl FnOnce(nix::Error) -> HwError {
    move |e| HwError::Pty { step, source: std::io::Error::from(e) }
}

fn path_err(path: &Path) -> impl FnOnce(std::io::Error) -> HwError + '_ {
    move |source| HwError::PortPath { path: path.to_owned(), source }
}

fn open_pty() -> Result<(Pty, PathBuf)> {
    let pty = openpty(None, None).map_err(pty_err("openpty"))?;
    let mut t = tcgetattr(&pty.slave).map_err(pty_err("tcgetattr"))?;
    cfmakeraw(&mut t);
    tcsetattr(&pty.slave, SetArg::TCSANOW, &t).map_err(pty_err("tcsetattr"))?;
    let name = nix::unistd::ttyname(&pty.slave).map_err(pty_err("ttyname"))?;
    Ok((Pty { master: File::from(pty.master), _slave: pty.slave }, name))
}

fn control(c: &Mutex<Control>) -> MutexGuard<'_, Control> {
    c.lock().unwrap_or_else(|p| p.into_inner())
}

impl VirtualLens {
    /// Creates the device and the pty, starts the serving thread and returns the handle.
    ///
    /// Errors: an invalid configuration (see [`VirtualDevice::new`]) as [`HwError::Core`];
    /// the OS refusing a pty or the serving thread ([`HwError::Pty`]) or the temporary
    /// directory and symlink ([`HwError::PortPath`]).
    pub fn spawn(config: VirtualLensConfig) -> Result<VirtualLens> {
        let device = VirtualDevice::new(config)?;
        // Folders of processes killed before they could remove theirs go first.
        folders::sweep_dead(&std::env::temp_dir());
        let dir = folders::next_path();
        std::fs::create_dir_all(&dir).map_err(path_err(&dir))?;
        folders::hold(&dir);
        let link = dir.join("lens");
        let (pty, name) = open_pty()?;
        std::os::unix::fs::symlink(&name, &link).map_err(path_err(&link))?;
        let control = Arc::new(Mutex::new(Control::default()));
        let (d2, c2) = (device.clone(), Arc::clone(&control));
        let thread = std::thread::Builder::new()
            .name("virtual-lens".into())
            .spawn(move || serve(&d2, &c2, pty))
            .map_err(|source| HwError::Pty { step: "serving thread", source })?;
        Ok(VirtualLens { device, control, dir, link, thread: Some(thread) })
    }

    /// The serial-port path to open (a symlink to the pty's slave).
    pub fn path(&self) -> &Path {
        &self.link
    }

    /// The device model behind the port (a handle to the same device).
    pub fn device(&self) -> &VirtualDevice {
        &self.device
    }

    /// Pulls the cable: closes the pty; the client's next I/O fails.
    pub fn disconnect(&self) {
        control(&self.control).disconnect = true;
        // Let the server drop the pty before the caller goes on.
        for _ in 0..200 {
            if !control(&self.control).disconnect {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Plugs the cable back in: a new pty behind the same [`Self::path`]. The lens keeps its
    /// current and temperature.
    pub fn reconnect(&self) -> Result<()> {
        let (pty, name) = open_pty()?;
        let tmp = self.dir.join("lens.new");
        let _ = std::fs::remove_file(&tmp);
        std::os::unix::fs::symlink(&name, &tmp).map_err(path_err(&tmp))?;
        std::fs::rename(&tmp, &self.link).map_err(path_err(&self.link))?;
        control(&self.control).new_pty = Some(pty);
        Ok(())
    }
}

impl std::ops::Deref for VirtualLens {
    type Target = VirtualDevice;

    fn deref(&self) -> &VirtualDevice {
        &self.device
    }
}

impl Drop for VirtualLens {
    fn drop(&mut self) {
        control(&self.control).stop = true;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        folders::release(&self.dir);
    }
}

/// As [`VirtualDevice`]'s: directly on the model, without the serial port.
impl etl_core::lens::Lens for VirtualLens {
    type Error = HwError;

    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        etl_core::lens::Lens::set_current_ma(&mut self.device, e_in_ma)
    }

    fn current_ma(&mut self) -> Result<f64> {
        etl_core::lens::Lens::current_ma(&mut self.device)
    }

    fn temperature_c(&mut self) -> Result<f64> {
        etl_core::lens::Lens::temperature_c(&mut self.device)
    }
}

/// Applies the handle's requests; false when the server must stop.
fn obey(control: &Mutex<Control>, pty: &mut Option<Pty>, buf: &mut Vec<u8>) -> bool {
    let mut c = self::control(control);
    if c.stop {
        return false;
    }
    if c.disconnect {
        *pty = None;
        buf.clear();
        c.disconnect = false;
    }
    if let Some(p) = c.new_pty.take() {
        *pty = Some(p);
        buf.clear();
    }
    true
}

/// Whether the master has bytes to read within 20 ms.
fn readable(master: &File) -> bool {
    let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
    match poll(&mut fds, 20u16) {
        Ok(n) if n > 0 => fds[0].revents().is_some_and(|r| r.contains(PollFlags::POLLIN)),
        _ => false,
    }
}

/// The serving loop: poll the master, decode commands, answer.
fn serve(device: &VirtualDevice, control: &Mutex<Control>, first: Pty) {
    let mut pty = Some(first);
    let mut buf: Vec<u8> = Vec::new();
    let mut last_rx = Instant::now();
    let mut chunk = [0u8; 4096];
    while obey(control, &mut pty, &mut buf) {
        let Some(p) = pty.as_mut() else {
            std::thread::sleep(Duration::from_millis(2));
            continue;
        };
        if !readable(&p.master) {
            // A partial command left alone for 50 ms is dropped (the host gave up on it).
            if !buf.is_empty() && last_rx.elapsed() > Duration::from_millis(50) {
                buf.clear();
            }
            continue;
        }
        let n = match p.master.read(&mut chunk) {
            Ok(n) => n,
            // EIO: no client has the slave open (after it closed the port). Wait.
            Err(_) => {
                std::thread::sleep(Duration::from_millis(2));
                continue;
            }
        };
        last_rx = Instant::now();
        responder::receive(&device.shared, chunk.get(..n).unwrap_or(&chunk), &mut buf);
        let master = &mut p.master;
        responder::process(&device.shared, &mut buf, &mut |delay, bytes| {
            if !delay.is_zero() {
                std::thread::sleep(delay);
            }
            let _ = master.write_all(&bytes);
        });
    }
}
