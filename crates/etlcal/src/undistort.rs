//! `etlcal undistort IMAGE... --calibration F (--e-in MA --t C | --e-com MA) --out DIR
//! [--json]`: each image, taken at the driver current E_in and lens temperature T (or at a
//! known compensated current), undistorted at the compensated current E_com (the
//! calibration's thermal surface, or `--e-com`) as the camera K(E_com)
//! without distortion sees it, written into DIR under its own file name and in its own
//! format (PNG, JPEG, TIFF; 8- or 16-bit grey or RGB, 32-bit float RGB).
//!
//! Every image is checked (readable header, the calibration's size, a supported pixel
//! type, no two outputs with one name, no output over its input) before anything is
//! written; the outputs are written as one set (`etl_formats::output::write_file_set`): a
//! kill, a full disk or an unreadable image leaves every earlier output as it was, or every
//! new one, never a mix of the two runs.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use crate::setting::SettingArgs;
use etl_core::model::CameraModel;
use etl_formats::output::write_file_set;
use etl_formats::{write_atomic, Error, Result};
use etl_image::undistort::{undistort_image, OutputCamera, Sample, SourceImage};
use image::{ColorType, DynamicImage, ImageBuffer, ImageFormat, Pixel};
use serde_json::json;

use super::print_json;

/// Arguments of `etlcal undistort`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The images to undistort (taken at the setting: --e-in and --t, or --e-com).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// The calibration and the setting the images were taken at.
    #[command(flatten)]
    pub setting: SettingArgs,
    /// Output directory (created if missing); each output keeps its input's file name.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// One image to undistort: where it is, where it goes, its format.
struct Job {
    input: PathBuf,
    output: PathBuf,
    format: ImageFormat,
}

/// Checks one input from its header only: an image, of the calibration's size and a pixel
/// type `undistort` writes back; its output in `out_dir` is not the input itself.
fn check_input(input: &Path, out_dir: &Path, size: [u32; 2]) -> Result<Job> {
    let bad = |message: String| Error::Image { path: input.to_owned(), message };
    let io = |source| Error::Io { path: input.to_owned(), source };
    etl_formats::output::check_input(input)?; // a FIFO would block the open below
    let reader = image::ImageReader::open(input).map_err(io)?.with_guessed_format().map_err(io)?;
    let format = reader.format().ok_or_else(|| bad("not an image (PNG, JPEG or TIFF)".into()))?;
    let decoder = reader.into_decoder().map_err(|e| bad(e.to_string()))?;
    let (w, h) = image::ImageDecoder::dimensions(&decoder);
    if [w, h] != size {
        return Err(bad(format!("the image is {w} x {h} px, the calibration is for {} x {}", size[0], size[1])));
    }
    let color = image::ImageDecoder::color_type(&decoder);
    if !matches!(color, ColorType::L8 | ColorType::L16 | ColorType::Rgb8 | ColorType::Rgb16 | ColorType::Rgb32F) {
        return Err(bad(format!("pixel type {color:?} is not supported (grey or RGB of 8 or 16 bits, RGB float)")));
    }
    let name = input.file_name().ok_or_else(|| bad("has no file name".into()))?;
    let output = out_dir.join(name);
    let same = match (std::fs::canonicalize(input), std::fs::canonicalize(&output)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same {
        return Err(bad(format!("--out {} would overwrite the input; choose another directory", out_dir.display())));
    }
    Ok(Job { input: input.to_owned(), output, format })
}

/// The undistorted copy of an image buffer of any supported sample type.
fn undistort_buffer<P: Pixel<Subpixel = T>, T: Sample + Send + Sync + image::Primitive>(
    img: &ImageBuffer<P, Vec<T>>,
    model: &CameraModel,
    e_com_ma: f64,
) -> Result<ImageBuffer<P, Vec<T>>> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let (k, d) = (model.intrinsics(e_com_ma)?, model.distortion(e_com_ma)?);
    let out = OutputCamera::of_intrinsics(&k, w, h)?;
    let src = SourceImage::new(img.as_raw(), w, h, P::CHANNEL_COUNT as usize)?;
    let pixels = undistort_image(&k, &d, &out, &src, T::from_f32(0.0))?;
    ImageBuffer::from_raw(img.width(), img.height(), pixels)
        .ok_or_else(|| Error::invalid("image", "undistorted image has an inconsistent size"))
}

/// Reads, undistorts and encodes one image, and writes it to `to` (the set's temporary
/// for `job.output`).
fn undistort_file(job: &Job, model: &CameraModel, e_com_ma: f64, to: &Path) -> Result<()> {
    let img = etl_image::read_image(&job.input)?;
    let out: DynamicImage = match &img {
        DynamicImage::ImageLuma8(b) => undistort_buffer(b, model, e_com_ma)?.into(),
        DynamicImage::ImageLuma16(b) => undistort_buffer(b, model, e_com_ma)?.into(),
        DynamicImage::ImageRgb8(b) => undistort_buffer(b, model, e_com_ma)?.into(),
        DynamicImage::ImageRgb16(b) => undistort_buffer(b, model, e_com_ma)?.into(),
        DynamicImage::ImageRgb32F(b) => undistort_buffer(b, model, e_com_ma)?.into(),
        other => {
            return Err(Error::Image {
                path: job.input.clone(),
                message: format!("pixel type {:?} is not supported", other.color()),
            })
        }
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    out.write_to(&mut bytes, job.format).map_err(|e| Error::Output {
        path: job.output.clone(),
        source: std::io::Error::other(format!("cannot encode: {e}")),
    })?;
    write_atomic(to, bytes.get_ref())
}

/// Runs `etlcal undistort`.
pub fn run(args: Args) -> Result<()> {
    let (cal, camera) = args.setting.camera()?;
    let e_com = camera.setting_value();
    let mut names = HashSet::new();
    let mut jobs = Vec::with_capacity(args.images.len());
    for input in &args.images {
        let job = check_input(input, &args.out, cal.image_size)?;
        if !names.insert(job.output.clone()) {
            return Err(Error::invalid_value(
                "IMAGE",
                input,
                format!("two images would be written to {}; give images of distinct file names", job.output.display()),
            ));
        }
        jobs.push(job);
    }
    crate::output::create_dir(&args.out)?;
    let model = cal.model()?;
    let outputs: Vec<&Path> = jobs.iter().map(|j| j.output.as_path()).collect();
    write_file_set(&outputs, |temps| {
        jobs.iter().zip(temps).try_for_each(|(job, tmp)| undistort_file(job, &model, e_com, tmp))
    })?;
    if !args.json {
        for job in &jobs {
            outln!("{} -> {}", job.input.display(), job.output.display());
        }
    }
    if args.json {
        let images: Vec<_> = jobs.iter().map(|j| json!({"input": j.input, "output": j.output})).collect();
        print_json(&json!({"e_com_ma": e_com, "extrapolated": camera.extrapolated(), "images": images}));
    } else {
        outln!("E_com {e_com:.3} mA: {} image(s) undistorted into {}", jobs.len(), args.out.display());
    }
    Ok(())
}
