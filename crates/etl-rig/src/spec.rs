//! Device specs as the command line and Python give them: `sim`, `files:DIR`,
//! `aravis:NAME`, `v4l2:/dev/video0` for a camera; `sim`, `manual`,
//! `zaber:PORT[,microstep_um=UM][,device=N][,axis=N]` for a stage; `virtual` or
//! `ld4:PORT` (or a bare port path) for the lens. Parsing checks only the spelling: opening
//! the device ([`crate::rig`]) finds out whether it is there.

use std::path::PathBuf;

use crate::error::{Error, ErrorKind, Result};

/// A camera.
#[derive(Debug, Clone, PartialEq)]
pub enum CameraSpec {
    /// The synthetic camera: the board rendered at the virtual lens's state and the
    /// simulated stage's position (etl-sim), defocus included.
    Sim,
    /// The images of a folder replayed in name order (PNG, TIFF, JPEG).
    Files(PathBuf),
    /// A GenICam camera through aravis (cargo feature `aravis`), by its aravis id.
    Aravis(String),
    /// A V4L2 device (parsed; opening one is refused: no V4L2 backend yet).
    V4l2(PathBuf),
}

/// A stage.
#[derive(Debug, Clone, PartialEq)]
pub enum StageSpec {
    /// A simulated stage (moves at once, travel [`crate::stage::sim::SIM_TRAVEL_MM`]).
    Sim,
    /// A hand-moved stage: prompts on stderr, reads Enter or the position off stdin.
    Manual,
    /// A Zaber stage over its ASCII protocol.
    Zaber(ZaberSpec),
}

/// A Zaber axis on a serial port.
#[derive(Debug, Clone, PartialEq)]
pub struct ZaberSpec {
    /// The serial port.
    pub port: PathBuf,
    /// The device's microstep size, um (its datasheet's "microstep size"; required: the
    /// protocol counts microsteps and does not say their size).
    pub microstep_um: f64,
    /// Device address (1..=99, default 1: the first device of a chain).
    pub device: u8,
    /// Axis number (1..=9, default 1).
    pub axis: u8,
}

/// A lens.
#[derive(Debug, Clone, PartialEq)]
pub enum LensSpec {
    /// The virtual lens on a pseudo-terminal, driven through the real serial client.
    Virtual,
    /// An Optotune Lens Driver 4 on a serial port.
    Ld4(PathBuf),
}

fn bad(device: &str, spec: &str, message: String) -> Error {
    Error::device(format!("{device} {spec}"), ErrorKind::InvalidInput, message)
}

impl std::str::FromStr for CameraSpec {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        let (kind, rest) = s.split_once(':').unwrap_or((s, ""));
        let need = |what: &str| -> Result<String> {
            if rest.is_empty() {
                return Err(bad("camera", s, format!("give {what} after '{kind}:'")));
            }
            Ok(rest.to_owned())
        };
        match kind {
            "sim" if rest.is_empty() => Ok(CameraSpec::Sim),
            "files" => Ok(CameraSpec::Files(need("a folder")?.into())),
            "aravis" => Ok(CameraSpec::Aravis(need("the camera's aravis id (etlcal camera list)")?)),
            "v4l2" => Ok(CameraSpec::V4l2(need("a device path such as /dev/video0")?.into())),
            _ => Err(bad(
                "camera",
                s,
                "unknown camera spec; use sim, files:DIR, aravis:NAME or v4l2:/dev/videoN".to_owned(),
            )),
        }
    }
}

impl std::fmt::Display for CameraSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CameraSpec::Sim => write!(f, "sim"),
            CameraSpec::Files(d) => write!(f, "files:{}", d.display()),
            CameraSpec::Aravis(n) => write!(f, "aravis:{n}"),
            CameraSpec::V4l2(p) => write!(f, "v4l2:{}", p.display()),
        }
    }
}

impl std::str::FromStr for StageSpec {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.split_once(':') {
            None if s == "sim" => Ok(StageSpec::Sim),
            None if s == "manual" => Ok(StageSpec::Manual),
            Some(("zaber", rest)) => parse_zaber(s, rest).map(StageSpec::Zaber),
            _ => Err(bad("stage", s, "unknown stage spec; use sim, manual or zaber:PORT,microstep_um=UM".to_owned())),
        }
    }
}

