//! `etlcal lens --virtual --dynamics F characterise --camera sim`: the lens's dynamics
//! measured from frames alone ([`etl_calib::lens_dynamics::characterise`]), printed and
//! optionally written as `etlcal.lens-dynamics/1` (`--out`) and as a report with the step
//! responses plotted (`--report DIR`: index.html, step_responses.png and .svg; the
//! directory replaced as a set; `--json` lists the files under `"report"`).

use std::path::PathBuf;

use etl_calib::lens_dynamics::{characterise, Characterisation, CharacteriseOptions};
use etl_core::physics::dynamics::LensDynamics;
use etl_formats::output::Output;
use etl_formats::{compact, Error, LensDynamicsFile, Result};
use etl_hw::client::LensClient;
use etl_hw::virtual_lens::VirtualLens;
use etl_sim::lens_camera::SimLensCamera;
use serde_json::json;

use super::print_json;

/// Arguments of `etlcal lens characterise`.
#[derive(clap::Args, Debug)]
pub struct CharacteriseArgs {
    /// The camera that frames the lens: `sim` (a board rendered at the virtual lens's state
    /// at each frame's time; needs `--virtual --dynamics F`). Real cameras: not yet.
    #[arg(long, value_name = "SPEC")]
    pub camera: String,
    /// The camera's frame rate, Hz (1..=100000).
    #[arg(long, default_value_t = 2000.0, value_name = "HZ")]
    pub frame_rate: f64,
    /// Where to write the measured dynamics (`etlcal.lens-dynamics/1`; the temperature's
    /// time constant and self-heating are not measured and are written as the published
    /// defaults, which the file's `source` says).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Also write a report into DIR (created if missing, replaced as a set): index.html
    /// with the measured numbers and the step responses plotted.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// The simulated camera on `device`, refused in one line for any other SPEC or lens.
fn camera(a: &CharacteriseArgs, device: Option<&VirtualLens>, has_dynamics: bool) -> Result<SimLensCamera> {
    if a.camera != "sim" {
        let message = format!("--camera {}: only `sim` exists yet (real cameras are not built)", a.camera);
        return Err(Error::invalid_value("--camera", a.camera.as_str(), message));
    }
    let Some(device) = device else {
        return Err(Error::invalid("--camera", "--camera sim frames the virtual lens: pass --virtual --dynamics F"));
    };
    if !has_dynamics {
        return Err(Error::invalid(
            "--dynamics",
            "a virtual lens without --dynamics follows its current at once: there is nothing to characterise",
        ));
    }
    SimLensCamera::new(device.device().clone(), a.frame_rate)
        .map_err(|e| e.rename_input("frame_rate_hz", "--frame-rate"))
}

/// The measured numbers as the file, with the unmeasured thermal ones said in `source`.
fn as_file(c: &Characterisation) -> LensDynamicsFile {
    let p = LensDynamics::PUBLISHED;
    let d = LensDynamics {
        natural_frequency_hz: c.natural_frequency_hz,
        damping: c.damping,
        creep_fraction: c.creep_fraction.clamp(0.0, 0.5),
        creep_tau_s: c.creep_tau_s,
        hysteresis_ma: c.hysteresis_ma.max(0.0),
        ..p
    };
    let source = format!(
        "measured by etlcal lens characterise (step response, creep, hysteresis, from frames); thermal_tau_s {} s and \
         self_heating_c_per_ma {} not measured: the published defaults",
        compact(p.thermal_tau_s),
        compact(p.self_heating_c_per_ma)
    );
    LensDynamicsFile::new(&d, Some(source))
}

/// Writes the report of `c` into `dir` as a set; the paths written.
fn report(c: &Characterisation, a: &CharacteriseArgs, dir: &std::path::Path, json_out: bool) -> Result<Vec<String>> {
    use etl_report::lens_dynamics::{write_characterisation_report, CHARACTERISATION_REPORT_FILES};
    let source = format!("the virtual lens with its dynamics, framed by camera {} at {} Hz", a.camera, a.frame_rate);
    let files = crate::output::write_dir_set(dir, &CHARACTERISATION_REPORT_FILES, |staging| {
        let files = write_characterisation_report(c, &source, staging)?;
        Ok(crate::output::moved(files, staging, dir))
    })?;
    if !json_out {
        outln!("wrote the report to {} (open index.html)", dir.display());
    }
    Ok(files.iter().map(|p| p.display().to_string()).collect())
}

/// Runs `etlcal lens characterise`.
pub fn run(
    client: &mut LensClient,
    device: Option<&VirtualLens>,
    has_dynamics: bool,
    a: &CharacteriseArgs,
    json_out: bool,
) -> Result<()> {
    let outputs: Vec<Output<'_>> =
        a.out.iter().map(|f| Output::File(f)).chain(a.report.iter().map(|d| Output::Dir(d))).collect();
    crate::output::check([], &outputs)?;
    let mut cam = camera(a, device, has_dynamics)?;
    let c = characterise(client, &mut cam, &CharacteriseOptions::default(), &crate::progress::Bar::new(!json_out))?;
    if let Some(out) = &a.out {
        crate::output::create_parent(out)?;
        as_file(&c).save(out)?;
    }
    let report = match &a.report {
        Some(dir) => report(&c, a, dir, json_out)?,
        None => vec![],
    };
    let steps: Vec<_> =
        c.steps.iter().map(|s| json!({"step_ma": s.step_ma, "settling_ms": 1000.0 * s.settling_s})).collect();
    let mut j = json!({
        "settling_ms": {"up": 1000.0 * c.settling_s[0], "down": 1000.0 * c.settling_s[1]},
        "hysteresis_ma": c.hysteresis_ma,
        "creep_tau_s": c.creep_tau_s,
        "creep_fraction": c.creep_fraction,
        "repeatability_ma": c.repeatability_ma,
        "natural_frequency_hz": c.natural_frequency_hz,
        "damping": c.damping,
        "scale_px_per_ma": c.scale_px_per_ma,
        "shaped_settling_ms": c.shaped_settling_s.map(|s| json!({"up": 1000.0 * s[0], "down": 1000.0 * s[1]})),
        "steps": steps,
    });
    if a.report.is_some() {
        j["report"] = json!(report);
    }
    if json_out {
        print_json(&j);
    } else {
        outln!(
            "settling {:.2} ms up, {:.2} ms down (largest step, to 2 %); hysteresis {:.3} mA; creep {:.2} % over {:.2} s; \
             repeatability {:.4} mA; {:.1} Hz, damping {:.3}",
            1000.0 * c.settling_s[0],
            1000.0 * c.settling_s[1],
            c.hysteresis_ma,
            100.0 * c.creep_fraction,
            c.creep_tau_s,
            c.repeatability_ma,
            c.natural_frequency_hz,
            c.damping
        );
    }
    Ok(())
}
