//! The physical model of an ETL group (paper section 2, Eq. 1-10): actuator pressure,
//! membrane deflection and curvature, the focal length of the liquid lens f_liq, the
//! gravity error, and the compound focal length f_com of the ETL behind a prime lens.
//!
//! The camera model does not use it (the paper replaces Eq. 8 and 10 by the cubic of
//! Eq. 12); it is the ground truth of Fig. 5 (how well polynomials of each degree follow
//! f_com) and drives the virtual lens. [`LensPhysics::paper`] holds the section 5.1.1
//! values: f_liq goes from 120.5 mm at 0 mA to 50.5 mm at 250 mA.
//!
//! It also says why the focus law of a calibrated camera ([`crate::focus::FocusLaw`]) has
//! its form: with the sensor fixed, Gaussian imaging makes the vergence of the plane in focus
//! affine in the group's power, Eq. 10 makes that affine in the liquid lens's power, and
//! Eq. 1-4 make the latter nearly affine in the current; on [`LensPhysics::paper`] the
//! current in focus is a quadratic in the vergence to 0.055 mA RMS over 80..225 mA (an affine
//! law leaves 1.1 mA). docs/METHOD.md, "The focus law".
//!
//! [`dynamics`] adds time: the step response, creep and hysteresis of the membrane, and
//! [`shaping`] a command that settles a step faster.
//!
//! Units: pressures in Pa, lengths in mm, currents in mA (the paper's E_com: apply the
//! temperature compensation first, Eq. 8).

pub mod compound;
pub mod dynamics;
pub mod gravity;
pub mod lens;
pub mod membrane;
pub mod shaping;

pub use lens::LensPhysics;
