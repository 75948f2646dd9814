//! Helpers every command-line test shares.

use std::process::{Command, Output};

/// Runs the `etlcal` binary that `cargo test` built, with `args`.
pub fn etlcal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_etlcal")).args(args).output().expect("run etlcal")
}

/// Runs `etlcal` with `args`: (exit code, or -1 if killed by a signal; stdout; stderr).
pub fn etlcal_run(args: &[&str]) -> (i32, String, String) {
    let out = etlcal(args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Renders the 9 x 7 pattern at E_com `e_com` (mA, as given on the command line) into `a`,
/// in focus, and into `b`, 2 mm nearer: the two images of a measured stage move. Returns
/// the stage position of `a`, mm.
pub fn render_move_pair(a: &str, b: &str, e_com: &str) -> f64 {
    let render = |out: &str, seed: &str, extra: &[&str]| -> serde_json::Value {
        let mut args = vec!["render", "--out", out, "--e-com", e_com, "--pattern", "9x7", "--seed", seed, "--json"];
        args.extend_from_slice(extra);
        let (code, stdout, stderr) = etlcal_run(&args);
        assert_eq!(code, 0, "{args:?}: {stderr}");
        serde_json::from_str(&stdout).unwrap()
    };
    let z_a = render(a, "1", &[])["z_w_mm"].as_f64().unwrap();
    render(b, "2", &["--z-mm", &format!("{}", z_a - 2.0)]);
    z_a
}

/// Every file under `dir` (relative path -> bytes); also the proof that no temporary is left.
pub fn tree(dir: &std::path::Path) -> std::collections::BTreeMap<std::path::PathBuf, Vec<u8>> {
    use std::{
        collections::BTreeMap,
        path::{Path, PathBuf},
    };
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(p.strip_prefix(root).unwrap().to_owned(), std::fs::read(&p).unwrap_or_default());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}
