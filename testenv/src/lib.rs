//! The programs Vigil's tests need beyond Rust, found where they are or
//! installed when they are missing, so that `cargo test --workspace` does its
//! own set-up on a fresh Debian or Ubuntu machine:
//! - [`chromium`]: a headless Chromium and its WebDriver, for the live
//!   view's browser test (`sim/tests/live.rs`);
//! - [`postgres_bindir`]: PostgreSQL's server programs, for the database
//!   tests (`tests/postgres`);
//! - [`python3`]: for the Python example's test
//!   (`sim/tests/python_example.rs`);
//! - [`kill`]: for the graceful shutdown test (`tests/api/ops.rs`).
//!
//! Each looks for its program (an override variable, the usual places, the
//! `PATH`). When it is missing, Debian's package is installed with `apt-get
//! update` and `apt-get install -y --no-install-recommends` (as root, or
//! through `sudo -n` when that needs no password), and the program is looked
//! for again. When it can be neither found nor installed the function panics
//! with what is missing, the command that installs it and why it was not
//! installed: the test fails, it is never skipped. [`NO_INSTALL`] turns
//! installing off.
//!
//! What is installed and why goes straight to the standard error (not
//! through the test harness's capture, and apt-get's output with it), so a
//! long pause is explained while it happens. Installs are serialised: in a
//! process by a mutex, across processes (test binaries run at the same time,
//! as nextest does) by a lock on `vigil-testenv.lock` in the temporary
//! directory; whoever waited looks again before installing.

use std::ffi::OsStr;
use std::fs::{File, OpenOptions, TryLockError};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, OnceLock, PoisonError};
use std::time::Instant;

/// The environment variable that turns installing off: set to anything but
/// the empty string or `0`, a missing program fails its tests at once (with
/// the command that would install it) instead of being installed.
pub const NO_INSTALL: &str = "VIGIL_TEST_NO_INSTALL";

/// A headless browser and its WebDriver server.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Browser {
    /// The browser's executable: `$CHROMIUM`, else the first `chromium`,
    /// `chromium-browser`, `google-chrome` or `chrome` on the `PATH`.
    pub chromium: PathBuf,
    /// The WebDriver server: `$CHROMEDRIVER`, else `chromedriver` on the
    /// `PATH`.
    pub chromedriver: PathBuf,
}

/// Chromium and chromedriver, installed (Debian's `chromium` and
/// `chromium-driver`) when either is missing.
///
/// `CHROMIUM` and `CHROMEDRIVER`, when set, name the executables (a path,
/// or a name looked up on the `PATH`) and nothing is installed for them.
/// Looks once per process; later calls return the same answer.
///
/// # Panics
/// When they are missing and cannot be installed (not root and no
/// password-less sudo, no `apt-get`, `apt-get` failed, [`NO_INSTALL`] set),
/// or when `CHROMIUM` or `CHROMEDRIVER` names no executable file; the
/// message says what is missing, how to install it and why it was not.
#[track_caller]
pub fn chromium() -> Browser {
    static FOUND: OnceLock<Result<Browser, String>> = OnceLock::new();
    provide(&FOUND, &CHROMIUM, find_browser)
}

/// The directory of PostgreSQL's server programs (`initdb`, `pg_ctl`,
/// `postgres`), installed (Debian's `postgresql`) when missing.
///
/// The directory is `$VIGIL_PG_BIN` when set (and then nothing is
/// installed), else the newest `/usr/lib/postgresql/*/bin`, else
/// `pg_config --bindir`, else the first directory on the `PATH` that has
/// all three. Looks once per process; later calls return the same answer.
///
/// # Panics
/// When they are missing and cannot be installed, or when `VIGIL_PG_BIN`
/// lacks one of them; the message says what is missing, how to install it
/// and why it was not.
#[track_caller]
pub fn postgres_bindir() -> PathBuf {
    static FOUND: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    provide(&FOUND, &POSTGRES, find_postgres)
}

