//! Surviving a shader that never ends. A dispatch that lavapipe (or a GPU
//! driver) is running cannot be cancelled: after a wait runs past the time
//! limit the device is hung, a driver thread spins for ever, and only ending
//! the process frees it. So `watch` replaces itself: the loop reports the
//! time-out, ends with a [`Restart`], and the command line re-executes the
//! same binary with the same arguments (`execv` keeps the process id, the
//! terminal and the pipes; it ends every thread, the spinning one included).
//! The new process gets, through its environment, the reload number to go on
//! from, the live page's address, and a [`Quarantine`]: a hash of the files
//! that hung. It does not render them again; it shows the error, keeps the
//! last good image (on disk and on the page) and renders the next save.
//! Browsers isolate their GPU process for the same reason; here the process
//! is the isolation, and a normal edit pays nothing for it.

use std::ffi::OsString;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// The environment variables that carry a restart to the new process.
const ENV_SNAPSHOT: &str = "PENUMBRA_WATCH_HUNG_FILES";
const ENV_ERROR: &str = "PENUMBRA_WATCH_HUNG_ERROR";
const ENV_NEXT: &str = "PENUMBRA_WATCH_NEXT_RELOAD";
const ENV_SERVE: &str = "PENUMBRA_WATCH_SERVE";
const ENV_FILES: &str = "PENUMBRA_WATCH_HUNG_PATHS";

/// The most files a quarantine carries.
const MAX_FILES: usize = 4096;

/// The longest error text carried over (the environment is no place for more).
const MAX_ERROR_BYTES: usize = 4096;

/// The files that hung the device, as they were: their hash, and the error
/// that reported it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Quarantine {
    /// The scene's files and user shaders (not its textures) when the
    /// time-out happened: watched again by the new process.
    pub files: Vec<PathBuf>,
    /// [`snapshot`] of `files` when the time-out happened.
    pub snapshot: String,
    /// The time-out's error message.
    pub error: String,
}

/// What a restarted loop goes on from.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Resume {
    /// The files not to render again until one of them changes.
    pub quarantine: Option<Quarantine>,
    /// The number of the first reload (the one after the hung one).
    pub next_reload: u64,
    /// The address the live page had (`--serve` may have asked for port 0).
    pub serve: Option<SocketAddr>,
}

/// What the loop hands back when the device hung: everything the next
/// process needs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Restart {
    /// The files that hung and the error.
    pub quarantine: Quarantine,
    /// The number of the next reload.
    pub next_reload: u64,
    /// The live page's bound address.
    pub serve: Option<SocketAddr>,
}

