//! Load on the live page (`watch --serve`, issue 36), on loopback only and
//! bounded in count and time: a server started here on 127.0.0.1:0 with a
//! `Live` (no device: a small PNG, then an "edit"), 300 concurrent
//! `/events` clients, and the hostile ones — a client that pipelines 3,000
//! `GET /image.png` and never reads, a slow-headers client (one byte every
//! 500 ms), a `POST` with `Content-Length: 1000000000000` — while a probe
//! client fetches `/` and `/image.png` every 50 ms. It measures the probe's
//! latency (each must be answered within 100 ms), the process's threads
//! (`/proc/self/status`, and the server's by name) against the connection
//! cap, and that the edit reaches every `/events` client.
//!
//! ```sh
//! cargo run -p penumbra-tools --bin live_load             # docs/live_page.md
//! cargo run -p penumbra-tools --bin live_load -- --events 300 --seconds 15
//! ```
//!
//! Exits non-zero when a check fails.

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use clap::Parser;
use common::ms;
use common::stats::{median, percentile};
use penumbra::watch::server::{Limits, Live, Server};

/// The latency every probe must stay within.
const BOUND: Duration = Duration::from_millis(100);
/// The time between probes.
const PROBE_EVERY: Duration = Duration::from_millis(50);
/// What an `/events` client sees once the edit's image is announced.
const EDIT_MARKER: &[u8] = b"\"version\":2";
/// What it sees at connection (the first image).
const FIRST_MARKER: &[u8] = b"\"version\":1";

#[derive(Parser)]
#[command(about = "Load on the live page's server, on loopback")]
struct Args {
    /// Concurrent `/events` clients (at most 450: the cap is 512 connections).
    #[arg(long, default_value_t = 300, value_parser = clap::value_parser!(u32).range(1..=450))]
    events: u32,
    /// The length of the run in seconds (at least 12, so the slow-headers
    /// client meets the 10 s head deadline; at most 60).
    #[arg(long, default_value_t = 15, value_parser = clap::value_parser!(u64).range(12..=60))]
    seconds: u64,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let limits = Limits::default();
    let live = Arc::new(Live::default());
    live.set_image(png(0)?);
    live.set_status(None, "reload 0: the first image".into());
    let server = Server::start(SocketAddr::from(([127, 0, 0, 1], 0)), live.clone())?;
    let addr = server.addr;
    let cpu = common::machine::CpuInfo::read();
    println!(
        "live_load: {} /events clients for {} s on {addr} (the server's limits: {} connections, head {} s, write {} s)",
        args.events,
        args.seconds,
        limits.max_connections,
        limits.head_timeout.as_secs(),
        limits.write_timeout.as_secs()
    );
    println!("cpu: {}, {} processors", cpu.describe(), processors());
    println!(
        "at: {}, commit {}",
        common::machine::utc_now(),
        common::machine::git_commit(&common::repo_root())
    );

