//! The lens of a rig: etl-core's [`Lens`] trait over the Optotune Lens Driver 4 client
//! (`ld4:PORT`), the virtual lens (`virtual`: served on a pseudo-terminal and driven
//! through the same serial client, as `etlcal lens --virtual` does), a GenICam camera's
//! lens features (`genicam:NAME`, module `genicam`, cargo feature `aravis`) or any driver
//! ([`RigLens::from_driver`]), named for errors.
//!
//! A current is always approached from below ([`RigLens::approach_ma`]): the lens first
//! goes [`APPROACH_MA`] under the target, then to it, so that every view sits on the
//! rising branch of the lens's hysteresis loop. With a shaper ([`RigLens::set_shaper`]) the
//! last step up is split by it ([`etl_hw::client::shaped_step`]): the membrane does not
//! ring, and the frames find it settled sooner.

use etl_core::lens::Lens;
use etl_core::physics::shaping::ZvShaper;
use etl_hw::client::{LensClient, OpenOptions};
use etl_hw::virtual_lens::{VirtualDevice, VirtualLens, VirtualLensConfig};
use etl_hw::HwError;

use crate::error::{Error, Result};
use crate::spec::LensSpec;

#[cfg(feature = "aravis")]
pub mod genicam;

/// How far below a target current the lens goes first, mA (larger than the published
/// hysteresis widths of shape-changing-polymer lenses, a few mA).
pub const APPROACH_MA: f64 = 10.0;

/// A lens with its name.
pub struct RigLens {
    name: String,
    lens: Box<dyn Lens<Error = Error>>,
    limits_ma: [f64; 2],
    // Kept alive while the client talks to it (the virtual lens's server).
    virtual_lens: Option<VirtualLens>,
    shaper: Option<ZvShaper>,
}

impl RigLens {
    /// Opens the lens of `spec`; a virtual lens gets `config`.
    pub fn open(spec: &LensSpec, config: VirtualLensConfig) -> Result<RigLens> {
        let name = format!("lens {spec}");
        let (path, virtual_lens) = match spec {
            LensSpec::Virtual => {
                let v = VirtualLens::spawn(config).map_err(|e| Error::lens(&name, e))?;
                (v.path().to_owned(), Some(v))
            }
            LensSpec::Ld4(p) => (p.clone(), None),
            LensSpec::Genicam(g) => return open_genicam(g, &name),
        };
        let client = LensClient::open(&path, OpenOptions::default()).map_err(|e| Error::lens(&name, e))?;
        let limits_ma = client.limits_ma();
        let lens = Box::new(Named { name: name.clone(), lens: Box::new(client) });
        Ok(RigLens { name, lens, limits_ma, virtual_lens, shaper: None })
    }

    /// Any lens behind the trait with etl-hw's errors (a test double, another serial
    /// driver), named `name`, with its driver's limits `[lo, hi]` mA; its errors are led by
    /// the name.
    pub fn from_lens(name: impl Into<String>, lens: Box<dyn Lens<Error = HwError>>, limits_ma: [f64; 2]) -> RigLens {
        let name = name.into();
        let lens = Box::new(Named { name: name.clone(), lens });
        RigLens { name, lens, limits_ma, virtual_lens: None, shaper: None }
    }

    /// A driver whose errors are the rig's, each naming its device already (a Python
    /// object, a GenICam camera's lens), named `name`, with limits `[lo, hi]` mA.
    pub fn from_driver(name: impl Into<String>, lens: Box<dyn Lens<Error = Error>>, limits_ma: [f64; 2]) -> RigLens {
        RigLens { name: name.into(), lens, limits_ma, virtual_lens: None, shaper: None }
    }

    /// The device's name in errors: `lens SPEC`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The driver's current limits, mA.
    pub fn limits_ma(&self) -> [f64; 2] {
        self.limits_ma
    }

    /// The virtual lens's device, when this is the virtual lens.
    pub fn virtual_device(&self) -> Option<&VirtualDevice> {
        self.virtual_lens.as_ref().map(|v| v.device())
    }

    /// The virtual lens (its faults, its pty), when this is the virtual lens.
    pub fn virtual_lens(&self) -> Option<&VirtualLens> {
        self.virtual_lens.as_ref()
    }

