//! `zaber:PORT,microstep_um=UM[,device=N][,axis=N]`: a Zaber stage over its ASCII protocol
//! (Zaber's public "ASCII Protocol Manual"), 115200 baud, 8N1.
//!
//! A command is one line, `/DEVICE AXIS COMMAND\n` (`/1 1 move abs 20000`); the device
//! answers each with one reply line, `@DD A FLAG STATUS WARNING DATA`
//! (`@01 1 OK BUSY -- 0`): FLAG `OK` or `RJ` (rejected, DATA says why: `BADDATA` for a
//! value outside the limits, `BADCOMMAND`, `STATUSBUSY`, ...), STATUS `IDLE` or `BUSY`,
//! WARNING `--` or the highest-priority warning flag (`F*` are faults: `FS` stalled, `FD`
//! driver disabled, ...; `WR` no reference position, `WL` limit switch). Lines starting with
//! `#` (info) and `!` (alerts, `comm.alert`) are read and skipped. Positions are in
//! microsteps; the spec's `microstep_um` converts them (the protocol does not say it).
//!
//! A move: `move abs N`, then the axis is polled (`/D A` with no command) until `IDLE`,
//! then `get pos` reads the position back and its warning flag is checked. The limits are
//! `get limit.min` and `get limit.max`. Every reply must come within
//! [`ZaberOptions::reply_timeout`], every move end within [`ZaberOptions::move_timeout`].

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use super::Stage;
use crate::error::{Error, ErrorKind, Result};
use crate::spec::ZaberSpec;

/// Time limits of the client.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZaberOptions {
    /// Longest wait for a reply line.
    pub reply_timeout: Duration,
    /// Longest wait for a move or home to end.
    pub move_timeout: Duration,
    /// Interval between polls of a moving axis.
    pub poll_interval: Duration,
}

impl Default for ZaberOptions {
    /// 1 s per reply, 120 s per move, polls every 20 ms.
    fn default() -> Self {
        ZaberOptions {
            reply_timeout: Duration::from_secs(1),
            move_timeout: Duration::from_secs(120),
            poll_interval: Duration::from_millis(20),
        }
    }
}

/// One reply line, parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reply {
    /// Device address.
    pub device: u8,
    /// Axis (0: the whole device).
    pub axis: u8,
    /// `true` for `OK`, `false` for `RJ`.
    pub ok: bool,
    /// `true` while the axis moves.
    pub busy: bool,
    /// The warning flag (`--` for none).
    pub warning: String,
    /// The data field.
    pub data: String,
}

impl Reply {
    /// Parses `@01 1 OK IDLE -- 0`; `None` for any other line.
    pub fn parse(line: &str) -> Option<Reply> {
        let mut t = line.trim().strip_prefix('@')?.split_whitespace();
        let device = t.next()?.parse().ok()?;
        let axis = t.next()?.parse().ok()?;
        let ok = match t.next()? {
            "OK" => true,
            "RJ" => false,
            _ => return None,
        };
        let busy = match t.next()? {
            "BUSY" => true,
            "IDLE" => false,
            _ => return None,
        };
        let warning = t.next()?.to_owned();
        let data = t.collect::<Vec<_>>().join(" ");
        Some(Reply { device, axis, ok, busy, warning, data })
    }
}

/// What a rejection's data means, in words.
fn rejection_meaning(data: &str) -> &'static str {
    match data {
        "BADDATA" => "a value outside the stage's limits or range",
        "BADCOMMAND" => "a command this device does not know",
        "BADAXIS" => "no such axis",
        "DEVICEONLY" => "a command for the whole device, not an axis",
        "STATUSBUSY" => "the axis is moving",
        "PARKED" => "the axis is parked (unpark it)",
        "DRIVERDISABLED" => "the driver is disabled",
        "LOCKSTEP" => "the axis is in lockstep",
        _ => "refused",
    }
}

/// A Zaber axis behind a byte link (a serial port, or any `Read + Write`).
pub struct ZaberStage<L: Read + Write> {
    link: L,
    spec: ZaberSpec,
    options: ZaberOptions,
    pending: Vec<u8>,
}

impl ZaberStage<Box<dyn serialport::SerialPort>> {
    /// Opens the port of `spec` (115200 baud).
    pub fn open(spec: &ZaberSpec, options: ZaberOptions) -> Result<Self> {
        let port =
            serialport::new(spec.port.to_string_lossy(), 115_200).timeout(Duration::from_millis(10)).open().map_err(
                |e| Error::device(format!("stage zaber:{}", spec.port.display()), ErrorKind::LinkLost, e.to_string()),
            )?;
        Ok(ZaberStage::from_link(port, spec.clone(), options))
    }
}

impl<L: Read + Write> ZaberStage<L> {
    /// The client over `link` (reads must time out on their own, as a serial port's do).
    pub fn from_link(link: L, spec: ZaberSpec, options: ZaberOptions) -> Self {
        ZaberStage { link, spec, options, pending: Vec::new() }
    }

    fn err(&self, kind: ErrorKind, message: impl Into<String>) -> Error {
        Error::device(self.name(), kind, message)
    }