    // The event streams, read by one thread that polls them all.
    let t_connect = Instant::now();
    let mut streams = Vec::new();
    for _ in 0..args.events {
        let mut s = TcpStream::connect(addr)?;
        s.write_all(
            b"GET /events HTTP/1.1\r\nHost: localhost\r\nAccept: text/event-stream\r\n\r\n",
        )?;
        s.set_nonblocking(true)?;
        streams.push(s);
    }
    let done = Arc::new(AtomicBool::new(false));
    let reader = {
        let done = done.clone();
        std::thread::spawn(move || read_events(streams, &done))
    };
    let mut threads = Threads::default();
    while threads.connected(&server) < args.events as usize {
        anyhow::ensure!(
            !reader.is_finished() && t_connect.elapsed() < Duration::from_secs(10),
            "the /events clients did not all connect"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    println!(
        "connect: {} /events connections served after {:.0} ms",
        args.events,
        ms(t_connect.elapsed())
    );

    // The hostile clients.
    let t0 = Instant::now();
    let mut hog = TcpStream::connect(addr)?;
    let pipelined = b"GET /image.png HTTP/1.1\r\nHost: x\r\n\r\n".repeat(3000);
    hog.set_write_timeout(Some(Duration::from_secs(2)))?;
    let hog_sent = match hog.write_all(&pipelined) {
        Ok(()) => pipelined.len(),
        Err(_) => 0,
    };
    println!(
        "hostile: a client pipelined 3000 GET /image.png ({} bytes sent) and never reads",
        hog_sent
    );
    let slow = std::thread::spawn(move || slow_headers(addr));
    let huge = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(1));
        huge_body(addr)
    });

    // The probes, the edit half-way, the thread count all along.
    let run = Duration::from_secs(args.seconds);
    let mut latencies = (Vec::new(), Vec::new());
    let mut failures = Vec::new();
    let mut edit_at = None;
    while t0.elapsed() < run {
        let tick = Instant::now();
        if edit_at.is_none() && t0.elapsed() >= run / 2 {
            live.set_image(png(1)?);
            live.set_status(None, "reload 1: an edit".into());
            edit_at = Some((Instant::now(), t0.elapsed()));
        }
        for (path, lat) in [("/", &mut latencies.0), ("/image.png", &mut latencies.1)] {
            match probe(addr, path) {
                Ok(d) => lat.push(ms(d)),
                Err(e) => failures.push(format!(
                    "{path} at {:.1} s: {e}",
                    t0.elapsed().as_secs_f64()
                )),
            }
        }
        threads.sample(&server);
        std::thread::sleep(PROBE_EVERY.saturating_sub(tick.elapsed()));
    }
    let huge = huge
        .join()
        .map_err(|_| anyhow::anyhow!("the huge-body client panicked"))??;
    let slow = slow
        .join()
        .map_err(|_| anyhow::anyhow!("the slow client panicked"))??;
    println!(
        "hostile: POST with Content-Length: 1000000000000 answered `{}` in {:.1} ms",
        huge.0,
        ms(huge.1)
    );
    println!(
        "hostile: slow headers (one byte every 500 ms) answered `{}` after {:.1} s",
        slow.0,
        slow.1.as_secs_f64()
    );

    // Let the streams take in the last events, then stop reading.
    std::thread::sleep(Duration::from_millis(200));
    done.store(true, Ordering::Relaxed);
    let seen = reader
        .join()
        .map_err(|_| anyhow::anyhow!("the event reader panicked"))?;
    drop(hog);

    let all: Vec<f64> = latencies.0.iter().chain(&latencies.1).copied().collect();
    let over = all.iter().filter(|&&l| l > ms(BOUND)).count();
    println!(
        "probes: {} GET / and {} GET /image.png, all 200 with their whole body: {} failed; latency median {:.2} ms, p99 {:.2} ms, max {:.2} ms; over {} ms: {over}",
        latencies.0.len(),
        latencies.1.len(),
        failures.len(),
        median(&all),
        percentile(&all, 99.0),
        all.iter().copied().fold(0.0, f64::max),
        BOUND.as_millis()
    );
    for f in &failures {
        println!("  failed: {f}");
    }
    let (edit_instant, edit_time) = edit_at.ok_or_else(|| anyhow::anyhow!("no edit was made"))?;
    let first = seen.iter().filter(|c| c.first).count();
    let delays: Vec<f64> = seen
        .iter()
        .filter_map(|c| {
            c.edit
                .map(|t| ms(t.saturating_duration_since(edit_instant)))
        })
        .collect();
    println!(
        "edit at {:.1} s: {} of {} /events clients had the first frame, {} of {} got the edit's, within {:.1} ms (median {:.1} ms)",
        edit_time.as_secs_f64(),
        first,
        seen.len(),
        delays.len(),
        seen.len(),
        delays.iter().copied().fold(0.0, f64::max),
        median(&delays)
    );
    println!(
        "threads: process at most {} (/proc/self/status), of which the server's at most {} (accept loop and one per connection; the cap: {} connections); connections at most {}",
        threads.process_max,
        threads.server_max,
        limits.max_connections,
        threads.connections_max
    );
    drop(server);

    let mut failed = Vec::new();
    if over > 0 || !failures.is_empty() || all.is_empty() {
        failed.push("a probe was not answered within 100 ms");
    }
    if delays.len() != seen.len() || first != seen.len() {
        failed.push("an /events client missed a frame");
    }
    if threads.server_max > limits.max_connections {
        failed.push("more server threads than the cap");
    }
    if !huge.0.starts_with("HTTP/1.1 413") || huge.1 > BOUND {
        failed.push("the huge body was not refused at once");
    }
    if !slow.0.starts_with("HTTP/1.1 408") {
        failed.push("the slow-headers client was not timed out");
    }
    if failed.is_empty() {
        println!("result: every check passed");
        Ok(())
    } else {
        anyhow::bail!("{}", failed.join("; "))
    }
}

/// A 64×48 PNG, different for each `n`.
fn png(n: u8) -> anyhow::Result<Vec<u8>> {
    let img = image::RgbImage::from_fn(64, 48, |x, y| {
        image::Rgb([(x * 4) as u8, (y * 5) as u8, n.wrapping_mul(200)])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)?;
    Ok(out.into_inner())
}

fn processors() -> usize {
    std::thread::available_parallelism().map_or(0, |n| n.get())
}

/// One GET on a new connection, read to the end: the time to the whole
/// answer, checked to be a 200 with the body its `Content-Length` says.
fn probe(addr: SocketAddr, path: &str) -> anyhow::Result<Duration> {
    let t = Instant::now();
    let mut s = TcpStream::connect_timeout(&addr, Duration::from_secs(2))?;
    s.set_read_timeout(Some(Duration::from_secs(2)))?;
    write!(s, "GET {path} HTTP/1.1\r\nHost: localhost\r\n\r\n")?;
    let mut all = Vec::new();
    s.read_to_end(&mut all)?;
    let d = t.elapsed();
    let text = String::from_utf8_lossy(&all);
    let (head, _) = text
        .split_once("\r\n\r\n")
        .ok_or_else(|| anyhow::anyhow!("no complete answer"))?;
    anyhow::ensure!(
        head.starts_with("HTTP/1.1 200 "),
        "{}",
        head.lines().next().unwrap_or("")
    );
    let len: usize = head
        .lines()
        .find_map(|l| l.strip_prefix("Content-Length: "))
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| anyhow::anyhow!("no Content-Length"))?;
    let body = all.len() - (head.len() + 4);
    anyhow::ensure!(body == len, "{body} of {len} bytes");
    Ok(d)
}

