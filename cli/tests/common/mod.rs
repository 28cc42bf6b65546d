//! The command-line test harness: running a binary of the workspace (`particles` here, the
//! `validation` binary in `validation/tests/cli_errors.rs`, which includes this file through
//! `#[path]`) with arguments, a working directory and environment variables; waiting for it
//! with a bound that only catches a hang; fresh temporary directories; the fixtures of the
//! command-line error snapshots; and what the tests compare (stderr with the directory
//! replaced, the `error:` lines, every file under a directory).
//!
//! A test file uses it with `mod common;`. Each file uses a part of it, hence no dead-code
//! warnings. The insta assertions stay in the test files: insta names a snapshot file after
//! the module that asserts (`cli_errors__<case>.snap`), which must stay the test file's.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

/// How long a child process may run, or a condition take to come true, before a test calls
/// it a hang. Only a hang: a test never asserts that something was fast (a loaded machine
/// may be many times slower than a developer's).
pub const HANG: Duration = Duration::from_secs(600);

/// The `particles` binary cargo built for the tests of `particles-cli` (not available, and
/// not called, where this file is included by another package).
pub fn particles_bin() -> &'static str {
    match option_env!("CARGO_BIN_EXE_particles") {
        Some(bin) => bin,
        None => panic!("the particles binary is built only for the tests of particles-cli"),
    }
}

/// `bin ARGS` to run in `cwd` with `envs` set, colour off (`NO_COLOR`, no
/// `CLICOLOR_FORCE`), stdin empty, stdout and stderr piped; change what a test needs
/// before `output()` or `spawn()`.
pub fn command<I, S>(bin: &str, args: I, cwd: &Path, envs: &[(&str, &str)]) -> Command
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    let mut c = Command::new(bin);
    c.args(args)
        .current_dir(cwd)
        .env("NO_COLOR", "1")
        .env_remove("CLICOLOR_FORCE")
        .envs(envs.iter().copied())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

/// [`command`] for `particles`.
pub fn particles<I, S>(args: I, cwd: &Path, envs: &[(&str, &str)]) -> Command
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    command(particles_bin(), args, cwd, envs)
}

/// Runs `bin ARGS` in `cwd` with `envs` ([`command`]) to its end (bounded by [`HANG`]);
/// its exit status, stdout and stderr.
pub fn run_bin<I, S>(bin: &str, args: I, cwd: &Path, envs: &[(&str, &str)]) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    let mut c = command(bin, args, cwd, envs);
    let what = format!("{c:?}");
    wait_bounded(c.spawn().unwrap(), HANG, &what)
}

/// Runs `particles ARGS` in `cwd` with `envs` ([`run_bin`]); e.g.
/// `run_particles(["run", "scene.toml", "--quick", "--frames", "2", "--out", "out"], &dir, &[])`.
pub fn run_particles<I, S>(args: I, cwd: &Path, envs: &[(&str, &str)]) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    run_bin(particles_bin(), args, cwd, envs)
}

/// Runs `particles ARGS` in `cwd` and asserts that it succeeded (showing its stderr if
/// not); its output.
pub fn particles_ok<I, S>(args: I, cwd: &Path) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    let args: Vec<S> = args.into_iter().collect();
    let shown: Vec<String> = args
        .iter()
        .map(|a| a.as_ref().to_string_lossy().into_owned())
        .collect();
    let out = run_particles(&args, cwd, &[]);
    assert!(
        out.status.success(),
        "particles {shown:?} failed ({}):\n{}",
        out.status,
        stderr_of(&out)
    );
    out
}

/// Waits for `child` to end, reading its piped stdout and stderr meanwhile (so that a full
/// pipe cannot stall it); after `limit`, kills it and panics naming `what` (a hang).
pub fn wait_bounded(mut child: Child, limit: Duration, what: &str) -> Output {
    let stdout = drain(child.stdout.take());
    let stderr = drain(child.stderr.take());
    let status = wait_status(&mut child, limit, what);
    Output {
        status,
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
    }
}

/// Reads `pipe` (if any) to its end in a thread; what it held.
fn drain<R: Read + Send + 'static>(pipe: Option<R>) -> std::thread::JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut bytes = Vec::new();
        if let Some(mut p) = pipe {
            p.read_to_end(&mut bytes).ok();
        }
        bytes
    })
}

