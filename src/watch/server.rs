//! The live preview page (`--serve`): a small HTTP server with three
//! routes:
//!
//! * `/` — the page: the latest image, the current error drawn over it, and
//!   the timing line of the last reload;
//! * `/image.png` — the latest image (PNG);
//! * `/events` — server-sent events: one `frame` event (JSON: `version`,
//!   `error`, `line`) at connection and after every change; the page swaps
//!   the image when `version` changes. No polling: the browser keeps this one
//!   connection open.
//!
//! It serves these and nothing else, whatever a client sends (issue 36):
//! only `GET` and `HEAD`; a request that announces a body is refused from
//! its headers without reading the body; the request head is bounded in
//! bytes, target length and header count ([`request`]) and must arrive
//! within [`Limits::head_timeout`]. The accept loop only accepts: each
//! connection is served on a thread of its own (small stack) with a write
//! timeout, so a slow or non-reading client stalls only itself, and the
//! number of connections (and so of threads) is capped by
//! [`Limits::max_connections`]; beyond it a client gets a fixed 503 and is
//! closed, without a thread. Every answer closes its connection (pipelined
//! requests after the first are not read), except `/events`, which streams.
//!
//! std's `TcpListener` and the `httparse` parser, not an HTTP server crate:
//! tiny_http, used before, allocated a request body of any announced size
//! (one `Content-Length` aborted the process) and wrote responses on the
//! accept thread.

mod connection;
mod page;
pub mod request;

use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// The port `--serve` uses when none is given.
pub const DEFAULT_PORT: u16 = 8737;
/// What the page shows; shared between the loop and the server threads.
#[derive(Default)]
pub struct Live {
    state: Mutex<LiveState>,
    changed: Condvar,
}

#[derive(Clone, Default)]
struct LiveState {
    /// Counts changes of anything below (0: nothing yet).
    version: u64,
    /// Counts images.
    image_version: u64,
    png: Arc<Vec<u8>>,
    error: Option<String>,
    line: String,
    stopped: bool,
}

impl Live {
    /// Publishes a new image.
    pub fn set_image(&self, png: Vec<u8>) {
        let mut s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        s.png = Arc::new(png);
        s.image_version += 1;
        s.version += 1;
        self.changed.notify_all();
    }

    /// Publishes the current error (`None`: the files are good) and the
    /// timing line.
    pub fn set_status(&self, error: Option<String>, line: String) {
        let mut s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        s.error = error;
        s.line = line;
        s.version += 1;
        self.changed.notify_all();
    }

    /// Ends every event stream.
    pub fn stop(&self) {
        let mut s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        s.stopped = true;
        self.changed.notify_all();
    }

    fn snapshot(&self) -> LiveState {
        self.state.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// Waits until the version differs from `seen` (or `timeout` passes).
    fn wait_change(&self, seen: u64, timeout: Duration) -> LiveState {
        let s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        let (s, _) = self
            .changed
            .wait_timeout_while(s, timeout, |s| s.version == seen && !s.stopped)
            .unwrap_or_else(|p| p.into_inner());
        s.clone()
    }
}

/// Parses `--serve`'s value: `HOST:PORT`, a bare port (on 127.0.0.1), or a
/// bare IP address (on [`DEFAULT_PORT`]).
pub fn parse_addr(s: &str) -> Result<SocketAddr, String> {
    if let Ok(a) = s.parse::<SocketAddr>() {
        return Ok(a);
    }
    if let Ok(port) = s.trim_start_matches(':').parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    if let Ok(ip) = s.parse::<std::net::IpAddr>() {
        return Ok(SocketAddr::new(ip, DEFAULT_PORT));
    }
    use std::net::ToSocketAddrs;
    s.to_socket_addrs()
        .ok()
        .and_then(|mut a| a.next())
        .ok_or_else(|| format!("`{s}` is not an address: expected HOST:PORT, PORT or an IP"))
}

/// The server's bounds. [`Server::start`] uses the defaults; tests and
/// tools/measure/live_load.rs may set others.
#[derive(Clone, Debug)]
pub struct Limits {
    /// The most connections served at once, each on a thread of its own;
    /// one more is answered 503 and closed by the accept loop.
    pub max_connections: usize,
    /// The time a client has to send its whole request head.
    pub head_timeout: Duration,
    /// The longest a write to a client may block (an answer, or one event
    /// of a stream); a client that does not read for that long is closed.
    pub write_timeout: Duration,
}

impl Default for Limits {
    /// 512 connections (a browser needs two or three; hundreds of event
    /// streams fit), 10 s for the head, 10 s per write.
    fn default() -> Limits {
        Limits {
            max_connections: 512,
            head_timeout: Duration::from_secs(10),
            write_timeout: Duration::from_secs(10),
        }
    }
}

/// The stack of a connection's thread: it parses one head (httparse's
/// header array, 2 KiB) and formats small answers; the 2 MiB default would
/// reserve a gigabyte of address space at the connection cap.
const CONNECTION_STACK: usize = 64 * 1024;

/// What the accept loop and the connection threads share.
struct Shared {
    live: Arc<Live>,
    limits: Limits,
    /// Set when the server stops.
    stop: AtomicBool,
    /// Connections being served (each holds a [`Slot`]).
    active: AtomicUsize,
}

impl Shared {
    fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// One of the [`Limits::max_connections`] places; given back when dropped,
/// also when a connection's thread unwinds or fails to start.
struct Slot(Arc<Shared>);

impl Slot {
    /// A place, if the cap allows one more connection.
    fn take(shared: &Arc<Shared>) -> Option<Slot> {
        let max = shared.limits.max_connections;
        shared
            .active
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < max).then_some(n + 1)
            })
            .ok()
            .map(|_| Slot(shared.clone()))
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.active.fetch_sub(1, Ordering::AcqRel);
    }
}