/// The first `python3` on the `PATH` that runs (`python3 --version`
/// succeeds), installed (Debian's `python3`) when there is none. Looks once
/// per process; later calls return the same answer.
///
/// # Panics
/// When there is none and it cannot be installed; the message says how to
/// install it and why it was not.
#[track_caller]
pub fn python3() -> PathBuf {
    static FOUND: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    provide(&FOUND, &PYTHON3, find_python3)
}

/// The first `kill` program on the `PATH`, installed (Debian's `procps`,
/// which minimal images lack) when there is none. Looks once per process;
/// later calls return the same answer.
///
/// # Panics
/// When there is none and it cannot be installed; the message says how to
/// install it and why it was not.
#[track_caller]
pub fn kill() -> PathBuf {
    static FOUND: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    provide(&FOUND, &KILL, find_kill)
}

/// True if this process runs as root (its effective user id is 0), read
/// from `/proc/self/status`, else from `id -u`; false when neither says.
pub fn is_root() -> bool {
    euid() == Some(0)
}

/// Something the tests need, for the messages, and where Debian has it.
struct Need {
    /// What is missing.
    what: &'static str,
    /// Which tests need it, and what for.
    why: &'static str,
    /// Debian's packages that provide it.
    packages: &'static [&'static str],
    /// How to use a copy installed elsewhere instead.
    instead: &'static str,
}

const CHROMIUM: Need = Need {
    what: "a headless Chromium and its WebDriver (chromium, chromedriver)",
    why: "the live view's browser test (sim/tests/live.rs), which drives a real browser",
    packages: &["chromium", "chromium-driver"],
    instead: "set CHROMIUM and CHROMEDRIVER to an installed Chromium (or Chrome) and its \
              matching chromedriver",
};

const POSTGRES: Need = Need {
    what: "PostgreSQL's server programs (initdb, pg_ctl, postgres)",
    why: "the database tests (tests/postgres), which start a PostgreSQL server of their own",
    packages: &["postgresql"],
    instead: "set VIGIL_PG_BIN to the directory of initdb, pg_ctl and postgres, or \
              VIGIL_TEST_DATABASE_URL to a server where the tests may create databases (the \
              outage test still needs the programs)",
};

const PYTHON3: Need = Need {
    what: "python3",
    why: "the Python example's test (sim/tests/python_example.rs), which runs \
          examples/python/drive.py",
    packages: &["python3"],
    instead: "put a python3 that runs on the PATH",
};

const KILL: Need = Need {
    what: "the kill program",
    why: "the graceful shutdown test (tests/api/ops.rs), which sends a vigil-server SIGTERM \
          with it",
    packages: &["procps"],
    instead: "put a kill program on the PATH",
};

/// What a lookup found: `Ok(None)` when nothing, `Err` when an override
/// variable names something that is not there (nothing is installed then).
type Lookup<T> = Result<Option<T>, String>;

/// The cached answer of `find`, installing `need` once if needed.
#[track_caller]
fn provide<T: Clone>(
    cell: &OnceLock<Result<T, String>>,
    need: &Need,
    find: fn() -> Lookup<T>,
) -> T {
    match cell.get_or_init(|| ensure(need, find)) {
        Ok(found) => found.clone(),
        Err(message) => panic!("{message}"),
    }
}

/// Finds, else installs and finds again; `Err` is the message to fail with.
fn ensure<T>(need: &Need, find: fn() -> Lookup<T>) -> Result<T, String> {
    let root = is_root();
    let misdirected = |e: String| {
        need.failure(
            &format!(
                "{e}; unset it to let the tests find or install {}",
                need.what
            ),
            root,
        )
    };
    if let Some(found) = find().map_err(misdirected)? {
        return Ok(found);
    }
    let _lock = InstallLock::take();
    // Another test process may have installed it while we waited.
    if let Some(found) = find().map_err(misdirected)? {
        return Ok(found);
    }
    let host = Host::here();
    let route = route(&host).map_err(|refusal| need.failure(&refusal.reason(), root))?;
    install(need, route).map_err(|e| need.failure(&e, root))?;
    find().map_err(misdirected)?.ok_or_else(|| {
        need.failure(
            &format!(
                "apt-get installed {}, yet {} is still not found where the tests look \
                 (PATH={})",
                need.packages.join(" "),
                need.what,
                std::env::var("PATH").unwrap_or_default()
            ),
            root,
        )
    })
}

