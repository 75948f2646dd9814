//! The lens's dynamics measured from frames alone (`etlcal lens characterise`): how long
//! a step takes to settle, up and down, the width of the hysteresis loop, the creep, the
//! repeatability, and the membrane's natural frequency and damping
//! ([`etl_core::physics::dynamics`] is the model they are the numbers of).
//!
//! The camera looks at a checkerboard through the lens. The lens's power sets the image's
//! scale, so the mean distance of the detected corners from their centroid follows the
//! current the optics are at ([`board_scale`]). Two levels approached from below, far
//! apart and each read after the lens has come to rest, map the scale to mA (both carry
//! the same offset of the loop, which so cancels). Then:
//! - each step of [`CharacteriseOptions::steps_ma`], up from `base_ma` and back down, is
//!   framed at the camera's rate for `window_s`; the settling time is when the measured
//!   current last leaves `tolerance_fraction` of the step about the level the window ends
//!   at ([`analysis::settling_s`]); the largest up step fits the natural frequency and
//!   damping ([`analysis::second_order_fit`]);
//! - one target approached from below and from above, `repeats` times each, gives the
//!   loop's width (the mean difference) and the repeatability (the spread from below);
//! - the largest step framed over `creep_s`, past its ringing, fits the creep's
//!   exponential beside a linear drift, the lens warming at its new current
//!   ([`analysis::exponential_fit`]).
//!
//! Last, the largest step is taken again with the command split by the zero-vibration
//! shaper of the fitted membrane ([`ZvShaper`]), and its settling timed the same way:
//! what shaping gains on this lens, measured in frames.
//!
//! Choices: levels are read after `rest_s` (several creep time constants, so creep does
//! not bias them); the step window starts at the command (the camera's own latency is
//! not corrected).

pub mod analysis;

use etl_core::lens::Lens;
use etl_core::physics::dynamics::LensDynamics;
use etl_core::physics::shaping::ZvShaper;
use etl_core::progress::Progress;
use etl_formats::{Error, Result};
use etl_image::checkerboard::detect_corners;
/// The board pattern a [`TimedCamera`] sees (etl-image's).
pub use etl_image::checkerboard::Pattern;
use image::GrayImage;

use analysis::Sample;

/// A camera that frames the lens at its own rate.
pub trait TimedCamera {
    /// Grabs the next frame: its time (s, on a monotonic clock) and the image.
    fn grab(&mut self) -> Result<(f64, GrayImage)>;
    /// Lets `s` seconds pass without framing (a real rig sleeps).
    fn wait_s(&mut self, s: f64) -> Result<()>;
    /// The present time on the frames' clock, s.
    fn now_s(&self) -> f64;
    /// The pattern of the board it sees.
    fn pattern(&self) -> Pattern;
}

/// What the characterisation does.
#[derive(Debug, Clone, PartialEq)]
pub struct CharacteriseOptions {
    /// The level the steps start from, mA.
    pub base_ma: f64,
    /// The step sizes, mA (positive; each is taken up and back down).
    pub steps_ma: Vec<f64>,
    /// How long each step is framed, s.
    pub window_s: f64,
    /// The settling tolerance, as a fraction of the step.
    pub tolerance_fraction: f64,
    /// How long the lens rests before a level is read, s.
    pub rest_s: f64,
    /// Frames averaged for a level at rest.
    pub level_frames: usize,
    /// The hysteresis target's distance above `base_ma` and the approach from either side, mA.
    pub hysteresis_approach_ma: f64,
    /// Approaches from each side.
    pub repeats: usize,
    /// How long the creep is framed, s, and the frames it takes.
    pub creep_s: f64,
    /// Frames of the creep record.
    pub creep_frames: usize,
}

impl CharacteriseOptions {
    /// The largest of `steps_ma`, mA.
    pub fn largest_step_ma(&self) -> f64 {
        self.steps_ma.iter().copied().fold(0.0, f64::max)
    }
}

