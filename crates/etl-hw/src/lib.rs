//! etl-hw: the Optotune Lens Driver 4 serial protocol, temperature sensors and a virtual
//! lens device for tests and demos.
//!
//! - [`codec`]: CRC-16/ARC, every command and reply of the facts sheet
//!   (`docs/PROTOCOL.md`) a user needs, units;
//! - [`client::LensClient`]: the driver over a serial port (`serialport`) or any other
//!   [`transport::Transport`];
//! - [`virtual_lens::VirtualDevice`]: a device model speaking the same protocol, with the
//!   paper's lens physics, a thermal model and fault injection, reached in-process
//!   ([`virtual_lens::VirtualTransport`]) or, on Unix, on a pseudo-terminal
//!   (`virtual_lens::VirtualLens`);
//! - [`ntc`]: an external NTC thermistor (beta, Steinhart-Hart, divider);
//! - [`hold`]: live temperature compensation (hold a wanted E_com);
//! - [`discover`]: finding the driver among the serial ports by USB VID/PID.
//!
//! ```
//! # #[cfg(unix)] {
//! use etl_hw::client::{LensClient, OpenOptions};
//! use etl_hw::virtual_lens::{VirtualLens, VirtualLensConfig};
//!
//! let device = VirtualLens::spawn(VirtualLensConfig::default()).unwrap();
//! let lens = LensClient::open(device.path(), OpenOptions::default()).unwrap();
//! let sent = lens.set_current_ma(100.0).unwrap();
//! assert!((sent.commanded_ma - 100.0).abs() < 0.04); // one DAC step is 0.0715 mA
//! assert!((lens.temperature_c().unwrap() - 25.0).abs() < 1.0);
//! # }
//! ```

pub mod client;
pub mod codec;
pub mod discover;
pub mod error;
pub mod hold;
pub mod ntc;
pub mod transport;
pub mod virtual_lens;

pub use error::{HwError, Result};
