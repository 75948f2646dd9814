//! [`Transport`]: the byte link under [`crate::client::LensClient`], the serial port in
//! production, something else in tests (a scripted transcript, the in-process
//! [`crate::virtual_lens::VirtualTransport`]).
//!
//! The client needs four things of a link and nothing more: send a command's bytes, know
//! how many received bytes wait (to drain stray frames before a command), read with a
//! deadline (every read has one, so that no call hangs) and discard unread input (after a
//! corrupted reply, the rest of the frame is garbage).

use std::io::{self, Read, Write};
use std::time::Duration;

use serialport::{ClearBuffer, SerialPort};

/// A byte link to a Lens Driver 4.
pub trait Transport {
    /// Writes every byte of `bytes` and flushes them onto the line.
    fn send(&mut self, bytes: &[u8]) -> io::Result<()>;

    /// How many received bytes can be read now without waiting.
    fn bytes_waiting(&mut self) -> io::Result<usize>;

    /// Reads received bytes into `buf`, waiting at most `timeout` for the first one;
    /// `Ok(0)` when nothing arrived in time (a timeout is not an error here: the client
    /// keeps its own deadline over several reads).
    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize>;

    /// Discards received bytes not yet read. Best effort: the next command's drain
    /// resynchronises the line anyway.
    fn discard_input(&mut self) -> io::Result<()>;

    /// A name for messages (the port path of a serial port).
    fn name(&self) -> String {
        "transport".to_owned()
    }
}

/// The serial port (`serialport`): the default transport of the client.
impl Transport for Box<dyn SerialPort> {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.write_all(bytes)?;
        self.flush()
    }

    fn bytes_waiting(&mut self) -> io::Result<usize> {
        let n = self.bytes_to_read().map_err(io::Error::from)?;
        // u32 -> usize cannot fail on the 32- and 64-bit targets serialport supports.
        Ok(usize::try_from(n).unwrap_or(usize::MAX))
    }

    fn receive(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.set_timeout(timeout).map_err(io::Error::from)?;
        match self.read(buf) {
            Err(e) if e.kind() == io::ErrorKind::TimedOut => Ok(0),
            r => r,
        }
    }

    fn discard_input(&mut self) -> io::Result<()> {
        self.clear(ClearBuffer::Input).map_err(io::Error::from)
    }

    fn name(&self) -> String {
        SerialPort::name(&**self).unwrap_or_else(|| "serial port".to_owned())
    }
}