/// The slow-headers client: a request line, then one header byte every
/// 500 ms; returns the server's first line and when it came.
fn slow_headers(addr: SocketAddr) -> anyhow::Result<(String, Duration)> {
    let t = Instant::now();
    let mut s = TcpStream::connect(addr)?;
    s.write_all(b"GET / HTTP/1.1\r\nX-Slow: ")?;
    s.set_read_timeout(Some(Duration::from_millis(500)))?;
    let mut buf = [0u8; 512];
    while t.elapsed() < Duration::from_secs(30) {
        match s.read(&mut buf) {
            Ok(n) => {
                let text = String::from_utf8_lossy(&buf[..n]);
                return Ok((
                    text.lines().next().unwrap_or("(closed)").to_string(),
                    t.elapsed(),
                ));
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                if s.write_all(b"a").is_err() {
                    return Ok(("(closed while sending)".into(), t.elapsed()));
                }
            }
            Err(e) => return Ok((format!("({e})"), t.elapsed())),
        }
    }
    Ok(("(no answer in 30 s)".into(), t.elapsed()))
}

/// The tester's request: a POST announcing a terabyte; returns the first
/// line of the answer and its latency.
fn huge_body(addr: SocketAddr) -> anyhow::Result<(String, Duration)> {
    let t = Instant::now();
    let mut s = TcpStream::connect(addr)?;
    s.set_read_timeout(Some(Duration::from_secs(5)))?;
    s.write_all(b"POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000000000\r\n\r\nfirst bytes of the body")?;
    let mut buf = [0u8; 512];
    let n = s.read(&mut buf)?;
    let d = t.elapsed();
    let text = String::from_utf8_lossy(&buf[..n]);
    Ok((text.lines().next().unwrap_or("(closed)").to_string(), d))
}

/// What one `/events` client saw.
#[derive(Clone, Copy, Default)]
struct Seen {
    /// It had the first image's frame.
    first: bool,
    /// When it had the edit's frame.
    edit: Option<Instant>,
}

/// Reads every event stream (non-blocking, woken by `poll`) until `done`.
fn read_events(mut streams: Vec<TcpStream>, done: &AtomicBool) -> Vec<Seen> {
    let mut seen = vec![Seen::default(); streams.len()];
    let mut tails = vec![Vec::<u8>::new(); streams.len()];
    let mut buf = [0u8; 4096];
    while !done.load(Ordering::Relaxed) {
        let mut fds: Vec<libc::pollfd> = streams
            .iter()
            .map(|s| libc::pollfd {
                fd: s.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            })
            .collect();
        // SAFETY: `fds` is a valid array of `fds.len()` pollfd structures.
        let ready = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, 50) };
        if ready <= 0 {
            continue;
        }
        for (i, fd) in fds.iter().enumerate() {
            if fd.revents == 0 {
                continue;
            }
            loop {
                match streams[i].read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        let tail = &mut tails[i];
                        tail.extend_from_slice(&buf[..n]);
                        if contains(tail, FIRST_MARKER) {
                            seen[i].first = true;
                        }
                        if seen[i].edit.is_none() && contains(tail, EDIT_MARKER) {
                            seen[i].edit = Some(Instant::now());
                        }
                        // Keep enough to find a marker split across reads.
                        let keep = tail.len().saturating_sub(64);
                        tail.drain(..keep);
                    }
                }
            }
        }
    }
    drop(streams.drain(..));
    seen
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

/// The largest thread and connection counts seen.
#[derive(Default)]
struct Threads {
    process_max: usize,
    server_max: usize,
    connections_max: usize,
}

impl Threads {
    /// Samples the counts; returns the connections now.
    fn sample(&mut self, server: &Server) {
        self.process_max = self.process_max.max(process_threads());
        self.server_max = self.server_max.max(server_threads());
        self.connections_max = self.connections_max.max(server.connections());
    }

    fn connected(&mut self, server: &Server) -> usize {
        self.sample(server);
        server.connections()
    }
}

/// `Threads:` of /proc/self/status.
fn process_threads() -> usize {
    std::fs::read_to_string("/proc/self/status")
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(0)
}

/// The server's threads: those named `watch-http…` (/proc/self/task/*/comm).
fn server_threads() -> usize {
    std::fs::read_dir("/proc/self/task")
        .into_iter()
        .flatten()
        .flatten()
        .filter(|t| {
            std::fs::read_to_string(t.path().join("comm"))
                .is_ok_and(|c| c.starts_with("watch-http"))
        })
        .count()
}
