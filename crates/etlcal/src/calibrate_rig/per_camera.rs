//! `calibrate-rig`'s per-camera flags: `--thermal [CAM=]FILE|paper` (every camera's lens,
//! or one camera's) and `--camera-flags CAM="FLAGS"` (the method, model and
//! bundle-adjustment flags of `calibrate` for one camera, parsed by the same parser as
//! the shared ones and applied on top of them), turned into etl-calib's per-camera
//! requests ([`etl_calib::rig_calibration::CameraRequest`]). CAM is a camera's index or
//! name, as `triangulate --pixel CAM:U,V` resolves it.

use std::path::{Path, PathBuf};

use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches};
use etl_calib::request::{CalibrationRequest, DistortionChoice, FocalDegreeChoice, RequestOption};
use etl_calib::rig_calibration::CameraRequest;
use etl_formats::calibration::ThermalRef;
use etl_formats::{Error, Result};
use serde_json::{json, Value};

use crate::calibrate::RequestFlags;
use crate::rig_setting::camera_index;

/// The parser of `--camera-flags`' FLAGS: the request flags of `calibrate`, alone.
#[derive(clap::Parser, Debug)]
#[command(name = "--camera-flags", no_binary_name = true, disable_help_flag = true, disable_version_flag = true)]
struct CameraFlagsParser {
    #[command(flatten)]
    request: RequestFlags,
}

/// One `--camera-flags CAM="FLAGS"`: the camera as given, its flags and the options they
/// set (what is applied on top of the shared request).
#[derive(Debug)]
pub struct CameraFlags {
    /// The value as given (for messages).
    pub value: String,
    /// CAM as given.
    pub cam: String,
    /// FLAGS parsed.
    pub flags: RequestFlags,
    /// The options FLAGS give.
    pub given: Vec<RequestOption>,
}

/// The refusal of a `--camera-flags` value.
fn bad_flags(value: &str, why: impl std::fmt::Display) -> Error {
    Error::invalid_value("--camera-flags", value, format!("--camera-flags {value:?}: {why}"))
}

/// Parses one `--camera-flags CAM="FLAGS"` (FLAGS split as a POSIX shell splits words:
/// quotes keep a value with spaces whole). Refused in one
/// line: no `CAM=`, a flag that is not per camera (`--out`, `--solver`, `--dataset`,
/// `--json`, and `--thermal`, which has its own `CAM=FILE` form), what the parser of
/// `calibrate`'s flags refuses.
pub fn parse_camera_flags(value: &str) -> Result<CameraFlags> {
    let (cam, words) = value.split_once('=').ok_or_else(|| bad_flags(value, "give CAM=\"FLAGS\""))?;
    if cam.trim().is_empty() {
        return Err(bad_flags(value, "give CAM=\"FLAGS\" (CAM a camera's index or name)"));
    }
    // Split as a POSIX shell would, so that a value with spaces can be quoted in FLAGS.
    let words =
        shlex::split(words).ok_or_else(|| bad_flags(value, "FLAGS has an unclosed quote or ends in a backslash"))?;
    let command = CameraFlagsParser::command();
    let longs: Vec<String> = command.get_arguments().filter_map(|a| a.get_long()).map(|l| format!("--{l}")).collect();
    for word in words.iter().filter(|w| w.starts_with("--")) {
        let name = word.split('=').next().unwrap_or(word.as_str());
        if name == "--thermal" {
            return Err(bad_flags(value, "a camera's lens surface is --thermal CAM=FILE|paper, not one of its flags"));
        }
        if !longs.iter().any(|l| l == name) {
            return Err(bad_flags(
                value,
                format!("{name} is not a per-camera flag (per camera: the method, model and bundle-adjustment flags of calibrate)"),
            ));
        }
    }
    let matches = command.try_get_matches_from(&words).map_err(|e| {
        let text = e.render().to_string();
        bad_flags(value, text.lines().next().unwrap_or("").trim_start_matches("error: "))
    })?;
    let parsed = CameraFlagsParser::from_arg_matches(&matches).map_err(|e| bad_flags(value, e.kind()))?;
    let given = matches
        .ids()
        .filter(|id| matches.value_source(id.as_str()) == Some(ValueSource::CommandLine))
        .filter_map(|id| match id.as_str() {
            "huber_px" => Some(RequestOption::Robust),
            key => RequestOption::from_key(key),
        })
        .collect();
    Ok(CameraFlags { value: value.to_owned(), cam: cam.trim().to_owned(), flags: parsed.request, given })
}

/// Every path `--thermal` values may name (the whole value, and what follows a `CAM=`),
/// `paper` left out: the inputs an output must not overwrite.
pub fn thermal_paths(values: &[String]) -> Vec<PathBuf> {
    let mut paths = vec![];
    for v in values {
        paths.push(PathBuf::from(v));
        paths.extend(v.split_once('=').map(|(_, file)| PathBuf::from(file)));
    }
    paths.retain(|p| crate::output::thermal_file(Some(p)).is_some());
    paths
}

/// The surfaces `--thermal` gives: every camera's, and each camera's own (by index).
#[derive(Debug, Default)]
pub struct Surfaces {
    /// `--thermal FILE|paper`: every camera's without its own.
    pub shared: Option<PathBuf>,
    /// `--thermal CAM=FILE|paper`: camera index, surface.
    pub per_camera: Vec<(usize, PathBuf)>,
}