/// A hash of the contents of `files` (sorted by path; a file that cannot be
/// read counts as missing): the same text in the same files gives the same
/// snapshot, any save that changes one gives another.
pub fn snapshot(files: &[PathBuf]) -> String {
    let mut files: Vec<&PathBuf> = files.iter().collect();
    files.sort();
    files.dedup();
    let mut h = Sha256::new();
    for f in files {
        let path = f.as_os_str().as_encoded_bytes();
        h.update((path.len() as u64).to_le_bytes());
        h.update(path);
        match std::fs::read(f) {
            Ok(bytes) => {
                h.update([1]);
                h.update((bytes.len() as u64).to_le_bytes());
                h.update(&bytes);
            }
            Err(_) => h.update([0]),
        }
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

impl Resume {
    /// Reads what a restart left in the environment (nothing: a fresh
    /// start) and removes it, so that no child process inherits it.
    pub fn take_from_env() -> Resume {
        let names = [ENV_SNAPSHOT, ENV_ERROR, ENV_NEXT, ENV_SERVE, ENV_FILES];
        let vars: Vec<(&str, String)> = names
            .iter()
            .filter_map(|n| std::env::var(n).ok().map(|v| (*n, v)))
            .collect();
        for n in names {
            // Called at start-up, before the loop starts its threads.
            std::env::remove_var(n);
        }
        Resume::from_vars(|name| {
            vars.iter()
                .find(|(n, _)| *n == name)
                .map(|(_, v)| v.clone())
        })
    }

    /// [`Resume::take_from_env`] from the variables `get` gives; anything
    /// malformed counts as absent.
    fn from_vars(get: impl Fn(&str) -> Option<String>) -> Resume {
        Resume {
            quarantine: get(ENV_SNAPSHOT)
                .filter(|s| s.len() == 64 && s.bytes().all(|b| b.is_ascii_hexdigit()))
                .map(|snapshot| Quarantine {
                    files: get(ENV_FILES)
                        .map(|f| f.split('\n').take(MAX_FILES).map(PathBuf::from).collect())
                        .unwrap_or_default(),
                    snapshot,
                    error: get(ENV_ERROR).unwrap_or_default(),
                }),
            next_reload: get(ENV_NEXT).and_then(|n| n.parse().ok()).unwrap_or(0),
            serve: get(ENV_SERVE).and_then(|s| s.parse().ok()),
        }
    }
}

impl Restart {
    /// The environment that carries this restart ([`Resume::take_from_env`]).
    pub fn env(&self) -> Vec<(&'static str, String)> {
        let mut error = self.quarantine.error.clone();
        if error.len() > MAX_ERROR_BYTES {
            let mut end = MAX_ERROR_BYTES;
            while !error.is_char_boundary(end) {
                end -= 1;
            }
            error.truncate(end);
        }
        // The environment holds no NUL.
        let error = error.replace('\0', "\\u{0}");
        // One path a line: a path with a line break (or a NUL, which no path
        // has) is left out, and is then not watched after the restart.
        let files: Vec<String> = self
            .quarantine
            .files
            .iter()
            .filter_map(|p| p.to_str())
            .filter(|p| !p.contains(['\n', '\0']))
            .take(MAX_FILES)
            .map(str::to_string)
            .collect();
        let mut env = vec![
            (ENV_FILES, files.join("\n")),
            (ENV_SNAPSHOT, self.quarantine.snapshot.clone()),
            (ENV_ERROR, error),
            (ENV_NEXT, self.next_reload.to_string()),
        ];
        if let Some(a) = self.serve {
            env.push((ENV_SERVE, a.to_string()));
        }
        env
    }

    /// Replaces this process with a new run of the same binary and
    /// arguments, carrying this restart in the environment. Returns only if
    /// that fails.
    pub fn exec(&self) -> std::io::Error {
        use std::io::Write as _;
        use std::os::unix::process::CommandExt as _;
        let args: Vec<OsString> = std::env::args_os().skip(1).collect();
        let _ = std::io::stdout().flush();
        let _ = std::io::stderr().flush();
        // /proc/self/exe: this very binary, even if a rebuild replaced the file.
        let exe = Path::new("/proc/self/exe");
        let exe = if exe.exists() {
            exe.to_path_buf()
        } else {
            std::env::current_exe().unwrap_or_else(|_| exe.to_path_buf())
        };
        let mut cmd = std::process::Command::new(exe);
        if let Some(argv0) = std::env::args_os().next() {
            cmd.arg0(argv0);
        }
        cmd.args(args).envs(self.env()).exec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_snapshot_changes_with_any_file_and_not_with_the_order() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.wgsl");
        let b = dir.path().join("b.json");
        std::fs::write(&a, "loop {}").unwrap();
        std::fs::write(&b, "{}").unwrap();
        let one = snapshot(&[a.clone(), b.clone()]);
        assert_eq!(one, snapshot(&[b.clone(), a.clone()]));
        assert_eq!(one.len(), 64);
        std::fs::write(&a, "loop { break; }").unwrap();
        assert_ne!(one, snapshot(&[a.clone(), b.clone()]));
        std::fs::remove_file(&b).unwrap();
        assert_ne!(one, snapshot(&[a, b]));
    }

    #[test]
    fn a_restart_round_trips_through_the_environment() {
        let restart = Restart {
            quarantine: Quarantine {
                files: vec!["/s/scene.json".into(), "/s/loop.wgsl".into()],
                snapshot: "ab".repeat(32),
                error: "loop.wgsl: the shade stage ran past the time limit".into(),
            },
            next_reload: 7,
            serve: Some("127.0.0.1:8737".parse().unwrap()),
        };
        let env = restart.env();
        let get = |name: &str| env.iter().find(|(k, _)| *k == name).map(|(_, v)| v.clone());
        let resume = Resume::from_vars(get);
        assert_eq!(resume.quarantine.as_ref(), Some(&restart.quarantine));
        assert_eq!(resume.next_reload, 7);
        assert_eq!(resume.serve, restart.serve);
        // Nothing set: a fresh start; a malformed snapshot is ignored.
        assert_eq!(Resume::from_vars(|_| None), Resume::default());
        let bad = Resume::from_vars(|n| (n == ENV_SNAPSHOT).then(|| "zz".into()));
        assert_eq!(bad.quarantine, None);
    }

    #[test]
    fn a_long_error_is_cut_at_a_character_boundary() {
        let restart = Restart {
            quarantine: Quarantine {
                files: Vec::new(),
                snapshot: "0".repeat(64),
                error: "é".repeat(5000),
            },
            next_reload: 1,
            serve: None,
        };
        let env = restart.env();
        let error = &env.iter().find(|(k, _)| *k == ENV_ERROR).unwrap().1;
        assert!(error.len() <= MAX_ERROR_BYTES && error.chars().all(|c| c == 'é'));
    }
}