impl Need {
    /// The message of a test that cannot have what it needs.
    fn failure(&self, reason: &str, root: bool) -> String {
        format!(
            "\n\n*** MISSING TEST PREREQUISITE: {} ***\n\
             needed by:     {}\n\
             not installed: {reason}\n\
             install it:    {}\n\
             or instead:    {}\n",
            self.what,
            self.why,
            install_command(self.packages, root),
            self.instead
        )
    }
}

/// The command a person runs to install `packages` (with sudo unless root).
fn install_command(packages: &[&str], root: bool) -> String {
    let sudo = if root { "" } else { "sudo " };
    format!(
        "{sudo}apt-get update && {sudo}apt-get install -y --no-install-recommends {}",
        packages.join(" ")
    )
}

/// What decides whether and how packages can be installed here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Host {
    /// The effective user id, when known.
    uid: Option<u32>,
    /// `apt-get` is on the `PATH`.
    apt_get: bool,
    /// What `sudo` would do for us (not asked when root).
    sudo: Sudo,
    /// [`NO_INSTALL`] is set.
    no_install: bool,
}

/// What `sudo -n` does here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sudo {
    /// Not on the `PATH`.
    Absent,
    /// `sudo -n true` fails: it wants a password (or forbids us).
    Refuses,
    /// `sudo -n true` succeeds.
    Runs,
}

/// How packages are installed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    /// `apt-get` itself: we are root.
    AsRoot,
    /// `sudo -n apt-get`.
    Sudo,
}

/// Why packages are not installed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Refusal {
    /// [`NO_INSTALL`] is set.
    NoInstall,
    /// No `apt-get`: not Debian or Ubuntu.
    NoAptGet,
    /// Not root, and sudo cannot help.
    NotRoot {
        /// The effective user id, when known.
        uid: Option<u32>,
        /// What sudo does.
        sudo: Sudo,
    },
}

impl Refusal {
    /// Why, in words.
    fn reason(&self) -> String {
        match *self {
            Refusal::NoInstall => format!("{NO_INSTALL} is set, which turns installing off"),
            Refusal::NoAptGet => "apt-get is not on the PATH (not Debian or Ubuntu?); install \
                                  the equivalent of these Debian packages with your system's \
                                  package manager"
                .to_owned(),
            Refusal::NotRoot { uid, sudo } => {
                let who = uid.map_or("an unknown user".to_owned(), |u| format!("uid {u}"));
                let sudo = match sudo {
                    Sudo::Absent => "sudo is not installed",
                    Sudo::Refuses => "`sudo -n true` fails (sudo wants a password)",
                    // Not a refusal; kept total for the message.
                    Sudo::Runs => "sudo runs",
                };
                format!("installing needs root; the tests run as {who}, and {sudo}")
            }
        }
    }
}

/// Whether and how `host` installs packages: the whole decision, pure.
fn route(host: &Host) -> Result<Route, Refusal> {
    if host.no_install {
        return Err(Refusal::NoInstall);
    }
    if !host.apt_get {
        return Err(Refusal::NoAptGet);
    }
    if host.uid == Some(0) {
        return Ok(Route::AsRoot);
    }
    match host.sudo {
        Sudo::Runs => Ok(Route::Sudo),
        sudo => Err(Refusal::NotRoot {
            uid: host.uid,
            sudo,
        }),
    }
}

impl Host {
    /// This machine, now.
    fn here() -> Host {
        let uid = euid();
        let sudo = if uid == Some(0) {
            Sudo::Absent
        } else {
            match on_path(&["sudo"], executable) {
                None => Sudo::Absent,
                Some(sudo) => {
                    let runs = Command::new(sudo)
                        .args(["-n", "true"])
                        .stdin(Stdio::null())
                        .stdout(Stdio::null())
                        .stderr(Stdio::null())
                        .status()
                        .is_ok_and(|s| s.success());
                    if runs { Sudo::Runs } else { Sudo::Refuses }
                }
            }
        };
        Host {
            uid,
            apt_get: on_path(&["apt-get"], executable).is_some(),
            sudo,
            no_install: std::env::var_os(NO_INSTALL).is_some_and(|v| !v.is_empty() && v != "0"),
        }
    }
}