    /// One reply line, within the reply timeout.
    fn read_line(&mut self, command: &str) -> Result<String> {
        let deadline = Instant::now() + self.options.reply_timeout;
        loop {
            if let Some(k) = self.pending.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.pending.drain(..=k).collect();
                return Ok(String::from_utf8_lossy(&line).trim().to_owned());
            }
            if Instant::now() >= deadline {
                let t = self.options.reply_timeout;
                return Err(self.err(ErrorKind::Timeout, format!("no reply to '{command}' within {t:?}")));
            }
            let mut buf = [0u8; 256];
            match self.link.read(&mut buf) {
                Ok(0) => std::thread::sleep(Duration::from_millis(2)),
                Ok(n) => self.pending.extend_from_slice(&buf[..n]),
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::TimedOut | std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(self.err(ErrorKind::LinkLost, format!("serial I/O: {e}"))),
            }
        }
    }

    /// Sends `command` to the spec's axis and returns its reply (info and alert lines
    /// skipped); a rejection or a fault flag is an error naming the command.
    pub fn command(&mut self, command: &str) -> Result<Reply> {
        let line = format!("/{} {} {command}\n", self.spec.device, self.spec.axis);
        let line = line.replace(" \n", "\n");
        self.link
            .write_all(line.as_bytes())
            .and_then(|()| self.link.flush())
            .map_err(|e| self.err(ErrorKind::LinkLost, format!("serial I/O: {e}")))?;
        loop {
            let text = self.read_line(command)?;
            if text.starts_with('#') || text.starts_with('!') || text.is_empty() {
                continue;
            }
            let reply = Reply::parse(&text)
                .ok_or_else(|| self.err(ErrorKind::Protocol, format!("unreadable reply '{text}' to '{command}'")))?;
            if reply.device != self.spec.device || (reply.axis != self.spec.axis && reply.axis != 0) {
                continue;
            }
            if !reply.ok {
                let message = format!("refused '{command}': {} ({})", reply.data, rejection_meaning(&reply.data));
                return Err(self.err(ErrorKind::Refused, message));
            }
            if reply.warning.starts_with('F') {
                let message = format!("fault flag {} after '{command}' (FS stalled, FD driver disabled, ...): clear it with 'warnings clear'", reply.warning);
                return Err(self.err(ErrorKind::Refused, message));
            }
            return Ok(reply);
        }
    }

    fn number(&self, reply: &Reply, what: &str) -> Result<i64> {
        reply.data.parse::<i64>().map_err(|_| {
            self.err(ErrorKind::Protocol, format!("{what}: '{}' is not a number of microsteps", reply.data))
        })
    }

    fn get_steps(&mut self, setting: &str) -> Result<i64> {
        let r = self.command(&format!("get {setting}"))?;
        self.number(&r, setting)
    }

    /// Polls until the axis is idle (within the move timeout).
    fn wait_idle(&mut self, what: &str) -> Result<Reply> {
        let deadline = Instant::now() + self.options.move_timeout;
        loop {
            let r = self.command("")?;
            if !r.busy {
                return Ok(r);
            }
            if Instant::now() >= deadline {
                let t = self.options.move_timeout;
                return Err(self.err(ErrorKind::Timeout, format!("{what} did not end within {t:?}")));
            }
            std::thread::sleep(self.options.poll_interval);
        }
    }

    fn to_mm(&self, steps: i64) -> f64 {
        steps as f64 * self.spec.microstep_um * 1e-3
    }
}

impl<L: Read + Write> Stage for ZaberStage<L> {
    fn name(&self) -> String {
        format!("stage zaber:{}", self.spec.port.display())
    }

    fn move_mm(&mut self, z_mm: f64) -> Result<f64> {
        let steps = (z_mm * 1e3 / self.spec.microstep_um).round();
        if !(steps.is_finite() && steps.abs() < 1e15) {
            return Err(self.err(ErrorKind::InvalidInput, format!("position {z_mm} mm is not a position")));
        }
        let command = format!("move abs {}", steps as i64);
        self.command(&command)?;
        let idle = self.wait_idle(&command)?;
        if idle.warning == "WR" {
            return Err(self.err(ErrorKind::Refused, "no reference position (warning WR): home the stage first"));
        }
        self.position_mm()
    }

    fn position_mm(&mut self) -> Result<f64> {
        let steps = self.get_steps("pos")?;
        Ok(self.to_mm(steps))
    }

    fn home(&mut self) -> Result<()> {
        self.command("home")?;
        self.wait_idle("home")?;
        Ok(())
    }

    fn limits_mm(&mut self) -> Result<[f64; 2]> {
        let lo = self.get_steps("limit.min")?;
        let hi = self.get_steps("limit.max")?;
        Ok([self.to_mm(lo), self.to_mm(hi)])
    }

    fn present_offstate_pose(&mut self, k: usize, count: usize) -> Result<()> {
        // The stage moves along the axis only: a hand tilts the board.
        let mut manual = super::manual::StdioManualStage::stdio();
        manual.present_offstate_pose(k, count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replies_parse() {
        let r = Reply::parse("@01 1 OK IDLE -- 12345\r\n").unwrap();
        assert_eq!(
            (r.device, r.axis, r.ok, r.busy, r.warning.as_str(), r.data.as_str()),
            (1, 1, true, false, "--", "12345")
        );
        let r = Reply::parse("@01 1 RJ IDLE -- BADDATA").unwrap();
        assert!(!r.ok && r.data == "BADDATA");
        assert!(Reply::parse("!01 1 IDLE --").is_none() && Reply::parse("@01 1 OK").is_none());
    }
}
