//! Which files to watch, and turning notify's raw events into debounced
//! batches.
//!
//! We watch the *directories* that hold the files (not the files' inodes) and
//! keep only events whose path is one of ours: an editor that saves by
//! writing a new file and renaming it over the old one (or by deleting and
//! re-creating it) replaces the inode, and a watch on the old inode would go
//! quiet. Our own reads of the files (inotify `OPEN`/`CLOSE_NOWRITE`) and
//! writes to other files in the same directories (the output image) are
//! ignored.

use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use notify::event::{AccessKind, AccessMode, EventKind};
use notify::{RecursiveMode, Watcher as _};

/// The files a reload depends on, split by what they invalidate.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WatchSet {
    /// The scene file and every file it read (glTF, buffers).
    pub scene: BTreeSet<PathBuf>,
    /// The shader sources.
    pub shaders: BTreeSet<PathBuf>,
}

impl WatchSet {
    /// The directories holding the files.
    fn dirs(&self) -> BTreeSet<PathBuf> {
        self.scene
            .iter()
            .chain(&self.shaders)
            .filter_map(|p| p.parent().map(Path::to_path_buf))
            .collect()
    }
}

/// An absolute path with its directory resolved (symlinks, `..`), which is
/// how notify reports the events of a watched directory. The file itself
/// need not exist (it may be between a delete and a create).
pub fn normalise(path: &Path) -> PathBuf {
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    };
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => dir
            .canonicalize()
            .map(|d| d.join(name))
            .unwrap_or_else(|_| abs.clone()),
        _ => abs,
    }
}

/// Files that changed together, within one debounce window.
#[derive(Clone, Debug)]
pub struct Batch {
    /// When the first event of the batch arrived.
    pub first_event: Instant,
    /// When the last event of the batch arrived.
    pub last_event: Instant,
    /// The changed files (normalised paths).
    pub paths: BTreeSet<PathBuf>,
}

/// Watches the directories of a [`WatchSet`] and debounces the events.
pub struct FileWatcher {
    watcher: notify::RecommendedWatcher,
    rx: Receiver<notify::Result<notify::Event>>,
    set: WatchSet,
    wanted: HashSet<PathBuf>,
    dirs: BTreeSet<PathBuf>,
    /// Events seen but not yet handed out (by [`FileWatcher::pending`]).
    buffered: Option<Batch>,
    /// Paths of the buffered batch whose last event did not finish a write
    /// ([`settles`]).
    unsettled: HashSet<PathBuf>,
    /// A batch whose every file has settled ends after this long without a
    /// new event...
    settle: Duration,
    /// ...and one with a file still being written after this long...
    quiet: Duration,
    /// ...or this long after its first event (a file written continuously).
    max_wait: Duration,
}

/// Does this kind of event mean the file's content may have changed?
fn is_change(kind: &EventKind) -> bool {
    match kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
        EventKind::Access(_) => false,
        EventKind::Create(_) | EventKind::Modify(_) | EventKind::Remove(_) => true,
        EventKind::Any | EventKind::Other => true,
    }
}

/// Does this event finish writing `path`, so that its content is what the
/// writer meant? A close after writing (inotify's `CLOSE_WRITE`: an editor
/// that saves in place, `std::fs::write`) or a rename onto the path (an
/// editor that saves to a temporary file and renames it over ours). A
/// create, a modify without a close, a delete or a rename away are the
/// middle of a save: the batch then waits for the debounce window.
fn settles(kind: &EventKind, paths: &[PathBuf], path: &Path) -> bool {
    use notify::event::{ModifyKind, RenameMode};
    match kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
        EventKind::Modify(ModifyKind::Name(RenameMode::To)) => true,
        EventKind::Modify(ModifyKind::Name(RenameMode::Both)) => {
            paths.last().is_some_and(|p| p == path)
        }
        _ => false,
    }
}

/// How long a batch whose files have all settled waits for more events: an
/// editor or `git checkout` that writes several files in a row writes the
/// next within this, so they reload together.
pub const SETTLE: Duration = Duration::from_millis(3);

