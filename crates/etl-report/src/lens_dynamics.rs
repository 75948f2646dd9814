//! The report of `etlcal lens characterise`: the lens's step responses as the frames saw
//! them, and the numbers measured from them (settling, hysteresis, creep, repeatability,
//! the fitted membrane, the shaped step).

use std::path::{Path, PathBuf};

use etl_calib::lens_dynamics::{Characterisation, StepResponse};

use crate::figure::{write_figure, Chart, Figure, Series};
use crate::html::esc;
use crate::{Error, Result};

/// The files [`write_characterisation_report`] writes, in its output directory.
pub const CHARACTERISATION_REPORT_FILES: [&str; 3] = ["index.html", "step_responses.png", "step_responses.svg"];

/// One step as the plot shows it: (time since the command in ms, the fraction of the step
/// arrived), so that steps of any size and sign share one axis; the 2 % band is drawn
/// around 1.
fn normalised(s: &StepResponse) -> Vec<(f64, f64)> {
    let Some(&(_, start)) = s.samples.first() else { return vec![] };
    s.samples.iter().map(|&(t, ma)| (1000.0 * t, (ma - start) / s.step_ma)).collect()
}

/// The figure: the up steps and the down steps in two panels, each with the 2 % band.
fn figure(c: &Characterisation) -> Figure {
    let panel = |up: bool| {
        let steps = c.steps.iter().filter(|s| (s.step_ma > 0.0) == up);
        let mut series: Vec<Series> = steps
            .enumerate()
            .map(|(k, s)| {
                let name = format!("{:+.0} mA, settled in {:.2} ms", s.step_ma, 1000.0 * s.settling_s);
                Series::line(name, k, normalised(s))
            })
            .collect();
        let t_end = series.iter().flat_map(|s| s.points.iter().map(|p| p.0)).fold(0.0, f64::max);
        for (name, y) in [("+2 %", 1.02), ("-2 %", 0.98)] {
            series.push(Series::reference(name, 7, vec![(0.0, y), (t_end, y)]));
        }
        Chart {
            title: if up { "Steps up".into() } else { "Steps down".into() },
            x_label: "time since the command, ms".into(),
            y_label: "fraction of the step arrived".into(),
            log_y: false,
            series,
            x_names: vec![],
        }
    };
    Figure { name: "step_responses".into(), grid: (1, 2), panels: vec![panel(true), panel(false)] }
}

/// Writes [`CHARACTERISATION_REPORT_FILES`] for `c` into `dir` (which exists); `source`
/// says what was characterised (e.g. "the virtual lens with fixtures/...json, camera sim at
/// 2000 Hz"). Returns the paths. Errors: a file that cannot be written, a plot that fails.
pub fn write_characterisation_report(c: &Characterisation, source: &str, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = write_figure(dir, &figure(c))?;
    let path = dir.join(CHARACTERISATION_REPORT_FILES[0]);
    std::fs::write(&path, page(c, source)).map_err(|source| Error::Output { path: path.clone(), source })?;
    files.insert(0, path);
    Ok(files)
}

/// The page: what was measured, then the plot and one row per step.
fn page(c: &Characterisation, source: &str) -> String {
    let rows: String = c
        .steps
        .iter()
        .map(|s| {
            format!(
                "<tr><td>{:+.1}</td><td>{:.3}</td><td>{}</td></tr>",
                s.step_ma,
                1000.0 * s.settling_s,
                s.samples.len()
            )
        })
        .collect();
    let shaped = match c.shaped_settling_s {
        Some([u, d]) => format!(
            "The largest step split by the zero-vibration shaper of the fitted membrane settles in {:.2} ms up and \
             {:.2} ms down.",
            1000.0 * u,
            1000.0 * d
        ),
        None => "The fitted membrane is not underdamped: no shaper applies.".into(),
    };
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Lens dynamics</title></head><body>\n\
         <h1>Lens dynamics, measured from frames</h1>\n<p>{source}</p>\n<ul>\
         <li>Settling of the largest step (to 2 % of the step): <b>{up:.2} ms up, {down:.2} ms down</b>. {shaped}</li>\
         <li>Membrane fitted to the largest step up: {f:.1} Hz natural frequency, damping {z:.3}.</li>\
         <li>Hysteresis (one target approached from below and from above): <b>{h:.3} mA</b>.</li>\
         <li>Creep: {cf:.2} % of a step, time constant <b>{ct:.2} s</b>.</li>\
         <li>Repeatability (one target approached from below, 1 std): {r:.4} mA.</li>\
         <li>Image scale: {k:.3} px per mA (every figure is the board's scale in the frames through it).</li></ul>\n\
         <h2>Step responses</h2>\n<p>The current each frame saw (the board's scale mapped to mA), as the fraction \
         of the step arrived, against the time since the command; dashed: the 2 % band.</p>\n\
         <img src=\"{png}\" alt=\"step responses\">\n\
         <table><tr><th>step, mA</th><th>settling, ms</th><th>frames</th></tr>{rows}</table>\n</body></html>\n",
        source = esc(source),
        up = 1000.0 * c.settling_s[0],
        down = 1000.0 * c.settling_s[1],
        f = c.natural_frequency_hz,
        z = c.damping,
        h = c.hysteresis_ma,
        cf = 100.0 * c.creep_fraction,
        ct = c.creep_tau_s,
        r = c.repeatability_ma,
        k = c.scale_px_per_ma,
        png = CHARACTERISATION_REPORT_FILES[1],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(step_ma: f64, settling_s: f64) -> StepResponse {
        let samples =
            (0..50).map(|k| (k as f64 * 5e-4 - 5e-4, 100.0 + step_ma * (1.0 - (-(k as f64) / 8.0).exp()))).collect();
        StepResponse { step_ma, samples, settling_s }
    }

    /// A step's samples are drawn as the fraction arrived; the page states the numbers and
    /// links the plot, which is written.
    #[test]
    fn the_page_and_the_plot() {
        let c = Characterisation {
            steps: vec![step(50.0, 0.015), step(-50.0, 0.0145)],
            settling_s: [0.015, 0.0145],
            hysteresis_ma: 0.45,
            repeatability_ma: 0.01,
            creep_tau_s: 2.1,
            creep_fraction: 0.01,
            natural_frequency_hz: 150.0,
            damping: 0.28,
            scale_px_per_ma: 0.5,
            shaped_settling_s: Some([0.004, 0.004]),
        };
        let n = normalised(&c.steps[1]);
        assert_eq!(n[0], (-0.5, 0.0));
        assert!((n[49].1 - (1.0 - (-49.0f64 / 8.0).exp())).abs() < 1e-12);
        let dir = tempfile::tempdir().unwrap();
        let files = write_characterisation_report(&c, "test <lens>", dir.path()).unwrap();
        let names: Vec<_> = files.iter().map(|p| p.file_name().unwrap().to_str().unwrap().to_owned()).collect();
        assert_eq!(names, CHARACTERISATION_REPORT_FILES);
        let html = std::fs::read_to_string(&files[0]).unwrap();
        assert!(
            html.contains("15.00 ms up, 14.50 ms down")
                && html.contains("0.450 mA")
                && html.contains("test &lt;lens&gt;")
        );
        assert!(html.contains("4.00 ms up"), "{html}");
        assert!(std::fs::metadata(&files[1]).unwrap().len() > 1000);
    }
}