/// `apt-get update` (once per process) and `apt-get install -y
/// --no-install-recommends` of the packages; `Err` says which command failed.
fn install(need: &Need, route: Route) -> Result<(), String> {
    static UPDATED: AtomicBool = AtomicBool::new(false);
    let packages = need.packages.join(" ");
    let how = match route {
        Route::AsRoot => "as root",
        Route::Sudo => "through sudo -n",
    };
    say(&format!(
        "missing {}, needed by {}: installing Debian's {packages} with apt-get ({how}); \
         this can take a few minutes",
        need.what, need.why
    ));
    let started = Instant::now();
    if !UPDATED.load(Ordering::Relaxed) {
        apt(route, &["update"])?;
        UPDATED.store(true, Ordering::Relaxed);
    }
    // Only what the tests need: no recommended extras (the server's would
    // bring `sysstat` and its timers).
    let mut args = vec!["install", "-y", "--no-install-recommends"];
    args.extend(need.packages);
    apt(route, &args)?;
    say(&format!(
        "installed {packages} in {:.0} s",
        started.elapsed().as_secs_f64()
    ));
    Ok(())
}

/// Runs `apt-get ARGS`, non-interactive, its output on our standard error.
fn apt(route: Route, args: &[&str]) -> Result<(), String> {
    // Wait for another apt or dpkg (unattended upgrades, a person) rather
    // than fail at once.
    let options = ["-q", "-o", "DPkg::Lock::Timeout=300"];
    let mut cmd = match route {
        Route::AsRoot => Command::new("apt-get"),
        Route::Sudo => {
            let mut c = Command::new("sudo");
            // sudo resets the environment: `env` passes DEBIAN_FRONTEND on.
            c.args(["-n", "env", "DEBIAN_FRONTEND=noninteractive", "apt-get"]);
            c
        }
    };
    cmd.env("DEBIAN_FRONTEND", "noninteractive")
        .args(options)
        .args(args)
        .stdin(Stdio::null())
        .stdout(std::io::stderr());
    let shown = format!(
        "{}apt-get {}",
        if route == Route::Sudo { "sudo -n " } else { "" },
        args.join(" ")
    );
    say(&format!("running {shown}"));
    let status = cmd
        .status()
        .map_err(|e| format!("`{shown}` could not start: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{shown}` failed ({status}; its output is above)"))
    }
}

/// Holds the installs of this process and of others, while it lives.
struct InstallLock {
    _process: MutexGuard<'static, ()>,
    /// Locked; closing it unlocks. None when it could not be locked.
    _file: Option<File>,
}

impl InstallLock {
    /// Waits for the installs of other threads and other processes.
    fn take() -> InstallLock {
        static PROCESS: Mutex<()> = Mutex::new(());
        let process = PROCESS.lock().unwrap_or_else(PoisonError::into_inner);
        let path = std::env::temp_dir().join("vigil-testenv.lock");
        // Another user's lock file can only be read; flock works on that.
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .or_else(|_| File::open(&path));
        let file = match file {
            Ok(file) => match file.try_lock() {
                Ok(()) => Some(file),
                Err(TryLockError::WouldBlock) => {
                    say(&format!(
                        "waiting for another test process that is installing (lock {})",
                        path.display()
                    ));
                    match file.lock() {
                        Ok(()) => Some(file),
                        Err(e) => unlocked(&path, &e),
                    }
                }
                Err(TryLockError::Error(e)) => unlocked(&path, &e),
            },
            Err(e) => unlocked(&path, &e),
        };
        InstallLock {
            _process: process,
            _file: file,
        }
    }
}

/// Says that installs go on without the cross-process lock, and why.
fn unlocked(path: &Path, e: &std::io::Error) -> Option<File> {
    say(&format!(
        "cannot lock {} ({e}); installing without it",
        path.display()
    ));
    None
}

/// One line on the standard error, past the test harness's capture.
fn say(line: &str) {
    let _ = writeln!(std::io::stderr().lock(), "vigil-testenv: {line}");
}

