//! Fault injection for the virtual lens: what a flaky cable, a busy driver or a firmware
//! quirk does to the byte stream. Counters apply to the next N events and count down.

use std::time::Duration;

/// Faults the virtual lens injects (all off by default). Set them with
/// [`VirtualDevice::set_faults`](super::VirtualDevice::set_faults) or
/// [`VirtualDevice::with_faults`](super::VirtualDevice::with_faults).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Faults {
    /// Every reply is sent this long (wall time) after its command.
    pub reply_delay: Duration,
    /// The next N replies are never sent (the command is executed).
    pub silence_next: u32,
    /// The next N replies have a CRC byte flipped.
    pub corrupt_next: u32,
    /// Sent before the next reply, once (stray bytes on the line).
    pub garbage_before_next: Vec<u8>,
    /// The next N commands are treated as if their CRC had failed (not executed; answered
    /// `E 01`, or `N\r\n` when [`VirtualLensConfig::nack_on_crc`](super::VirtualLensConfig::nack_on_crc) is set).
    pub crc_error_next: u32,
    /// The next command (also a fire-and-forget one) is not executed and answered with
    /// the error frame `E` + this id.
    pub error_frame_next: Option<u8>,
    /// The next N bytes the host sends are lost.
    pub drop_rx_bytes_next: u32,
}

impl Faults {
    /// A reply delay of `ms` milliseconds, which must lie in
    /// 0..=[`MAX_REPLY_DELAY_MS`](super::MAX_REPLY_DELAY_MS) (finite): the checked
    /// conversion instead of `Duration::from_secs_f64`, which panics on huge values.
    ///
    /// ```
    /// use etl_hw::virtual_lens::Faults;
    /// assert_eq!(Faults::reply_delay_from_ms(250.0).unwrap().as_millis(), 250);
    /// assert!(Faults::reply_delay_from_ms(1e30).is_err() && Faults::reply_delay_from_ms(-1.0).is_err());
    /// ```
    pub fn reply_delay_from_ms(ms: f64) -> Result<Duration, etl_core::Error> {
        let bad = etl_core::Error::InvalidArgument { what: "reply delay must lie in 0..=60000 ms" };
        if !(0.0..=super::MAX_REPLY_DELAY_MS).contains(&ms) {
            return Err(bad);
        }
        Duration::try_from_secs_f64(ms / 1e3).map_err(|_| bad)
    }
}
