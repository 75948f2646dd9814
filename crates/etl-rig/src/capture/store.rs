//! The capture's output: `DIR/dataset.json` (`etlcal.dataset/1`) with the images in
//! `DIR/offstate/offNN.png` and `DIR/views/viewNN.png`, named by their index in the plan.
//!
//! Always whole on disk: an image is written atomically (a temporary file in its folder,
//! synced, renamed over the name), and only then the dataset that lists it, atomically too.
//! A kill leaves at worst an image the dataset does not list yet (taken again on resume)
//! or a temporary file of a dead process (removed on resume).
//!
//! Resuming ([`Store::open`] on a folder with a dataset): the dataset must be of the same
//! plan (its boards, and each view's stage position and current within
//! [`RESUME_TOLERANCE_MM`] and [`RESUME_TOLERANCE_MA`] of the plan's); every image it
//! lists is decoded and its size checked. The first image that is missing or does not
//! decode, and every view of its kind after it, are dropped and taken again.
//!
//! A dataset whose ETL views have not begun (the lens-off views come first) holds no
//! `views` yet: `etlcal calibrate` refuses it until the capture has taken one.

use std::path::{Path, PathBuf};

use etl_formats::dataset::{Dataset, DatasetView, OffstateImage};
use etl_formats::plan::{Focus, Plan};
use etl_formats::{read_json, write_atomic, write_json};
use serde_json::json;

use crate::camera::Pixels;
use crate::error::{Error, Result};

/// How far a resumed view's recorded stage position may be from the plan's, mm (a
/// stage's read-back differs from the command by its resolution).
pub const RESUME_TOLERANCE_MM: f64 = 0.05;
/// How far a resumed view's recorded current may be from the plan's, mA (the driver
/// quantises the current, 0.07 mA steps on a Lens Driver 4).
pub const RESUME_TOLERANCE_MA: f64 = 0.5;

/// The dataset file's name in the output folder.
pub const DATASET_FILE: &str = "dataset.json";

/// The relative path of lens-off view `k`.
pub fn offstate_image(k: usize) -> PathBuf {
    PathBuf::from(format!("offstate/off{k:02}.png"))
}

/// The relative path of ETL view `k`.
pub fn view_image(k: usize) -> PathBuf {
    PathBuf::from(format!("views/view{k:02}.png"))
}

/// The output folder and its dataset.
pub struct Store {
    dir: PathBuf,
    /// The dataset as on disk.
    pub dataset: Dataset,
    /// Views kept from an earlier run: (lens-off, ETL).
    pub resumed: (usize, usize),
}

impl Store {
    /// Opens `dir` for `plan` with images of `image_size`: resumes its dataset (module
    /// docs) or starts an empty one (nothing is written until the first view).
    pub fn open(dir: &Path, plan: &Plan, image_size: [u32; 2]) -> Result<Store> {
        let path = dir.join(DATASET_FILE);
        let mut dataset = if path.exists() {
            let d: Dataset = read_json(&path, etl_formats::dataset::FORMAT)?;
            check_same_plan(&d, plan, image_size, &path)?;
            d
        } else {
            let mut d = Dataset::new(image_size, plan.board);
            d.offstate_board = plan.offstate_views.map(|_| plan.offstate_board());
            d
        };
        let off = verified_prefix(dir, dataset.offstate_views.iter().map(|v| &v.image), offstate_image, image_size);
        dataset.offstate_views.truncate(off);
        let views = verified_prefix(dir, dataset.views.iter().map(|v| &v.image), view_image, image_size);
        dataset.views.truncate(views);
        for sub in ["offstate", "views"] {
            let d = dir.join(sub);
            if d.is_dir() {
                remove_dead_temps(&d);
            }
        }
        if dir.is_dir() {
            remove_dead_temps(dir);
        }
        Ok(Store { dir: dir.to_owned(), dataset, resumed: (off, views) })
    }

