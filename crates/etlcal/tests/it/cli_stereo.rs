//! `etlcal stereo` on the real images of fixtures/wide (SOURCE.md there): the same
//! camera's images given as both cameras of a pair (R = I, T = 0 exactly), each camera's
//! object exactly `etlcal zhang --json`'s, and the one-line refusals of bad input (exit 1,
//! nothing on stdout).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

/// The first `n` images of a fixtures/wide set, as strings.
fn set(name: &str, n: usize) -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/wide").join(name);
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    v.sort();
    v.into_iter().take(n).map(|p| p.display().to_string()).collect()
}

/// `etlcal stereo LEFT... --right RIGHT... --pattern 11x8 --square 1 EXTRA...`.
fn stereo(left: &[String], right: &[String], extra: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_etlcal"));
    cmd.arg("stereo").args(left).arg("--right").args(right).args(["--pattern", "11x8", "--square", "1"]).args(extra);
    cmd.output().unwrap()
}

fn json(out: &Output) -> Value {
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

/// One camera's images as both cameras: R = I and T = 0 to rounding in both modes, and
/// (fixed intrinsics) each camera's object is `etlcal zhang --json`'s on the same images,
/// key for key and number for number; in the joint mode the same keys.
#[test]
fn stereo_same_images_give_identity_and_zhang_objects() {
    let images = set("stereo752_left", 6);
    let mut zhang = Command::new(env!("CARGO_BIN_EXE_etlcal"));
    zhang.arg("zhang").args(&images).args(["--pattern", "11x8", "--square", "1", "--model", "opencv", "--json"]);
    let z = json(&zhang.output().unwrap());
    for mode in ["fixed", "joint"] {
        let v = json(&stereo(&images, &images, &["--model", "opencv", "--intrinsics", mode, "--json"]));
        for key in ["left", "right", "rotation_rodrigues", "translation_mm", "rms_px", "views_used"] {
            assert!(v.get(key).is_some(), "{mode}: {key} missing");
        }
        let rt: Vec<f64> = ["rotation_rodrigues", "translation_mm"]
            .iter()
            .flat_map(|k| v[k].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect::<Vec<_>>())
            .collect();
        assert!(rt.iter().all(|x| x.abs() < 1e-9), "{mode}: {rt:?}");
        assert_eq!((v["views_used"].as_u64(), v["intrinsics"].as_str()), (Some(6), Some(mode)));
        for side in ["left", "right"] {
            let keys = |o: &Value| o.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
            assert_eq!(keys(&v[side]), keys(&z), "{mode} {side}");
            if mode == "fixed" {
                assert_eq!(v[side], z, "{side}");
            }
        }
    }
}

/// The paper's model: the keys of `etlcal zhang --json` without `--model`.
#[test]
fn stereo_paper_model_objects_have_zhangs_keys() {
    let images = set("stereo752_left", 4);
    let mut zhang = Command::new(env!("CARGO_BIN_EXE_etlcal"));
    zhang.arg("zhang").args(&images).args(["--pattern", "11x8", "--square", "1", "--json"]);
    let z = json(&zhang.output().unwrap());
    let v = json(&stereo(&images, &images, &["--model", "paper", "--json"]));
    assert_eq!(v["left"], z);
    assert_eq!(v["model"], "paper");
}

/// Exit 1, one line on stderr containing `what`, nothing on stdout.
fn refused(out: Output, what: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(out.stdout.is_empty());
    let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("etlcal: warning")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].starts_with("etlcal: error: ") && lines[0].contains(what), "{err}");
}

#[test]
fn stereo_refuses_unequal_image_counts() {
    let s = set("stereo752_left", 4);
    refused(
        stereo(&s, &s[..3], &["--model", "opencv"]),
        "4 LEFT images but 3 --right images: give one right image per left image",
    );
}

/// Images of another board (fixtures/wide/opencv_left, 9x6) stand for views in which the
/// 11x8 board is not found.
#[test]
fn stereo_refuses_pairs_never_seen_by_both_cameras() {
    let (s, o) = (set("stereo752_left", 6), set("opencv_left", 3));
    let left = [&s[..3], &o[..]].concat();
    let right = [&o[..], &s[3..]].concat();
    refused(stereo(&left, &right, &["--model", "opencv"]), "both cameras see the board in 0 of 6 pairs");
}

#[test]
fn stereo_refuses_too_few_views() {
    let (s, o) = (set("stereo752_left", 4), set("opencv_left", 2));
    refused(
        stereo(&s[..2], &s[..2], &["--model", "opencv"]),
        "the left camera sees the board in 2 of 2 pairs; each camera needs at least 3 views",
    );
    // Three views each, two of them pairs: the intrinsics held need one pair, the joint
    // mode three.
    let left = vec![s[0].clone(), s[1].clone(), s[2].clone(), o[0].clone()];
    let right = vec![s[0].clone(), s[1].clone(), o[1].clone(), s[3].clone()];
    let v = json(&stereo(&left, &right, &["--model", "opencv", "--json"]));
    assert_eq!(v["pairs_used"], serde_json::json!([0, 1]));
    assert_eq!(v["left"]["views_used"], 3);
    refused(
        stereo(&left, &right, &["--model", "opencv", "--intrinsics", "joint"]),
        "both cameras see the board in 2 of 4 pairs; the joint mode needs at least 3",
    );
}

#[test]
fn stereo_refuses_a_camera_that_never_sees_the_board() {
    let (s, o) = (set("stereo752_left", 3), set("opencv_left", 3));
    refused(stereo(&s, &o, &["--model", "opencv"]), "in none of the 3 images of the right camera");
}

#[test]
fn stereo_refuses_opencv_flags_with_the_paper_model() {
    let s = set("stereo752_left", 3);
    refused(stereo(&s, &s, &["--model", "paper", "--fix-k3"]), "--fix-k3");
}

#[test]
fn stereo_refuses_opencv_yaml_with_the_paper_model_and_writes_nothing() {
    let s = set("stereo752_left", 3);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pair.yml");
    refused(
        stereo(&s, &s, &["--model", "paper", "--opencv-yaml", out.to_str().unwrap()]),
        "--opencv-yaml needs --model opencv",
    );
    assert!(!out.exists());
}
