//! Panics at the boundaries with dependencies, and the last-resort report.
//!
//! Known bad input is checked before it reaches a dependency, and reported as
//! an ordinary error. Some dependencies (the `gltf` crate's accessors, naga)
//! can still panic on a document that passed their own validation; at those
//! boundaries [`catch`] turns the panic into an error that the caller
//! attaches to the file and field. [`install_hook`] is for a bug not found
//! yet: the command line prints one `error:` line instead of a backtrace.

use std::cell::Cell;
use std::panic::{self, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::Mutex;

thread_local! {
    /// How many [`catch`] calls are active on this thread.
    static CATCHING: Cell<u32> = const { Cell::new(0) };
}

/// The file the command line is working on, for the last-resort message.
static SUBJECT: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Runs `f`, returning the panic's message as `Err` if it panics. While it
/// runs, the hook of [`install_hook`] stays silent on this thread: the panic
/// is reported by the caller as an error about its input.
pub fn catch<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    CATCHING.with(|c| c.set(c.get() + 1));
    let result = panic::catch_unwind(AssertUnwindSafe(f));
    CATCHING.with(|c| c.set(c.get() - 1));
    result.map_err(|payload| message(payload.as_ref()))
}

/// Whether a [`catch`] is active on this thread.
pub fn catching() -> bool {
    CATCHING.with(|c| c.get() > 0)
}

/// The text of a panic payload.
pub fn message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// Names the file that the last-resort message blames.
pub fn set_subject(file: PathBuf) {
    *SUBJECT.lock().unwrap_or_else(|e| e.into_inner()) = Some(file);
}

/// Replaces the default panic output (message and backtrace hint) with one
/// line, `error: FILE: internal error: MESSAGE at LOCATION (a bug in penumbra ...)`,
/// for panics outside [`catch`]. The panic then unwinds as usual, so
/// temporary output files are removed by their destructors.
pub fn install_hook() {
    panic::set_hook(Box::new(|info| {
        if catching() {
            return;
        }
        let file = SUBJECT
            .lock()
            .map(|s| s.clone())
            .unwrap_or_else(|e| e.into_inner().clone());
        let file = file.map_or_else(|| "penumbra".to_string(), |f| f.display().to_string());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let line = format!(
            "{file}: internal error: {}{at} (a bug in penumbra: please report it with this input)",
            message(info.payload())
        );
        eprintln!("error: {}", crate::terminal::diagnostic(&line));
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catch_returns_the_message() {
        assert_eq!(catch(|| 7), Ok(7));
        let err = catch(|| -> u32 { panic!("boom {}", 3) }).unwrap_err();
        assert_eq!(err, "boom 3");
        assert!(!catching());
    }
}