fn parse_zaber(s: &str, rest: &str) -> Result<ZaberSpec> {
    let mut parts = rest.split(',');
    let port = parts.next().unwrap_or("");
    if port.is_empty() {
        return Err(bad("stage", s, "give the serial port after 'zaber:'".to_owned()));
    }
    let (mut microstep_um, mut device, mut axis) = (None, 1u8, 1u8);
    for part in parts {
        let (key, value) = part.split_once('=').unwrap_or((part, ""));
        let number = |hi: u8| -> Result<u8> {
            value
                .parse::<u8>()
                .ok()
                .filter(|n| (1..=hi).contains(n))
                .ok_or_else(|| bad("stage", s, format!("{key}={value}: give a whole number in 1..={hi}")))
        };
        match key {
            "microstep_um" => {
                let um = value.parse::<f64>().ok().filter(|u| u.is_finite() && *u > 0.0 && *u <= 1000.0);
                microstep_um = Some(um.ok_or_else(|| {
                    bad("stage", s, format!("microstep_um={value}: give the microstep size in (0, 1000] um"))
                })?);
            }
            "device" => device = number(99)?,
            "axis" => axis = number(9)?,
            _ => return Err(bad("stage", s, format!("unknown option '{key}'; use microstep_um, device, axis"))),
        }
    }
    let microstep_um = microstep_um.ok_or_else(|| {
        bad(
            "stage",
            s,
            "give the microstep size, zaber:PORT,microstep_um=UM (the datasheet's; e.g. 0.047625 for an X-LSM)"
                .to_owned(),
        )
    })?;
    Ok(ZaberSpec { port: port.into(), microstep_um, device, axis })
}

impl std::fmt::Display for StageSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StageSpec::Sim => write!(f, "sim"),
            StageSpec::Manual => write!(f, "manual"),
            StageSpec::Zaber(z) => write!(f, "zaber:{}", z.port.display()),
        }
    }
}

impl std::str::FromStr for LensSpec {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.split_once(':') {
            None if s == "virtual" => Ok(LensSpec::Virtual),
            Some(("ld4", port)) if !port.is_empty() => Ok(LensSpec::Ld4(port.into())),
            None if s.starts_with('/') => Ok(LensSpec::Ld4(s.into())),
            _ => Err(bad("lens", s, "unknown lens spec; use virtual, ld4:PORT or a port path".to_owned())),
        }
    }
}

impl std::fmt::Display for LensSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LensSpec::Virtual => write!(f, "virtual"),
            LensSpec::Ld4(p) => write!(f, "{}", p.display()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_bad_ones_are_named() {
        assert_eq!("sim".parse::<CameraSpec>().unwrap(), CameraSpec::Sim);
        assert_eq!("files:/a".parse::<CameraSpec>().unwrap(), CameraSpec::Files("/a".into()));
        assert_eq!("v4l2:/dev/video0".parse::<CameraSpec>().unwrap(), CameraSpec::V4l2("/dev/video0".into()));
        assert_eq!("aravis:Fake_1".parse::<CameraSpec>().unwrap(), CameraSpec::Aravis("Fake_1".into()));
        let e = "webcam".parse::<CameraSpec>().unwrap_err().to_string();
        assert!(e.starts_with("camera webcam: unknown camera spec"), "{e}");
        let z = "zaber:/dev/ttyUSB0,microstep_um=0.1,axis=2".parse::<StageSpec>().unwrap();
        assert_eq!(
            z,
            StageSpec::Zaber(ZaberSpec { port: "/dev/ttyUSB0".into(), microstep_um: 0.1, device: 1, axis: 2 })
        );
        assert!("zaber:/dev/ttyUSB0".parse::<StageSpec>().unwrap_err().to_string().contains("microstep_um"));
        assert_eq!("manual".parse::<StageSpec>().unwrap(), StageSpec::Manual);
        assert_eq!("/dev/ttyACM0".parse::<LensSpec>().unwrap(), LensSpec::Ld4("/dev/ttyACM0".into()));
        assert_eq!("virtual".parse::<LensSpec>().unwrap(), LensSpec::Virtual);
        assert!("foo".parse::<LensSpec>().is_err());
    }
}