    /// Commands `e_in_ma`; returns the current commanded (clamped, quantised), mA.
    pub fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        self.lens.set_current_ma(e_in_ma)
    }

    /// Splits every approach's last step by `shaper` (None: plain steps).
    pub fn set_shaper(&mut self, shaper: Option<ZvShaper>) {
        self.shaper = shaper;
    }

    /// Goes to `e_in_ma` from below: first [`APPROACH_MA`] under it (within the driver's
    /// lower limit), then to it, that step shaped when a shaper is set; returns the
    /// current commanded, mA.
    pub fn approach_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        let below = self.set_current_ma((e_in_ma - APPROACH_MA).max(self.limits_ma[0]))?;
        let Some(z) = self.shaper else { return self.set_current_ma(e_in_ma) };
        let ((_, to), _) = etl_hw::client::shaped_step(below, e_in_ma, &z, |ma| self.set_current_ma(ma))?;
        Ok(to)
    }

    /// The lens temperature, degC.
    pub fn temperature_c(&mut self) -> Result<f64> {
        self.lens.temperature_c()
    }

    /// The current the driver is at, mA.
    pub fn current_ma(&mut self) -> Result<f64> {
        self.lens.current_ma()
    }
}

#[cfg(feature = "aravis")]
fn open_genicam(spec: &crate::spec::GenicamLensSpec, _name: &str) -> Result<RigLens> {
    RigLens::genicam(genicam::GenicamLens::open(spec)?)
}

#[cfg(not(feature = "aravis"))]
fn open_genicam(_spec: &crate::spec::GenicamLensSpec, name: &str) -> Result<RigLens> {
    let message =
        "this etlcal was built without the aravis feature (cargo install --path crates/etlcal --features aravis)";
    Err(Error::device(name, crate::error::ErrorKind::InvalidInput, message))
}

#[cfg(feature = "aravis")]
impl RigLens {
    /// The lens of a GenICam camera, its limits the command feature's bounds.
    pub fn genicam(lens: genicam::GenicamLens) -> Result<RigLens> {
        let limits_ma = lens.limits_ma()?;
        Ok(RigLens::from_driver(lens.name().to_owned(), Box::new(lens), limits_ma))
    }
}

/// An etl-hw lens whose errors become the rig's, led by the lens's name.
struct Named {
    name: String,
    lens: Box<dyn Lens<Error = HwError>>,
}

impl Lens for Named {
    type Error = Error;
    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        self.lens.set_current_ma(e_in_ma).map_err(|e| Error::lens(&self.name, e))
    }
    fn current_ma(&mut self) -> Result<f64> {
        self.lens.current_ma().map_err(|e| Error::lens(&self.name, e))
    }
    fn temperature_c(&mut self) -> Result<f64> {
        self.lens.temperature_c().map_err(|e| Error::lens(&self.name, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};
    use std::time::Instant;

    /// A lens that logs each current commanded and when.
    struct Log(Arc<Mutex<Vec<(f64, Instant)>>>);

    impl Lens for Log {
        type Error = HwError;
        fn set_current_ma(&mut self, e_in_ma: f64) -> std::result::Result<f64, HwError> {
            self.0.lock().unwrap().push((e_in_ma, Instant::now()));
            Ok(e_in_ma)
        }
        fn current_ma(&mut self) -> std::result::Result<f64, HwError> {
            Ok(self.0.lock().unwrap().last().map_or(0.0, |c| c.0))
        }
        fn temperature_c(&mut self) -> std::result::Result<f64, HwError> {
            Ok(27.0)
        }
    }

    /// An approach goes 10 mA under the target, then up: plainly, or by the shaper (its
    /// fraction of the 10 mA at once, the target no earlier than its delay later).
    #[test]
    fn an_approach_from_below_plain_and_shaped() {
        let log = Arc::new(Mutex::new(vec![]));
        let mut lens = RigLens::from_lens("lens test", Box::new(Log(Arc::clone(&log))), [-290.0, 290.0]);
        assert_eq!(lens.approach_ma(150.0).unwrap(), 150.0);
        let plain: Vec<f64> = log.lock().unwrap().iter().map(|c| c.0).collect();
        assert_eq!(plain, [140.0, 150.0]);
        log.lock().unwrap().clear();
        lens.set_shaper(Some(ZvShaper { first_fraction: 0.7, delay_s: 0.006 }));
        assert_eq!(lens.approach_ma(150.0).unwrap(), 150.0);
        let shaped = log.lock().unwrap().clone();
        let currents: Vec<f64> = shaped.iter().map(|c| c.0).collect();
        assert_eq!(currents, [140.0, 147.0, 150.0]);
        assert!(shaped[2].1.duration_since(shaped[1].1).as_secs_f64() >= 0.006);
    }
}