/// The surfaces of `--thermal` values for a rig of cameras `names`: `CAM=FILE` when what
/// precedes the first `=` is a camera of the rig, else the whole value is every camera's
/// file. Refused in one line: two for every camera, two for one camera, a value with
/// `CAM=` whose CAM is no camera and which is no file either.
pub fn surfaces(values: &[String], names: &[&str]) -> Result<Surfaces> {
    let mut out = Surfaces::default();
    for v in values {
        let bad = |why: String| Error::invalid_value("--thermal", v.as_str(), format!("--thermal {v:?}: {why}"));
        let own = v.split_once('=').and_then(|(cam, file)| camera_index(names, cam).map(|k| (k, file)));
        match own {
            Some((k, file)) => {
                if out.per_camera.iter().any(|(c, _)| *c == k) {
                    return Err(bad(format!("camera {k} ({}) is given a surface twice", names[k])));
                }
                out.per_camera.push((k, PathBuf::from(file)));
            }
            None => {
                if let Some((cam, _)) = v.split_once('=').filter(|_| !Path::new(v).exists()) {
                    let why = format!(
                        "{cam:?} is not a camera of the rig (an index or a name; its cameras: {}) and {v:?} is no file",
                        names.join(", ")
                    );
                    return Err(bad(why));
                }
                if out.shared.is_some() {
                    return Err(bad("every camera's surface is given twice (one --thermal FILE|paper)".into()));
                }
                out.shared = Some(PathBuf::from(v));
            }
        }
    }
    Ok(out)
}

/// The cameras' own requests: `shared` (the rig's request, its surface included) with each
/// camera's `--camera-flags` applied on top and its own `--thermal CAM=FILE`, for the
/// cameras that have either, in the rig's order. Refused in one line: a CAM that is no
/// camera of the rig, one camera's flags given twice.
pub fn camera_requests(
    shared: &CalibrationRequest,
    flags: &[CameraFlags],
    own_surfaces: &[(usize, PathBuf)],
    names: &[&str],
) -> Result<Vec<CameraRequest>> {
    let mut resolved: Vec<(usize, &CameraFlags)> = vec![];
    for f in flags {
        let k = camera_index(names, &f.cam).ok_or_else(|| {
            bad_flags(
                &f.value,
                format!(
                    "{:?} is not a camera of the rig (an index or a name; its cameras: {})",
                    f.cam,
                    names.join(", ")
                ),
            )
        })?;
        if resolved.iter().any(|(c, _)| *c == k) {
            return Err(bad_flags(&f.value, format!("camera {k} ({}) is given its flags twice", names[k])));
        }
        resolved.push((k, f));
    }
    let mut requests = vec![];
    for (k, name) in names.iter().enumerate() {
        let flags = resolved.iter().find(|(c, _)| *c == k).map(|(_, f)| *f);
        let surface = own_surfaces.iter().find(|(c, _)| *c == k).map(|(_, p)| p.as_path());
        if flags.is_none() && surface.is_none() {
            continue;
        }
        let mut request = match flags {
            Some(f) => shared.overridden(&f.flags.request(None)?, &f.given),
            None => shared.clone(),
        };
        if let Some(path) = surface {
            request.thermal = Some(ThermalRef::choose(path)?);
        }
        requests.push(CameraRequest { camera: (*name).to_owned(), request });
    }
    Ok(requests)
}

/// What `--json` says of the request a camera got: its surface (the file, `paper`, or
/// null), its model choices and its estimator's options.
pub fn request_summary(r: &CalibrationRequest) -> Value {
    let distortion = match (r.model_auto, r.distortion) {
        (true, _) | (false, Some(DistortionChoice::Auto)) => "auto".to_owned(),
        (false, Some(DistortionChoice::Family(f))) => f.name().to_owned(),
        (false, None) => etl_core::model::DistortionModel::Paper.name().to_owned(),
    };
    let focal_degree = match (r.model_auto, r.focal_degree) {
        (true, _) | (false, Some(FocalDegreeChoice::Auto)) => json!("auto"),
        (false, Some(FocalDegreeChoice::Degree(d))) => json!(d),
        (false, None) => json!(etl_core::model::PAPER_FOCAL_DEGREE),
    };
    let centre = match (r.model_auto, r.centre) {
        (true, _) => "auto",
        (false, c) => c.map_or("fixed", |c| c.word()),
    };
    json!({
        "thermal": r.thermal.as_ref().map(|t| t.source.clone().unwrap_or_default()),
        "distortion": distortion,
        "focal_degree": focal_degree,
        "centre": centre,
        "fix_k3": r.fix_k3,
        "zero_tangent": r.zero_tangent,
        "a0": if r.a0.is_some() { "given" } else { "lens-off views" },
        "hold_a0": r.hold_a0,
        "estimator": if matches!(r.estimator(), etl_core::calib::Estimator::Paper) { "paper" } else { "eiv" },
        "sigma_px": r.priors.sigma_px,
        "sigma_e_ma": r.input_noise().sigma_e_ma,
    })
}
