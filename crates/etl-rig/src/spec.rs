//! Device specs as the command line and Python give them: `sim`, `files:DIR`,
//! `aravis:NAME`, `v4l2:/dev/video0` for a camera; `sim`, `manual`,
//! `zaber:PORT[,microstep_um=UM][,device=N][,axis=N]` for a stage; `virtual`,
//! `ld4:PORT` (or a bare port path) or `genicam:NAME[,feature=F][,unit=dpt|ma]
//! [,temperature=F]` for the lens. Parsing checks only the spelling: opening
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
    /// A V4L2 device (cargo feature `v4l2`, Linux), by its path.
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
    /// The lens a GenICam camera drives through its features (cargo feature `aravis`).
    Genicam(GenicamLensSpec),
}

/// What a lens feature of a GenICam camera holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LensUnit {
    /// A focal power, dpt (e.g. `FocalPower`).
    Dpt,
    /// A current, mA.
    Ma,
}

/// `genicam:NAME[,feature=F][,unit=dpt|ma][,temperature=F]` (crate::lens::genicam).
#[derive(Debug, Clone, PartialEq)]
pub struct GenicamLensSpec {
    /// The camera's aravis id.
    pub id: String,
    /// The lens's command feature (default `FocalPower`).
    pub feature: String,
    /// What the feature holds (default dpt).
    pub unit: LensUnit,
    /// The lens's temperature feature, degC (none by default).
    pub temperature: Option<String>,
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
            Some(("genicam", rest)) => parse_genicam(s, rest).map(LensSpec::Genicam),
            _ => {
                Err(bad("lens", s, "unknown lens spec; use virtual, ld4:PORT, a port path or genicam:NAME".to_owned()))
            }
        }
    }
}

fn parse_genicam(s: &str, rest: &str) -> Result<GenicamLensSpec> {
    let mut parts = rest.split(',');
    let id = parts.next().unwrap_or("");
    if id.is_empty() {
        return Err(bad("lens", s, "give the camera's aravis id after 'genicam:' (etlcal camera list)".to_owned()));
    }
    let mut spec =
        GenicamLensSpec { id: id.to_owned(), feature: "FocalPower".to_owned(), unit: LensUnit::Dpt, temperature: None };
    for part in parts {
        let (key, value) = part.split_once('=').unwrap_or((part, ""));
        if value.is_empty() {
            return Err(bad("lens", s, format!("{key}: give a value, {key}=...")));
        }
        match key {
            "feature" => spec.feature = value.to_owned(),
            "temperature" => spec.temperature = Some(value.to_owned()),
            "unit" => {
                spec.unit = match value {
                    "dpt" => LensUnit::Dpt,
                    "ma" => LensUnit::Ma,
                    _ => return Err(bad("lens", s, format!("unit={value}: use unit=dpt or unit=ma"))),
                }
            }
            _ => return Err(bad("lens", s, format!("unknown option '{key}'; use feature, unit, temperature"))),
        }
    }
    Ok(spec)
}

impl std::fmt::Display for LensSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LensSpec::Virtual => write!(f, "virtual"),
            LensSpec::Ld4(p) => write!(f, "{}", p.display()),
            LensSpec::Genicam(g) => {
                let unit = if g.unit == LensUnit::Dpt { "dpt" } else { "ma" };
                write!(f, "genicam:{},feature={},unit={unit}", g.id, g.feature)?;
                match &g.temperature {
                    Some(t) => write!(f, ",temperature={t}"),
                    None => Ok(()),
                }
            }
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
        let g = "genicam:10.0.0.5,temperature=LensTemperature".parse::<LensSpec>().unwrap();
        assert_eq!(g.to_string(), "genicam:10.0.0.5,feature=FocalPower,unit=dpt,temperature=LensTemperature");
        let e = "genicam:cam,unit=A".parse::<LensSpec>().unwrap_err().to_string();
        assert!(e.starts_with("lens genicam:cam,unit=A: unit=A: use unit=dpt or unit=ma"), "{e}");
        assert!("genicam:".parse::<LensSpec>().unwrap_err().to_string().contains("aravis id"));
        assert!("genicam:c,speed=3".parse::<LensSpec>().unwrap_err().to_string().contains("unknown option 'speed'"));
    }
}