/// The effective user id: `/proc/self/status`, else `id -u`.
fn euid() -> Option<u32> {
    if let Ok(status) = std::fs::read_to_string("/proc/self/status") {
        return effective_uid(&status);
    }
    let out = Command::new("id").arg("-u").output().ok()?;
    String::from_utf8_lossy(&out.stdout).trim().parse().ok()
}

/// The effective uid of a `/proc/PID/status` text (its `Uid:` line reads
/// real, effective, saved and file-system ids).
fn effective_uid(status: &str) -> Option<u32> {
    status
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

/// True for a file anyone may execute (following symbolic links).
fn executable(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::metadata(path).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
    }
    #[cfg(not(unix))]
    {
        path.is_file()
    }
}

/// The first `dir/name` for which `ok` holds, over the `PATH`'s
/// directories in order, then `names` in order.
fn on_path<N: AsRef<OsStr>>(names: &[N], ok: impl Fn(&Path) -> bool) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| names.iter().map(move |n| dir.join(n.as_ref())))
        .find(|p| ok(p))
}

/// The executable `$var` names (a path, or a name on the `PATH`); `None`
/// when `var` is unset or empty.
fn overridden(var: &str) -> Lookup<PathBuf> {
    let Some(value) = std::env::var_os(var).filter(|v| !v.is_empty()) else {
        return Ok(None);
    };
    let path = PathBuf::from(&value);
    let found = if path.components().count() == 1 && !path.is_absolute() {
        on_path(&[&value], executable)
    } else {
        Some(path).filter(|p| executable(p))
    };
    found.map(Some).ok_or_else(|| {
        format!(
            "{var} is set to {}, which is not an executable file",
            value.to_string_lossy()
        )
    })
}

/// Chromium and chromedriver: overrides, else the `PATH`.
fn find_browser() -> Lookup<Browser> {
    let chromedriver = match overridden("CHROMEDRIVER")? {
        Some(p) => Some(p),
        None => on_path(&["chromedriver"], executable),
    };
    let chromium = match overridden("CHROMIUM")? {
        Some(p) => Some(p),
        None => on_path(
            &["chromium", "chromium-browser", "google-chrome", "chrome"],
            executable,
        ),
    };
    Ok(chromium
        .zip(chromedriver)
        .map(|(chromium, chromedriver)| Browser {
            chromium,
            chromedriver,
        }))
}

/// The directory of `initdb`, `pg_ctl` and `postgres` (see
/// [`postgres_bindir`]).
fn find_postgres() -> Lookup<PathBuf> {
    let has = |d: &Path| {
        ["initdb", "pg_ctl", "postgres"]
            .iter()
            .all(|p| executable(&d.join(p)))
    };
    if let Some(dir) = std::env::var_os("VIGIL_PG_BIN").filter(|d| !d.is_empty()) {
        let dir = PathBuf::from(dir);
        return if has(&dir) {
            Ok(Some(dir))
        } else {
            Err(format!(
                "VIGIL_PG_BIN is set to {}, which lacks initdb, pg_ctl or postgres",
                dir.display()
            ))
        };
    }
    let mut versions: Vec<(u32, PathBuf)> = std::fs::read_dir("/usr/lib/postgresql")
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let v = e.file_name().to_string_lossy().parse::<u32>().ok()?;
            Some((v, e.path().join("bin")))
        })
        .filter(|(_, d)| has(d))
        .collect();
    versions.sort();
    if let Some((_, dir)) = versions.pop() {
        return Ok(Some(dir));
    }
    if let Ok(out) = Command::new("pg_config").arg("--bindir").output() {
        let dir = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        if has(&dir) {
            return Ok(Some(dir));
        }
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    Ok(std::env::split_paths(&path).find(|d| has(d)))
}

/// The first `python3` on the `PATH` that runs.
fn find_python3() -> Lookup<PathBuf> {
    Ok(on_path(&["python3"], |p| {
        executable(p)
            && Command::new(p)
                .arg("--version")
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
    }))
}

/// The first `kill` on the `PATH`.
fn find_kill() -> Lookup<PathBuf> {
    Ok(on_path(&["kill"], executable))
}

