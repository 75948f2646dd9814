//! A Zaber device on a pseudo-terminal (Unix), for tests: one axis speaking the subset of
//! the ASCII protocol the client uses ([`super::zaber`]): `move abs N` (rejected `BADDATA`
//! outside `limit.min..=limit.max`), `home`, `get pos`, `get limit.min`, `get limit.max`,
//! `warnings clear` and the empty command (status); anything else is `RJ ... BADCOMMAND`.
//! A move is `BUSY` for [`StandInConfig::move_time`]. Until homed the warning flag is `WR`
//! and moves are rejected with `BADDATA`; [`StandInConfig::homed`] starts it homed. Faults:
//! [`ZaberStandIn::stop_answering`] (never answers again). Every line received and sent
//! is kept ([`ZaberStandIn::transcript`]).

use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use nix::poll::{poll, PollFd, PollFlags};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};

use crate::error::{Error, ErrorKind, Result};

/// How the stand-in behaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StandInConfig {
    /// Device address.
    pub device: u8,
    /// Travel, microsteps.
    pub limits_steps: [i64; 2],
    /// How long a move or home stays `BUSY`.
    pub move_time: Duration,
    /// Starts with a reference position (else `WR` until `home`).
    pub homed: bool,
}

impl Default for StandInConfig {
    /// Device 1, travel 0..=1,000,000 microsteps, 50 ms moves, homed.
    fn default() -> Self {
        StandInConfig { device: 1, limits_steps: [0, 1_000_000], move_time: Duration::from_millis(50), homed: true }
    }
}

#[derive(Debug)]
struct Axis {
    pos: i64,
    busy_until: Option<Instant>,
    homed: bool,
}

/// A running stand-in; dropping it stops it.
pub struct ZaberStandIn {
    path: PathBuf,
    stop: Arc<AtomicBool>,
    silent: Arc<AtomicBool>,
    transcript: Arc<Mutex<Vec<String>>>,
    thread: Option<JoinHandle<()>>,
}

impl ZaberStandIn {
    /// Opens the pty and starts answering.
    pub fn spawn(config: StandInConfig) -> Result<ZaberStandIn> {
        let pty_err =
            |e: nix::Error| Error::device("stage zaber stand-in", ErrorKind::Other, format!("pseudo-terminal: {e}"));
        let pty = openpty(None, None).map_err(pty_err)?;
        let mut t = tcgetattr(&pty.slave).map_err(pty_err)?;
        cfmakeraw(&mut t);
        tcsetattr(&pty.slave, SetArg::TCSANOW, &t).map_err(pty_err)?;
        let path = nix::unistd::ttyname(&pty.slave).map_err(pty_err)?;
        let (stop, silent) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicBool::new(false)));
        let transcript = Arc::new(Mutex::new(Vec::new()));
        let (s2, q2, t2) = (Arc::clone(&stop), Arc::clone(&silent), Arc::clone(&transcript));
        let master = File::from(pty.master);
        let slave = pty.slave;
        let thread = std::thread::Builder::new()
            .name("zaber-stand-in".into())
            .spawn(move || serve(master, slave, config, &s2, &q2, &t2))
            .map_err(|e| Error::device("stage zaber stand-in", ErrorKind::Other, e.to_string()))?;
        Ok(ZaberStandIn { path, stop, silent, transcript, thread: Some(thread) })
    }

    /// The serial-port path to open.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// From now on, no command gets a reply (a stage that stopped answering).
    pub fn stop_answering(&self) {
        self.silent.store(true, Ordering::SeqCst);
    }

    /// Every line received (`> /1 1 get pos`) and sent (`< @01 1 OK IDLE -- 0`), in order.
    pub fn transcript(&self) -> Vec<String> {
        self.transcript.lock().map(|t| t.clone()).unwrap_or_default()
    }
}

impl Drop for ZaberStandIn {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn serve(
    mut master: File,
    _slave: OwnedFd,
    config: StandInConfig,
    stop: &AtomicBool,
    silent: &AtomicBool,
    transcript: &Mutex<Vec<String>>,
) {
    let mut axis = Axis { pos: 0, busy_until: None, homed: config.homed };
    let mut pending = Vec::new();
    while !stop.load(Ordering::SeqCst) {
        let ready = {
            let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
            poll(&mut fds, 20u16).unwrap_or(0)
        };
        if ready == 0 {
            continue;
        }
        let mut buf = [0u8; 256];
        let n = match master.read(&mut buf) {
            Ok(n) if n > 0 => n,
            _ => {
                std::thread::sleep(Duration::from_millis(5));
                continue;
            }
        };
        pending.extend_from_slice(&buf[..n]);
        while let Some(k) = pending.iter().position(|&b| b == b'\n') {
            let line: Vec<u8> = pending.drain(..=k).collect();
            let line = String::from_utf8_lossy(&line).trim().to_owned();
            if let Ok(mut t) = transcript.lock() {
                t.push(format!("> {line}"));
            }
            if silent.load(Ordering::SeqCst) {
                continue;
            }
            if let Some(reply) = answer(&line, &config, &mut axis) {
                if let Ok(mut t) = transcript.lock() {
                    t.push(format!("< {reply}"));
                }
                let _ = master.write_all(format!("{reply}\r\n").as_bytes());
            }
        }
    }
}

/// The reply to one command line (`None`: not addressed to this device).
fn answer(line: &str, config: &StandInConfig, axis: &mut Axis) -> Option<String> {
    let mut words = line.strip_prefix('/')?.split_whitespace();
    let device: u8 = words.next()?.parse().ok()?;
    if device != config.device {
        return None;
    }
    let axis_no: u8 = words.next().and_then(|a| a.parse().ok()).unwrap_or(0);
    let command: Vec<&str> = words.collect();
    if axis.busy_until.is_some_and(|t| Instant::now() >= t) {
        axis.busy_until = None;
    }
    let busy = axis.busy_until.is_some();
    let warning = if axis.homed { "--" } else { "WR" };
    let status = |ok: bool, busy: bool, data: &str| {
        format!(
            "@{device:02} {axis_no} {} {} {warning} {data}",
            if ok { "OK" } else { "RJ" },
            if busy { "BUSY" } else { "IDLE" }
        )
    };
    let [lo, hi] = config.limits_steps;
    Some(match command.as_slice() {
        [] => status(true, busy, "0"),
        ["get", "pos"] => status(true, busy, &axis.pos.to_string()),
        ["get", "limit.min"] => status(true, busy, &lo.to_string()),
        ["get", "limit.max"] => status(true, busy, &hi.to_string()),
        ["warnings", "clear"] => status(true, busy, "0"),
        ["home"] => {
            axis.pos = lo;
            axis.homed = true;
            axis.busy_until = Some(Instant::now() + config.move_time);
            format!("@{device:02} {axis_no} OK BUSY -- 0")
        }
        ["move", "abs", n] => match n.parse::<i64>() {
            Ok(n) if (lo..=hi).contains(&n) && axis.homed => {
                axis.pos = n;
                axis.busy_until = Some(Instant::now() + config.move_time);
                status(true, true, "0")
            }
            _ => status(false, busy, "BADDATA"),
        },
        _ => status(false, busy, "BADCOMMAND"),
    })
}