impl Default for CharacteriseOptions {
    /// Steps of 10, 25 and 50 mA from 100 mA framed for 60 ms, a 2 % tolerance, 10 s of
    /// rest, a 25 mA approach, 5 repeats, 10 s of creep in 60 frames.
    fn default() -> Self {
        CharacteriseOptions {
            base_ma: 100.0,
            steps_ma: vec![10.0, 25.0, 50.0],
            window_s: 0.06,
            tolerance_fraction: 0.02,
            rest_s: 10.0,
            level_frames: 5,
            hysteresis_approach_ma: 25.0,
            repeats: 5,
            creep_s: 10.0,
            creep_frames: 60,
        }
    }
}

/// One step's response.
#[derive(Debug, Clone, PartialEq)]
pub struct StepResponse {
    /// The step, mA (negative: down).
    pub step_ma: f64,
    /// The measured current at each frame: (time since the command s, mA); the first, at
    /// a negative time, just before the command.
    pub samples: Vec<Sample>,
    /// The settling time, s.
    pub settling_s: f64,
}

/// What was measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Characterisation {
    /// Every step's response, in the order taken.
    pub steps: Vec<StepResponse>,
    /// The largest step's settling time up and down, s.
    pub settling_s: [f64; 2],
    /// The loop's width, mA.
    pub hysteresis_ma: f64,
    /// The spread (standard deviation) of one target approached from below, mA.
    pub repeatability_ma: f64,
    /// The creep's time constant, s.
    pub creep_tau_s: f64,
    /// The fraction of a step that arrives by creep.
    pub creep_fraction: f64,
    /// The membrane's natural frequency (Hz) and damping, fitted to the largest up step.
    pub natural_frequency_hz: f64,
    /// Its damping ratio.
    pub damping: f64,
    /// Image scale per mA, px/mA (the conversion every figure went through).
    pub scale_px_per_ma: f64,
    /// The largest step's settling time up and down with the command split by the
    /// zero-vibration shaper of the fitted membrane (`etl_core::physics::shaping`), s;
    /// None when the fit is not underdamped (nothing to cancel).
    pub shaped_settling_s: Option<[f64; 2]>,
}

/// The board's scale in `image`: the mean distance of its corners from their centroid,
/// px. Errors: the board not found.
pub fn board_scale(image: &GrayImage, pattern: Pattern) -> Result<f64> {
    let corners = detect_corners(image, pattern)?.corners_px;
    let n = corners.len().max(1) as f64;
    let c = corners.iter().fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    Ok(corners.iter().map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt()).sum::<f64>() / n)
}

/// The rig under characterisation: the lens, the camera, and the scale-to-mA map.
struct Rig<'a, L: Lens, C: TimedCamera> {
    lens: &'a mut L,
    camera: &'a mut C,
    options: &'a CharacteriseOptions,
    /// (scale at `base_ma`, px per mA).
    map: (f64, f64),
    /// The current last commanded, mA.
    commanded: f64,
}

impl<L: Lens, C: TimedCamera> Rig<'_, L, C> {
    fn set(&mut self, e_ma: f64) -> Result<()> {
        self.commanded = self.lens.set_current_ma(e_ma).map_err(Error::lens)?;
        Ok(())
    }

    /// The board's scale averaged over `level_frames` frames after `rest_s`.
    fn scale_at_rest(&mut self) -> Result<f64> {
        self.camera.wait_s(self.options.rest_s)?;
        let n = self.options.level_frames.max(1);
        let mut sum = 0.0;
        for _ in 0..n {
            sum += board_scale(&self.camera.grab()?.1, self.camera.pattern())?;
        }
        Ok(sum / n as f64)
    }

    /// The current (mA) a scale stands for.
    fn ma_of(&self, scale: f64) -> f64 {
        self.options.base_ma + (scale - self.map.0) / self.map.1
    }

    /// From rest at `from_ma` (`rest_s` after commanding it), commands `to_ma` and frames
    /// the response for `window_s`, the command split by `shaper` when given (its first
    /// fraction at once, the rest after its delay, waited, not framed: a real rig sleeps).
    /// The first sample is a frame just before the command (negative time), the level the
    /// step starts from; the settling time is read to `tolerance_fraction` of the step.
    fn respond(&mut self, from_ma: f64, to_ma: f64, shaper: Option<&ZvShaper>) -> Result<StepResponse> {
        self.set(from_ma)?;
        self.camera.wait_s(self.options.rest_s)?;
        let before = self.camera.grab()?;
        let t0 = self.camera.now_s();
        if let Some(z) = shaper {
            self.set(z.command_ma(self.commanded, to_ma, 0.0))?;
            self.camera.wait_s(z.delay_s)?;
        }
        self.set(to_ma)?;
        let mut frames = vec![(before.0 - t0, before.1)];
        loop {
            let (t, image) = self.camera.grab()?;
            frames.push((t - t0, image));
            if t - t0 >= self.options.window_s {
                break;
            }
        }
        let pattern = self.camera.pattern();
        let samples: Vec<Sample> = frames
            .into_iter()
            .map(|(t, img)| Ok((t, self.ma_of(board_scale(&img, pattern)?))))
            .collect::<Result<_>>()?;
        let step_ma = to_ma - from_ma;
        let level = analysis::final_level(&samples, 0.1);
        let settling_s = analysis::settling_s(&samples, level, self.options.tolerance_fraction * step_ma.abs());
        Ok(StepResponse { step_ma, samples, settling_s })
    }
}

