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
