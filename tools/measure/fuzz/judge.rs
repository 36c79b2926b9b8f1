//! How a case is judged: a clean `Err` or success is fine; a panic, a hang or
//! an allocation out of proportion to the input is a bug.
//!
//! Memory is measured by a counting global allocator with per-thread totals,
//! so the peak of one case is the peak of the worker thread that ran it; a
//! compile also counts the whole process (naga runs on a thread of its own,
//! `penumbra::wgsl::stack`), see [`case_peak_all`].

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicIsize, Ordering};
use std::time::Duration;

/// A case slower than this (for an input under 1 MiB) is a hang.
pub const HANG: Duration = Duration::from_secs(2);

/// A worker whose case runs this long is stopped and the case saved.
pub const STUCK: Duration = Duration::from_secs(20);

/// Memory a case may use beyond 64 times its input: fixed costs such as
/// the parser's buffers and the scene's default objects.
pub const ALLOWANCE: usize = 4 << 20;

/// The allocation limit for an input of `len` bytes: 64 × its size plus [`ALLOWANCE`].
pub fn allowed(len: usize) -> usize {
    len.saturating_mul(64).saturating_add(ALLOWANCE)
}

/// The verdict on one case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Verdict {
    /// The loader (or compiler) accepted the input.
    Ok,
    /// The input was refused with an error.
    Err,
    /// It panicked.
    Panic,
    /// It took longer than [`HANG`].
    Hang,
    /// Its peak allocation exceeded [`allowed`].
    Huge,
    /// The worker process died (abort, stack overflow) or was stopped after [`STUCK`].
    Crash,
}

impl Verdict {
    /// All verdicts, in report order.
    pub const ALL: [Verdict; 6] = [
        Verdict::Ok,
        Verdict::Err,
        Verdict::Panic,
        Verdict::Hang,
        Verdict::Huge,
        Verdict::Crash,
    ];

    /// The name used in the report and the worker protocol.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::Err => "err",
            Verdict::Panic => "panic",
            Verdict::Hang => "hang",
            Verdict::Huge => "huge-alloc",
            Verdict::Crash => "crash",
        }
    }

    /// Whether this verdict is a bug.
    pub fn is_bug(self) -> bool {
        !matches!(self, Verdict::Ok | Verdict::Err)
    }
}

thread_local! {
    static CURRENT: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

/// The system allocator, counting this thread's live bytes and their peak.
pub struct Counting;

/// The process's live bytes, their peak since [`start_case`], and the live
/// bytes then.
static ALL_CURRENT: AtomicIsize = AtomicIsize::new(0);
static ALL_PEAK: AtomicIsize = AtomicIsize::new(0);
static ALL_START: AtomicIsize = AtomicIsize::new(0);

fn add(delta: isize) {
    let now = ALL_CURRENT.fetch_add(delta, Ordering::Relaxed) + delta;
    ALL_PEAK.fetch_max(now, Ordering::Relaxed);
    // `try_with`: the allocator also runs while thread-locals are torn down.
    let _ = CURRENT.try_with(|c| {
        let now = c.get() + delta;
        c.set(now);
        let _ = PEAK.try_with(|p| p.set(p.get().max(now)));
    });
}

// SAFETY: forwards to `System` unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            add(layout.size() as isize);
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            add(layout.size() as isize);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        add(-(layout.size() as isize));
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            add(new_size as isize - layout.size() as isize);
        }
        p
    }
}

/// Starts measuring a case on this thread.
pub fn start_case() {
    let now = CURRENT.with(Cell::get);
    PEAK.with(|p| p.set(now));
    let all = ALL_CURRENT.load(Ordering::Relaxed);
    ALL_START.store(all, Ordering::Relaxed);
    ALL_PEAK.store(all, Ordering::Relaxed);
}

/// Bytes the whole process allocated at its peak since [`start_case`],
/// beyond what it held then: for the compile targets, whose naga work runs
/// on another thread (the worker runs one case at a time; its watchdog
/// thread allocates next to nothing).
pub fn case_peak_all() -> usize {
    (ALL_PEAK.load(Ordering::Relaxed) - ALL_START.load(Ordering::Relaxed)).max(0) as usize
}

/// Bytes this thread allocated at its peak since [`start_case`], beyond what it held then.
pub fn case_peak(start: isize) -> usize {
    (PEAK.with(Cell::get) - start).max(0) as usize
}

/// This thread's live bytes.
pub fn current() -> isize {
    CURRENT.with(Cell::get)
}