/// The exit status of `child`, waited for at most `limit` (then it is killed and the test
/// panics naming `what`).
fn wait_status(child: &mut Child, limit: Duration, what: &str) -> ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if start.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            panic!("{what}: still running after {limit:?} (a hang; killed)");
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Polls `ready` until it is true while `child` runs: the handshake before a test signals
/// or kills a child at a given point of its work (something it wrote, never a delay).
/// Panics, naming `what`, if the child ends first (with its stderr, if piped) or nothing
/// happens within [`HANG`] (the child is then killed).
pub fn wait_until(child: &mut Child, what: &str, mut ready: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ready() {
        if let Some(status) = child.try_wait().unwrap() {
            let mut stderr = String::new();
            if let Some(e) = child.stderr.as_mut() {
                e.read_to_string(&mut stderr).ok();
            }
            panic!("{what}: the process ended ({status}) before it happened; stderr:\n{stderr}");
        }
        if start.elapsed() > HANG {
            child.kill().ok();
            child.wait().ok();
            panic!("{what}: not after {HANG:?} (a hang; killed)");
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// The exit code, or -1 when the process was ended by a signal.
pub fn code_of(out: &Output) -> i32 {
    out.status.code().unwrap_or(-1)
}

/// Stderr as text.
pub fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Stdout as text.
pub fn stdout_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Stderr with `dir` written `placeholder`, without trailing white space (what the error
/// snapshots hold).
pub fn stderr_in(out: &Output, dir: &Path, placeholder: &str) -> String {
    stderr_of(out)
        .replace(&dir.display().to_string(), placeholder)
        .trim_end()
        .to_string()
}

/// The `error:` lines of stderr, with `dir` written `placeholder`.
pub fn error_lines(out: &Output, dir: &Path, placeholder: &str) -> String {
    stderr_of(out)
        .lines()
        .filter(|l| l.starts_with("error:"))
        .collect::<Vec<_>>()
        .join("\n")
        .replace(&dir.display().to_string(), placeholder)
}

/// A fresh, empty directory `<temp>/<prefix>-<name>-<process id>` (one a test binary and
/// case; whatever an earlier run left there is removed).
pub fn temp_dir(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("{prefix}-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Every file under `dir`, recursively (name relative to `dir`, bytes), sorted by name.
pub fn files_under(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.push((name, std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// The valid scene of the command-line error cases (`good.toml`): small and quick, no VTK.
pub const GOOD_SCENE: &str = r#"
name = "good"
[simulation]
particle_spacing = 0.05
duration = 0.1
frame_dt = 0.02
[solver]
kind = "pbf"
substeps = 2
iterations = 2
[tank]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.2, 0.2, 0.2]
[output]
vtk = false
"#;

/// A fresh directory ([`temp_dir`]) holding what the command-line error cases refer to:
/// the valid scene `good.toml` ([`GOOD_SCENE`]), a malformed one `bad.toml` (its frame
/// step longer than its duration) and a plain file `notes.txt`.
pub fn error_case_dir(prefix: &str, case: &str) -> PathBuf {
    let dir = temp_dir(prefix, case);
    std::fs::write(dir.join("good.toml"), GOOD_SCENE).unwrap();
    std::fs::write(
        dir.join("bad.toml"),
        GOOD_SCENE.replace("frame_dt = 0.02", "frame_dt = 1e30"),
    )
    .unwrap();
    std::fs::write(dir.join("notes.txt"), "not a directory\n").unwrap();
    dir
}

/// Runs `bin ARGS` in `dir` ([`run_bin`]); its exit code and its stderr with `dir` written
/// `<dir>` ([`stderr_in`]).
pub fn run_in(bin: &str, dir: &Path, args: &[&str]) -> (i32, String) {
    let out = run_bin(bin, args, dir, &[]);
    (code_of(&out), stderr_in(&out, dir, "<dir>"))
}

/// Runs each command-line error case `(name, ARGS)` of `bin` in its own
/// [`error_case_dir`]`(prefix, name)` and asserts that it failed as a command-line error
/// does (exit code 1 or 2) before simulating anything (no `target` output directory
/// appeared); `snapshot(name, stderr)` then checks the message (an insta assertion in the
/// test file, so that the snapshot files keep the test file's name).
pub fn check_error_cases(
    bin: &str,
    prefix: &str,
    cases: &[(&str, &[&str])],
    mut snapshot: impl FnMut(&str, String),
) {
    for &(name, args) in cases {
        let dir = error_case_dir(prefix, name);
        let (code, stderr) = run_in(bin, &dir, args);
        assert!(
            code == 1 || code == 2,
            "{name}: exit code {code}, stderr:\n{stderr}"
        );
        snapshot(name, stderr);
        // Nothing was simulated: no output directory appeared.
        assert!(!dir.join("target").exists(), "{name}: wrote output");
    }
}