/// The map from scale to mA: two levels approached from below, `base_ma` and `base_ma` +
/// the largest step, each at rest.
fn scale_map<L: Lens, C: TimedCamera>(rig: &mut Rig<'_, L, C>) -> Result<(f64, f64)> {
    let o = rig.options;
    let top = o.base_ma + o.largest_step_ma();
    rig.set(o.base_ma - o.hysteresis_approach_ma)?;
    rig.camera.wait_s(o.rest_s)?;
    rig.set(o.base_ma)?;
    let low = rig.scale_at_rest()?;
    rig.set(top)?;
    let high = rig.scale_at_rest()?;
    let per_ma = (high - low) / (top - o.base_ma);
    if !(per_ma.abs() > 1e-9) {
        return Err(Error::invalid(
            "camera",
            "the board's scale does not change with the current: the camera cannot see the lens's power",
        ));
    }
    Ok((low, per_ma))
}

/// Every step up from `base_ma` and back down, with its settling time.
fn step_responses<L: Lens, C: TimedCamera>(rig: &mut Rig<'_, L, C>) -> Result<Vec<StepResponse>> {
    let o = rig.options;
    let mut out = vec![];
    for &step in &o.steps_ma {
        out.push(rig.respond(o.base_ma, o.base_ma + step, None)?);
        out.push(rig.respond(o.base_ma + step, o.base_ma, None)?);
    }
    Ok(out)
}

