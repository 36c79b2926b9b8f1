//! The live preview page (`--serve`): a small HTTP server (tiny_http) with
//! three routes:
//!
//! * `/` — the page: the latest image, the current error drawn over it, and
//!   the timing line of the last reload;
//! * `/image.png` — the latest image (PNG);
//! * `/events` — server-sent events: one `frame` event (JSON: `version`,
//!   `error`, `line`) at connection and after every change; the page swaps
//!   the image when `version` changes. No polling: the browser keeps this one
//!   connection open, and each client gets a thread of its own.

use std::io::Write;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
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

/// A running server.
pub struct Server {
    /// The address it listens on (the real port when 0 was asked for).
    pub addr: SocketAddr,
    server: Arc<tiny_http::Server>,
    thread: Option<JoinHandle<()>>,
    live: Arc<Live>,
}

impl Server {
    /// Starts serving `live` on `addr`.
    pub fn start(addr: SocketAddr, live: Arc<Live>) -> anyhow::Result<Server> {
        let server = Arc::new(
            tiny_http::Server::http(addr)
                .map_err(|e| anyhow::anyhow!("--serve {addr}: cannot listen: {e}"))?,
        );
        let addr = server
            .server_addr()
            .to_ip()
            .ok_or_else(|| anyhow::anyhow!("--serve {addr}: not an IP address"))?;
        let thread = {
            let server = server.clone();
            let live = live.clone();
            std::thread::Builder::new()
                .name("watch-http".into())
                .spawn(move || accept(&server, &live))?
        };
        Ok(Server {
            addr,
            server,
            thread: Some(thread),
            live,
        })
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.live.stop();
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn accept(server: &tiny_http::Server, live: &Arc<Live>) {
    let stopped = Arc::new(AtomicBool::new(false));
    for req in server.incoming_requests() {
        let path = req.url().split('?').next().unwrap_or("").to_string();
        let result = match (req.method(), path.as_str()) {
            (tiny_http::Method::Get, "/") => req.respond(
                tiny_http::Response::from_string(PAGE)
                    .with_header(header("Content-Type", "text/html; charset=utf-8")),
            ),
            (tiny_http::Method::Get, "/image.png") => {
                let png = live.snapshot().png;
                if png.is_empty() {
                    req.respond(
                        tiny_http::Response::from_string("no image yet").with_status_code(404),
                    )
                } else {
                    req.respond(
                        tiny_http::Response::from_data(png.as_slice())
                            .with_header(header("Content-Type", "image/png"))
                            .with_header(header("Cache-Control", "no-store")),
                    )
                }
            }
            (tiny_http::Method::Get, "/events") => {
                let live = live.clone();
                let stopped = stopped.clone();
                let _ = std::thread::Builder::new()
                    .name("watch-sse".into())
                    .spawn(move || stream_events(req.into_writer(), &live, &stopped));
                Ok(())
            }
            _ => req.respond(tiny_http::Response::from_string("not found").with_status_code(404)),
        };
        // A client that went away is not our problem.
        let _ = result;
    }
    stopped.store(true, Ordering::Relaxed);
}

fn header(name: &str, value: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("valid header")
}

/// One server-sent event stream; ends when the client goes away or the
/// server stops.
fn stream_events(mut w: Box<dyn Write + Send>, live: &Live, stopped: &AtomicBool) {
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n";
    if w.write_all(head.as_bytes())
        .and_then(|_| w.flush())
        .is_err()
    {
        return;
    }
    let mut state = live.snapshot();
    loop {
        if state.stopped || stopped.load(Ordering::Relaxed) {
            return;
        }
        let data = serde_json::json!({
            "version": state.image_version,
            "error": state.error,
            "line": state.line,
        });
        let msg = format!("event: frame\ndata: {data}\n\n");
        if w.write_all(msg.as_bytes()).and_then(|_| w.flush()).is_err() {
            return;
        }
        let seen = state.version;
        loop {
            state = live.wait_change(seen, Duration::from_secs(15));
            if state.version != seen || state.stopped {
                break;
            }
            // A comment line keeps proxies and the client's idle timer happy
            // and notices a client that went away.
            if w.write_all(b": keep-alive\n\n")
                .and_then(|_| w.flush())
                .is_err()
            {
                return;
            }
        }
    }
}

/// The page. The image is swapped only when a new one is complete, so the
/// page never shows a blank or half-loaded frame.
const PAGE: &str = r#"<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>penumbra watch</title>
<style>
  body { margin: 0; background: #111; color: #ddd; font: 14px/1.4 system-ui, sans-serif; }
  #view { position: relative; display: inline-block; }
  #image { display: block; max-width: 100vw; image-rendering: pixelated; }
  #error { position: absolute; left: 0; right: 0; top: 0; margin: 0; padding: 12px;
           background: rgba(110, 0, 0, 0.85); color: #fff; white-space: pre-wrap;
           font: 13px/1.35 ui-monospace, monospace; }
  #line { padding: 6px 10px; font: 12px/1.4 ui-monospace, monospace; color: #aaa; }
  #status { padding: 6px 10px; color: #888; }
</style>
</head>
<body>
<div id="view">
  <img id="image" alt="latest render">
  <pre id="error" hidden></pre>
</div>
<div id="line"></div>
<div id="status">connecting…</div>
<script>
  const image = document.getElementById('image');
  const error = document.getElementById('error');
  const line = document.getElementById('line');
  const status = document.getElementById('status');
  let shown = 0;
  const events = new EventSource('/events');
  events.addEventListener('open', () => { status.textContent = 'live'; });
  events.addEventListener('error', () => { status.textContent = 'disconnected; reconnecting…'; });
  events.addEventListener('frame', (e) => {
    const d = JSON.parse(e.data);
    if (d.version > 0 && d.version !== shown) {
      const next = new Image();
      // Loads can finish out of order: never go back to an older image.
      next.onload = () => {
        if (d.version > Number(image.dataset.version || 0)) {
          image.src = next.src;
          image.dataset.version = d.version;
        }
      };
      next.src = '/image.png?v=' + d.version;
      shown = d.version;
    }
    error.textContent = d.error || '';
    error.hidden = !d.error;
    line.textContent = d.line;
  });
</script>
</body>
</html>
"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses() {
        assert_eq!(
            parse_addr("127.0.0.1:8737").unwrap().to_string(),
            "127.0.0.1:8737"
        );
        assert_eq!(parse_addr("9000").unwrap().to_string(), "127.0.0.1:9000");
        assert_eq!(parse_addr(":9000").unwrap().to_string(), "127.0.0.1:9000");
        assert_eq!(parse_addr("0.0.0.0").unwrap().to_string(), "0.0.0.0:8737");
        assert_eq!(parse_addr("[::1]:80").unwrap().to_string(), "[::1]:80");
        assert!(parse_addr("not an address").is_err());
    }

    #[test]
    fn the_page_listens_and_does_not_poll() {
        assert!(PAGE.contains("new EventSource('/events')"));
        assert!(!PAGE.contains("setInterval") && !PAGE.contains("setTimeout"));
    }
}