/// A running server.
pub struct Server {
    /// The address it listens on (the real port when 0 was asked for).
    pub addr: SocketAddr,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Server {
    /// Starts serving `live` on `addr` with the default [`Limits`].
    pub fn start(addr: SocketAddr, live: Arc<Live>) -> anyhow::Result<Server> {
        Server::start_with(addr, live, Limits::default())
    }

    /// Starts serving `live` on `addr` within `limits`.
    pub fn start_with(addr: SocketAddr, live: Arc<Live>, limits: Limits) -> anyhow::Result<Server> {
        let listener = TcpListener::bind(addr)
            .map_err(|e| anyhow::anyhow!("--serve {addr}: cannot listen: {e}"))?;
        let addr = listener
            .local_addr()
            .map_err(|e| anyhow::anyhow!("--serve {addr}: {e}"))?;
        let shared = Arc::new(Shared {
            live,
            limits,
            stop: AtomicBool::new(false),
            active: AtomicUsize::new(0),
        });
        let thread = {
            let shared = shared.clone();
            std::thread::Builder::new()
                .name("watch-http".into())
                .spawn(move || accept(&listener, &shared))?
        };
        Ok(Server {
            addr,
            shared,
            thread: Some(thread),
        })
    }

    /// The connections being served now.
    pub fn connections(&self) -> usize {
        self.shared.active.load(Ordering::Acquire)
    }
}

impl Drop for Server {
    /// Stops accepting, ends every event stream and joins the accept loop
    /// (woken by a connection of its own). Connections being answered end
    /// on their own, within their timeouts.
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        self.shared.live.stop();
        let ip = match self.addr.ip() {
            IpAddr::V4(ip) if ip.is_unspecified() => IpAddr::V4(Ipv4Addr::LOCALHOST),
            IpAddr::V6(ip) if ip.is_unspecified() => IpAddr::V6(Ipv6Addr::LOCALHOST),
            ip => ip,
        };
        let wake = SocketAddr::new(ip, self.addr.port());
        let woken = TcpStream::connect_timeout(&wake, Duration::from_secs(1)).is_ok();
        if let Some(t) = self.thread.take() {
            // Unwoken, the loop ends at the next connection or with the process.
            if woken {
                let _ = t.join();
            }
        }
    }
}

/// The accept loop: hands each connection to a thread of its own, or, at
/// the cap, answers 503 without one. It never reads or blocks on a client.
fn accept(listener: &TcpListener, shared: &Arc<Shared>) {
    for conn in listener.incoming() {
        if shared.stopping() {
            return;
        }
        match conn {
            Ok(stream) => admit(stream, shared),
            // Out of file descriptors, or a connection reset before it was
            // accepted: wait a little rather than spin.
            Err(_) => std::thread::sleep(Duration::from_millis(10)),
        }
    }
}

/// Serves `stream` on a new thread if the cap allows, else refuses it.
fn admit(stream: TcpStream, shared: &Arc<Shared>) {
    let Some(slot) = Slot::take(shared) else {
        refuse_busy(stream);
        return;
    };
    let shared = shared.clone();
    // When the thread cannot start, the closure (the slot and the stream
    // with it) is dropped: the place is given back and the client closed.
    let _ = std::thread::Builder::new()
        .name("watch-http-conn".into())
        .stack_size(CONNECTION_STACK)
        .spawn(move || {
            let _slot = slot;
            connection::serve(stream, &shared);
        });
}

/// The 503 of a connection beyond the cap, written without blocking (it
/// fits a new socket's send buffer; if not, the client just sees the close).
fn refuse_busy(mut stream: TcpStream) {
    use std::io::Write;
    if stream.set_nonblocking(true).is_ok() {
        let _ = stream.write_all(&connection::busy_answer());
    }
    let _ = stream.shutdown(std::net::Shutdown::Write);
}

#[cfg(test)]
mod tests;