/// The loop's width and the repeatability: one target approached `repeats` times from
/// below and from above.
fn hysteresis<L: Lens, C: TimedCamera>(rig: &mut Rig<'_, L, C>) -> Result<(f64, f64)> {
    let o = rig.options;
    let target = o.base_ma + o.hysteresis_approach_ma;
    let (mut below, mut above) = (vec![], vec![]);
    for _ in 0..o.repeats.max(2) {
        for (side, out) in [(-1.0, &mut below), (1.0, &mut above)] {
            rig.set(target + side * o.hysteresis_approach_ma)?;
            // Long enough for the ringing; short, so that the lens warms alike from both
            // sides (the creep of this move has the rest below to die).
            rig.camera.wait_s(10.0 * o.window_s)?;
            rig.set(target)?;
            let s = rig.scale_at_rest()?;
            out.push(rig.ma_of(s));
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mb, ma) = (mean(&below), mean(&above));
    let spread = (below.iter().map(|x| (x - mb).powi(2)).sum::<f64>() / (below.len() - 1) as f64).sqrt();
    Ok((ma - mb, spread))
}

/// The creep after the largest step up: (tau s, fraction), fitted past the ringing
/// (from 10 window lengths on).
fn creep<L: Lens, C: TimedCamera>(rig: &mut Rig<'_, L, C>) -> Result<(f64, f64)> {
    let o = rig.options;
    let step = o.largest_step_ma();
    rig.set(o.base_ma)?;
    rig.camera.wait_s(o.rest_s)?;
    rig.set(o.base_ma + step)?;
    let t0 = rig.camera.now_s();
    let start = 10.0 * o.window_s;
    rig.camera.wait_s(start)?;
    let n = o.creep_frames.max(3);
    let dt = (o.creep_s - start).max(0.0) / n as f64;
    let mut samples = vec![];
    for _ in 0..n {
        let (t, image) = rig.camera.grab()?;
        samples.push((t - t0, rig.ma_of(board_scale(&image, rig.camera.pattern())?)));
        rig.camera.wait_s(dt)?;
    }
    let fit = analysis::exponential_fit(&samples, [0.01, 10.0 * o.creep_s.max(0.01)]);
    let (_, b, _, tau) =
        fit.ok_or_else(|| Error::invalid("creep", "the creep record does not determine an exponential"))?;
    Ok((tau, -b / step))
}

/// Checks the options: finite, positive where they must be, steps that leave room.
fn check(o: &CharacteriseOptions) -> Result<()> {
    let positive = [
        ("window_s", o.window_s),
        ("tolerance_fraction", o.tolerance_fraction),
        ("rest_s", o.rest_s),
        ("hysteresis_approach_ma", o.hysteresis_approach_ma),
        ("creep_s", o.creep_s),
    ];
    if let Some((what, x)) = positive.into_iter().find(|(_, x)| !(x.is_finite() && *x > 0.0)) {
        return Err(Error::invalid_value(what, x, format!("{what} = {x} must be finite and > 0")));
    }
    if o.steps_ma.is_empty() || o.steps_ma.iter().any(|s| !(s.is_finite() && *s > 0.0)) || !o.base_ma.is_finite() {
        return Err(Error::invalid("steps_ma", "at least one step, each finite and > 0, from a finite base_ma"));
    }
    if 10.0 * o.window_s >= o.creep_s {
        return Err(Error::invalid_value("creep_s", o.creep_s, "creep_s must exceed ten step windows"));
    }
    Ok(())
}

/// Characterises the lens through `camera` (module docs). Errors: bad options, a board
/// not found, a lens error, a scale that does not follow the current.
pub fn characterise<L: Lens, C: TimedCamera>(
    lens: &mut L,
    camera: &mut C,
    options: &CharacteriseOptions,
    progress: &dyn Progress,
) -> Result<Characterisation> {
    check(options)?;
    progress.start(4, "characterise");
    let mut rig = Rig { lens, camera, options, map: (0.0, 1.0), commanded: f64::NAN };
    rig.map = scale_map(&mut rig)?;
    progress.advance(1);
    let steps = step_responses(&mut rig)?;
    progress.advance(1);
    let (hysteresis_ma, repeatability_ma) = hysteresis(&mut rig)?;
    progress.advance(1);
    let (creep_tau_s, creep_fraction) = creep(&mut rig)?;
    progress.finish();
    let largest = |up: bool| {
        steps.iter().filter(|s| (s.step_ma > 0.0) == up).max_by(|a, b| a.step_ma.abs().total_cmp(&b.step_ma.abs()))
    };
    let (up, down) = (largest(true), largest(false));
    let (natural_frequency_hz, damping) = up
        .and_then(|s| analysis::second_order_fit(&s.samples, s.samples[0].1, analysis::final_level(&s.samples, 0.1)))
        .ok_or_else(|| Error::invalid("steps_ma", "the step responses do not determine a second-order fit"))?;
    let fitted = LensDynamics { natural_frequency_hz, damping, ..LensDynamics::PUBLISHED };
    let shaped = ZvShaper::of(&fitted).map(|z| shaped_steps(&mut rig, &z)).transpose()?;
    Ok(Characterisation {
        shaped_settling_s: shaped,
        settling_s: [up.map_or(0.0, |s| s.settling_s), down.map_or(0.0, |s| s.settling_s)],
        steps,
        hysteresis_ma,
        repeatability_ma,
        creep_tau_s,
        creep_fraction,
        natural_frequency_hz,
        damping,
        scale_px_per_ma: rig.map.1,
    })
}

/// The largest step up and back down, each shaped by `shaper`: their settling times, s,
/// by the same definition as the plain steps'.
fn shaped_steps<L: Lens, C: TimedCamera>(rig: &mut Rig<'_, L, C>, shaper: &ZvShaper) -> Result<[f64; 2]> {
    let (base, top) = (rig.options.base_ma, rig.options.base_ma + rig.options.largest_step_ma());
    Ok([rig.respond(base, top, Some(shaper))?.settling_s, rig.respond(top, base, Some(shaper))?.settling_s])
}
