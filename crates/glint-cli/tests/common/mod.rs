//! Helpers shared by the CLI's test files: running the binary as a user would
//! and reading what it said.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Run glint from the project root, as a user would (scenes there may then use
/// `../assets`: the current directory is one of their asset roots).
pub fn glint(args: &[&str]) -> Output {
    glint_with(args, &[])
}

/// [`glint`] with the environment variables `vars` set too.
pub fn glint_with(args: &[&str], vars: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(args)
        .current_dir(repo(""))
        .env("NODEVICE_SELECT", "1")
        .envs(vars.iter().copied())
        .output()
        .expect("run glint")
}

pub fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Lines glint itself printed (Mesa and wgpu log lines filtered out).
pub fn error_lines(o: &Output) -> Vec<String> {
    stderr(o).lines().filter(|l| l.starts_with("error:")).map(str::to_owned).collect()
}

/// Run glint with its standard output on `/dev/full`, where every write fails
/// with ENOSPC (`None` where the device is missing).
pub fn glint_to_full_stdout(args: &[&str]) -> Option<Output> {
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").ok()?;
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(args)
        .env("NODEVICE_SELECT", "1")
        .stdout(full)
        .output()
        .expect("run glint");
    Some(out)
}

/// No adapter (exit 2) skips a GPU test unless CI requires one.
pub fn no_adapter(out: &Output) -> bool {
    let skip = out.status.code() == Some(2) && std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() != Ok("1");
    if skip {
        eprintln!("skipping: no GPU adapter ({})", stderr(out));
    }
    skip
}

/// A failed write is exit 1 with one error line naming what could not be
/// written, never a panic.
pub fn assert_write_failed(out: &Output, what: &str) {
    let text = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(!text.contains("panicked"), "{text}");
    let errors = error_lines(out);
    assert_eq!(errors.len(), 1, "{text}");
    assert!(errors[0].starts_with(&format!("error: {what}: cannot write: ")), "{errors:?}");
}