#[cfg(test)]
mod tests {
    use super::*;

    const HOST: Host = Host {
        uid: Some(1000),
        apt_get: true,
        sudo: Sudo::Absent,
        no_install: false,
    };

    #[test]
    fn root_installs_with_apt_get() {
        let root = Host {
            uid: Some(0),
            ..HOST
        };
        assert_eq!(route(&root), Ok(Route::AsRoot));
        // sudo is not asked for when root.
        for sudo in [Sudo::Absent, Sudo::Refuses, Sudo::Runs] {
            assert_eq!(route(&Host { sudo, ..root }), Ok(Route::AsRoot));
        }
    }

    #[test]
    fn others_install_through_sudo_that_needs_no_password() {
        let user = Host {
            sudo: Sudo::Runs,
            ..HOST
        };
        assert_eq!(route(&user), Ok(Route::Sudo));
        assert_eq!(route(&Host { uid: None, ..user }), Ok(Route::Sudo));
    }

    #[test]
    fn others_without_sudo_are_refused() {
        for sudo in [Sudo::Absent, Sudo::Refuses] {
            let host = Host { sudo, ..HOST };
            assert_eq!(
                route(&host),
                Err(Refusal::NotRoot {
                    uid: Some(1000),
                    sudo
                })
            );
        }
    }

    #[test]
    fn no_install_and_no_apt_get_come_first() {
        for uid in [Some(0), Some(1000), None] {
            for sudo in [Sudo::Absent, Sudo::Refuses, Sudo::Runs] {
                let host = Host { uid, sudo, ..HOST };
                assert_eq!(
                    route(&Host {
                        no_install: true,
                        ..host
                    }),
                    Err(Refusal::NoInstall)
                );
                assert_eq!(
                    route(&Host {
                        apt_get: false,
                        ..host
                    }),
                    Err(Refusal::NoAptGet)
                );
            }
        }
    }

    #[test]
    fn the_message_says_what_how_and_why() {
        let refusal = Refusal::NotRoot {
            uid: Some(1000),
            sudo: Sudo::Absent,
        };
        let m = CHROMIUM.failure(&refusal.reason(), false);
        assert!(
            m.contains("MISSING TEST PREREQUISITE: a headless Chromium"),
            "{m}"
        );
        assert!(m.contains("sim/tests/live.rs"), "{m}");
        assert!(
            m.contains(
                "sudo apt-get update && sudo apt-get install -y --no-install-recommends chromium \
                 chromium-driver"
            ),
            "{m}"
        );
        assert!(m.contains("uid 1000, and sudo is not installed"), "{m}");
        assert!(m.contains("CHROMIUM and CHROMEDRIVER"), "{m}");
        let m = POSTGRES.failure(&Refusal::NoInstall.reason(), true);
        assert!(
            m.contains(
                "install it:    apt-get update && apt-get install -y --no-install-recommends \
                 postgresql\n"
            ),
            "{m}"
        );
        assert!(m.contains("VIGIL_TEST_NO_INSTALL is set"), "{m}");
    }

    #[test]
    fn the_effective_uid_is_the_second_of_the_uid_line() {
        let status = "Name:\tcat\nUmask:\t0022\nUid:\t1000\t0\t0\t0\nGid:\t100\t100\t100\t100\n";
        assert_eq!(effective_uid(status), Some(0));
        assert_eq!(effective_uid("Uid:\t0\t1000\t1000\t1000\n"), Some(1000));
        assert_eq!(effective_uid("Name:\tcat\n"), None);
        // This process: the same answer as `id -u`.
        let id = Command::new("id").arg("-u").output().expect("id -u runs");
        let id: u32 = String::from_utf8_lossy(&id.stdout)
            .trim()
            .parse()
            .expect("a uid");
        assert_eq!(euid(), Some(id));
    }

    #[test]
    fn programs_are_found_on_the_path() {
        // `sh` is on every PATH the tests run with.
        let sh = on_path(&["no-such-program-here", "sh"], executable).expect("sh");
        assert!(sh.ends_with("sh") && executable(&sh));
        assert_eq!(on_path(&["no-such-program-here"], executable), None);
    }
}