    /// Writes `pixels` as the image `rel` atomically (its folder created if missing).
    pub fn write_image(&self, rel: &Path, pixels: &Pixels) -> Result<()> {
        let path = self.dir.join(rel);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|source| etl_formats::Error::Io { path: parent.to_owned(), source })?;
        }
        write_atomic(&path, &pixels.to_png()?)?;
        Ok(())
    }

    /// Appends a lens-off view and saves the dataset.
    pub fn push_offstate(&mut self, image: PathBuf) -> Result<()> {
        let entry: OffstateImage = from_json(json!({ "image": image }))?;
        self.dataset.offstate_views.push(entry);
        self.save()
    }

    /// Appends an ETL view and saves the dataset.
    pub fn push_view(&mut self, image: PathBuf, e_in_ma: f64, temperature_c: f64, z_w_mm: f64) -> Result<()> {
        let entry: DatasetView =
            from_json(json!({"image": image, "e_in_ma": e_in_ma, "temperature_c": temperature_c, "z_w_mm": z_w_mm}))?;
        self.dataset.views.push(entry);
        self.save()
    }

    /// Writes the dataset atomically (checked first once it has an ETL view).
    fn save(&self) -> Result<()> {
        std::fs::create_dir_all(&self.dir)
            .map_err(|source| etl_formats::Error::Io { path: self.dir.clone(), source })?;
        let path = self.dir.join(DATASET_FILE);
        if self.dataset.views.is_empty() {
            write_json(&path, &self.dataset)?;
        } else {
            self.dataset.save(&path)?;
        }
        Ok(())
    }
}

/// A dataset entry from its JSON (so that keys added to the format later keep their
/// defaults here).
fn from_json<T: serde::de::DeserializeOwned>(value: serde_json::Value) -> Result<T> {
    serde_json::from_value(value)
        .map_err(|e| Error::Formats(etl_formats::Error::invalid("dataset", format!("cannot record the view: {e}"))))
}

/// Refuses a dataset of another plan or camera (named by its first difference).
fn check_same_plan(d: &Dataset, plan: &Plan, image_size: [u32; 2], path: &Path) -> Result<()> {
    let other = |what: String| {
        Error::Formats(etl_formats::Error::invalid(
            "--out",
            format!("{}: {what}: it is another capture's; choose another --out", path.display()),
        ))
    };
    if d.image_size != image_size {
        return Err(other(format!("its images are {:?} px, the camera's {image_size:?} px", d.image_size)));
    }
    if d.board != plan.board {
        return Err(other("its board is not the plan's".into()));
    }
    if !d.offstate_views.is_empty() && d.offstate_board() != plan.offstate_board() {
        return Err(other("its lens-off board is not the plan's".into()));
    }
    if d.offstate_views.len() > plan.offstate_count() || d.views.len() > plan.stage_mm.len() {
        return Err(other("it holds more views than the plan asks for".into()));
    }
    for (k, v) in d.views.iter().enumerate() {
        let z = plan.stage_mm[k];
        if (v.z_w_mm - z).abs() > RESUME_TOLERANCE_MM {
            return Err(other(format!("views[{k}] is at {} mm, the plan's stage_mm[{k}] {z} mm", v.z_w_mm)));
        }
        if let (Focus::Current, Some(c)) = (plan.focus, &plan.currents_ma) {
            if (v.e_in_ma - c[k]).abs() > RESUME_TOLERANCE_MA {
                return Err(other(format!(
                    "views[{k}] is at {} mA, the plan's currents_ma[{k}] {} mA",
                    v.e_in_ma, c[k]
                )));
            }
        }
    }
    Ok(())
}

/// How many of `images` are, in order, the expected names with decodable images of
/// `image_size`.
fn verified_prefix<'a>(
    dir: &Path,
    images: impl Iterator<Item = &'a PathBuf>,
    expected: fn(usize) -> PathBuf,
    image_size: [u32; 2],
) -> usize {
    let mut n = 0;
    for (k, image) in images.enumerate() {
        let good = *image == expected(k)
            && etl_image::read_image(&dir.join(image)).is_ok_and(|i| [i.width(), i.height()] == image_size);
        if !good {
            break;
        }
        n += 1;
    }
    n
}

/// Removes the temporary files (`.NAME.tmpPID`) that killed processes left in `dir`.
fn remove_dead_temps(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some((stem, _pid)) = name.strip_prefix('.').and_then(|n| n.rsplit_once(".tmp")) else { continue };
        etl_formats::output::remove_stale_temps(dir, std::ffi::OsStr::new(stem));
    }
}
