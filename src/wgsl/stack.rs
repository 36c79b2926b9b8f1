//! naga on a stack sized for the limits: the WGSL front end recurses once
//! per level of nesting and per operator of an expression chain, so a
//! shader's parse runs on a thread of its own whose stack
//! ([`super::limits::PARSE_STACK_BYTES`]) holds the deepest recursion that a
//! file within [`super::limits`] can cause, whichever thread (the main one,
//! a worker with a small stack) asks for the compile.

use super::limits::PARSE_STACK_BYTES;

/// Runs `f` on a thread with a stack of [`PARSE_STACK_BYTES`] and returns
/// its result; a panic in `f`, or a thread that cannot be started (the
/// system is out of threads or memory), is returned as `Err` with its
/// message, like [`crate::panics::catch`].
pub fn on_parse_stack<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, String> {
    std::thread::scope(|scope| {
        let handle = std::thread::Builder::new()
            .name("penumbra-naga".into())
            .stack_size(PARSE_STACK_BYTES)
            .spawn_scoped(scope, || crate::panics::catch(f))
            .map_err(|e| format!("cannot start the thread that parses shaders: {e}"))?;
        handle
            .join()
            .unwrap_or_else(|payload| Err(crate::panics::message(payload.as_ref())))
    })
}