impl FileWatcher {
    /// Starts watching; `quiet` is the debounce window.
    pub fn new(set: WatchSet, quiet: Duration) -> notify::Result<FileWatcher> {
        let (tx, rx) = mpsc::channel();
        let watcher = notify::recommended_watcher(move |ev| {
            let _ = tx.send(ev);
        })?;
        let mut w = FileWatcher {
            watcher,
            rx,
            set: WatchSet::default(),
            wanted: HashSet::new(),
            dirs: BTreeSet::new(),
            buffered: None,
            unsettled: HashSet::new(),
            settle: SETTLE.min(quiet),
            quiet,
            max_wait: Duration::from_secs(1).max(quiet * 4),
        };
        w.update(set)?;
        Ok(w)
    }

    /// The files being watched.
    pub fn set(&self) -> &WatchSet {
        &self.set
    }

    /// Watches a new set of files (a scene edit may reference other files),
    /// adding and removing directory watches as needed.
    pub fn update(&mut self, set: WatchSet) -> notify::Result<()> {
        let dirs = set.dirs();
        for gone in self.dirs.difference(&dirs) {
            // The directory may itself be gone; nothing to do then.
            let _ = self.watcher.unwatch(gone);
        }
        for new in dirs.difference(&self.dirs) {
            self.watcher.watch(new, RecursiveMode::NonRecursive)?;
        }
        self.dirs = dirs;
        self.wanted = set.scene.iter().chain(&set.shaders).cloned().collect();
        self.set = set;
        Ok(())
    }

    /// Moves the raw events that arrive until `deadline` into the buffer,
    /// returning early at the first relevant one; returns whether one came.
    /// A deadline in the past takes what has already arrived.
    fn drain(&mut self, deadline: Instant) -> bool {
        let mut got = false;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let ev = if got || left.is_zero() {
                match self.rx.try_recv() {
                    Ok(ev) => ev,
                    Err(_) => return got,
                }
            } else {
                match self.rx.recv_timeout(left) {
                    Ok(ev) => ev,
                    Err(RecvTimeoutError::Timeout) | Err(RecvTimeoutError::Disconnected) => {
                        return got
                    }
                }
            };
            let now = Instant::now();
            let ev = match ev {
                Ok(ev) => ev,
                // The watcher lost events (queue overflow): reload everything.
                Err(_) => notify::Event::new(EventKind::Other)
                    .add_some_path(self.wanted.iter().next().cloned()),
            };
            if !is_change(&ev.kind) {
                continue;
            }
            for p in &ev.paths {
                if self.wanted.contains(p) {
                    if settles(&ev.kind, &ev.paths, p) {
                        self.unsettled.remove(p);
                    } else {
                        self.unsettled.insert(p.clone());
                    }
                    let batch = self.buffered.get_or_insert_with(|| Batch {
                        first_event: now,
                        last_event: now,
                        paths: BTreeSet::new(),
                    });
                    batch.last_event = now;
                    batch.paths.insert(p.clone());
                    got = true;
                }
            }
        }
    }

    /// Whether a change arrived since the last batch (without waiting): the
    /// loop asks between the stages of a render, to cancel refinement.
    pub fn pending(&mut self) -> bool {
        self.drain(Instant::now());
        self.buffered.is_some()
    }

    /// Waits for the next batch of changes: returns once every changed file
    /// has settled (its writer closed it or renamed it into place) and no
    /// other event came for [`SETTLE`], else once the files have been quiet
    /// for the debounce window (or a second after the first event, if they
    /// never go quiet); `None` when `stop` is set.
    pub fn next_batch(&mut self, stop: &AtomicBool) -> Option<Batch> {
        while self.buffered.is_none() {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            self.drain(Instant::now() + Duration::from_millis(50));
        }
        loop {
            let b = self.buffered.as_ref()?;
            let wait = match self.unsettled.is_empty() {
                true => self.settle,
                false => self.quiet,
            };
            let end = (b.last_event + wait).min(b.first_event + self.max_wait);
            if Instant::now() >= end {
                self.unsettled.clear();
                return self.buffered.take();
            }
            self.drain(end);
        }
    }
}
