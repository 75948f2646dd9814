//! Finding the Lens Driver 4 among the serial ports: USB VID 0x03EB (Atmel) / PID 0x2018,
//! or "Optotune" in the USB product/manufacturer strings (facts sheet section 1; the
//! VID/PID rests on one source, so the description is a second chance).

use serialport::{SerialPortInfo, SerialPortType};

/// USB vendor id of the Lens Driver 4 (Atmel).
pub const LD4_VID: u16 = 0x03EB;
/// USB product id of the Lens Driver 4.
pub const LD4_PID: u16 = 0x2018;

/// Whether a port looks like a Lens Driver 4.
///
/// ```
/// use serialport::{SerialPortInfo, SerialPortType, UsbPortInfo};
/// let usb = |vid, pid, product: Option<&str>| SerialPortInfo {
///     port_name: "/dev/ttyACM0".into(),
///     port_type: SerialPortType::UsbPort(UsbPortInfo {
///         vid, pid, serial_number: None, manufacturer: None, product: product.map(Into::into),
///     }),
/// };
/// assert!(etl_hw::discover::is_lens_driver(&usb(0x03EB, 0x2018, None)));
/// assert!(etl_hw::discover::is_lens_driver(&usb(0x1234, 0x1, Some("Optotune LD"))));
/// assert!(!etl_hw::discover::is_lens_driver(&usb(0x2341, 0x0043, Some("Arduino Uno"))));
/// ```
pub fn is_lens_driver(info: &SerialPortInfo) -> bool {
    match &info.port_type {
        SerialPortType::UsbPort(u) => {
            let named = |s: &Option<String>| s.as_deref().is_some_and(|s| s.to_ascii_lowercase().contains("optotune"));
            (u.vid == LD4_VID && u.pid == LD4_PID) || named(&u.product) || named(&u.manufacturer)
        }
        _ => false,
    }
}

/// The paths of the serial ports that look like a Lens Driver 4 (empty if enumeration
/// fails).
pub fn find_lens_drivers() -> Vec<String> {
    serialport::available_ports()
        .map(|ports| ports.into_iter().filter(is_lens_driver).map(|p| p.port_name).collect())
        .unwrap_or_default()
}
