//! One request per verb behind both front ends: the CLI (`etlcal calibrate`, `etlcal
//! zhang`) and Python (`etlcal.calibrate(...)`, `etlcal.zhang(...)`) only parse their
//! arguments into a [`CalibrationRequest`] or a [`ZhangRequest`] and call its `run`, so
//! that every option exists in both, its default is defined once (here), it is refused by
//! one rule with one message, and the same request gives the same file whichever front end
//! made it (`crates/etl-py/tests/test_request_parity.py` checks it through both).
//!
//! A refusal ([`Refusal`]) carries the option at fault as a stable key
//! ([`RequestOption`]); each front end spells it in its own words ([`Spelling`]): the CLI
//! `--hold-a0`, Python `hold_a0`.

mod calibration;
mod conditioning;
mod option;
mod refusal;
mod zhang;

pub use calibration::{
    Calibrated, CalibrationRequest, CentreChoice, DistortionChoice, EivPriors, EstimatorChoice, FocalDegreeChoice,
    Method, StageSigma, DEFAULT_ROBUST_K_PX,
};
pub use conditioning::{ill_condition, IllCondition, MAX_PRINCIPAL_POINT_STD_FRACTION};
pub use option::{KeySpelling, RequestOption, Spelling};
pub use refusal::{largest, positive, Refusal};
pub use zhang::ZhangRequest;
