//! One connection of the live page, on a thread of its own: read one
//! request head within a deadline, answer it, close. Only `/events` stays
//! open, streaming. Every write has the server's write timeout, so a client
//! that does not read stalls only its own thread, and only for that long.

use std::io::{ErrorKind, Read, Write};
use std::net::{Shutdown, TcpStream};
use std::time::{Duration, Instant};

use super::request::{head_len, parse_request, Method, Refusal, Request, Route};
use super::{Live, Shared};

/// How long a closing connection waits for the client to finish sending
/// (so that it sees the answer, not a reset) ...
const LINGER_TIME: Duration = Duration::from_millis(500);
/// ... and the most bytes it discards meanwhile.
const LINGER_BYTES: usize = 64 * 1024;

/// The time between keep-alive comments on an idle event stream.
const KEEP_ALIVE: Duration = Duration::from_secs(15);

/// Serves one connection to its end.
pub(super) fn serve(mut stream: TcpStream, shared: &Shared) {
    let _ = stream.set_nodelay(true);
    if stream
        .set_write_timeout(Some(shared.limits.write_timeout))
        .is_err()
    {
        return;
    }
    let answer = match read_head(&mut stream, shared.limits.head_timeout) {
        Ok(head) => parse_request(&head),
        Err(Some(refusal)) => Err(refusal),
        Err(None) => return, // gone, or a read error
    };
    match answer {
        Ok(Request {
            method: Method::Get,
            route: Route::Events,
        }) => stream_events(&mut stream, &shared.live, shared),
        Ok(req) => {
            let _ = respond(&mut stream, req, &shared.live);
            close(stream);
        }
        Err(refusal) => {
            let _ = refuse(&mut stream, refusal);
            close(stream);
        }
    }
}

/// Reads one request head: at most [`super::request::MAX_HEAD`] bytes (plus
/// one read's worth that is ignored), all of it before `timeout` has passed.
/// Bytes after the head (a body, pipelined requests) are never looked at.
/// `Err(None)`: the client went away or the read failed.
fn read_head(stream: &mut TcpStream, timeout: Duration) -> Result<Vec<u8>, Option<Refusal>> {
    let deadline = Instant::now() + timeout;
    let mut buf = Vec::with_capacity(1024);
    let mut chunk = [0u8; 2048];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(Some(Refusal::Timeout));
        }
        stream.set_read_timeout(Some(left)).map_err(|_| None)?;
        let n = match stream.read(&mut chunk) {
            Ok(0) => return Err(None),
            Ok(n) => n,
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                return Err(Some(Refusal::Timeout))
            }
            Err(_) => return Err(None),
        };
        let from = buf.len();
        buf.extend_from_slice(&chunk[..n]);
        if let Some(len) = head_len(&buf, from)? {
            buf.truncate(len);
            return Ok(buf);
        }
    }
}

/// Answers a request for the page or the image (`HEAD`: the same headers,
/// no body); the image is 404 until there is one.
fn respond(stream: &mut TcpStream, req: Request, live: &Live) -> std::io::Result<()> {
    let png;
    let answer = match req.route {
        Route::Page => Answer::ok("text/html; charset=utf-8", super::page::PAGE.as_bytes()),
        Route::Image => {
            png = live.snapshot().png;
            if png.is_empty() {
                Answer {
                    code: 404,
                    reason: "Not Found",
                    content_type: TEXT,
                    body: b"no image yet\n",
                    extra: "",
                }
            } else {
                Answer::ok("image/png", &png)
            }
        }
        Route::Events => {
            // `HEAD /events`: the stream's headers, no stream.
            let head = events_head();
            return stream
                .write_all(head.as_bytes())
                .and_then(|_| stream.flush());
        }
    };
    answer.write(stream, req.method)
}

/// Answers a refusal with its status and small fixed body.
fn refuse(stream: &mut TcpStream, refusal: Refusal) -> std::io::Result<()> {
    Answer::refusal(refusal).write(stream, Method::Get)
}

/// The fixed answer of a connection that is refused before it is served
/// (the accept loop's cap): small enough for a new socket's send buffer.
pub(super) fn busy_answer() -> Vec<u8> {
    let answer = Answer::refusal(Refusal::Busy);
    let mut out = answer.head().into_bytes();
    out.extend_from_slice(answer.body);
    out
}

/// The content type of every refusal.
const TEXT: &str = "text/plain; charset=utf-8";

/// One answer; every answer closes its connection.
struct Answer<'a> {
    code: u16,
    reason: &'static str,
    content_type: &'static str,
    body: &'a [u8],
    /// Header lines beyond the usual ones, each ending in `\r\n`.
    extra: &'static str,
}

impl<'a> Answer<'a> {
    /// A 200 with `body`.
    fn ok(content_type: &'static str, body: &'a [u8]) -> Answer<'a> {
        Answer {
            code: 200,
            reason: "OK",
            content_type,
            body,
            extra: "",
        }
    }

    /// The answer to a refusal (a 405 names the methods allowed).
    fn refusal(refusal: Refusal) -> Answer<'static> {
        let (code, reason, body) = refusal.status();
        Answer {
            code,
            reason,
            content_type: TEXT,
            body: body.as_bytes(),
            extra: if refusal == Refusal::Method {
                "Allow: GET, HEAD\r\n"
            } else {
                ""
            },
        }
    }

    /// The status line and headers.
    fn head(&self) -> String {
        format!(
            "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\n\
             Cache-Control: no-store\r\nConnection: close\r\n{}\r\n",
            self.code,
            self.reason,
            self.content_type,
            self.body.len(),
            self.extra
        )
    }

    /// Writes the head and, for `GET`, the body.
    fn write(&self, stream: &mut TcpStream, method: Method) -> std::io::Result<()> {
        stream.write_all(self.head().as_bytes())?;
        if method == Method::Get {
            stream.write_all(self.body)?;
        }
        stream.flush()
    }
}

/// The head of an event stream (no length: it ends when the connection does).
fn events_head() -> &'static str {
    "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n"
}

/// Closes a connection after its answer: ends the sending side, then
/// discards what the client still sends for a moment (bounded in bytes and
/// time), so that closing with unread bytes does not reset the connection
/// before the client has read the answer.
fn close(mut stream: TcpStream) {
    if stream.shutdown(Shutdown::Write).is_err() {
        return;
    }
    let deadline = Instant::now() + LINGER_TIME;
    let mut chunk = [0u8; 2048];
    let mut discarded = 0;
    while discarded < LINGER_BYTES {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return;
        }
        match stream.read(&mut chunk) {
            Ok(0) => return,
            Ok(n) => discarded += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(_) => return,
        }
    }
}

/// One server-sent event stream: a `frame` event at once and after every
/// change, a keep-alive comment when idle; ends when the client goes away
/// (or does not read within the write timeout) or the server stops.
fn stream_events(stream: &mut TcpStream, live: &Live, shared: &Shared) {
    if stream
        .write_all(events_head().as_bytes())
        .and_then(|_| stream.flush())
        .is_err()
    {
        return;
    }
    let mut state = live.snapshot();
    loop {
        if state.stopped || shared.stopping() {
            return;
        }
        let data = serde_json::json!({
            "version": state.image_version,
            "error": state.error,
            "line": state.line,
        });
        let msg = format!("event: frame\ndata: {data}\n\n");
        if stream
            .write_all(msg.as_bytes())
            .and_then(|_| stream.flush())
            .is_err()
        {
            return;
        }
        let seen = state.version;
        loop {
            state = live.wait_change(seen, KEEP_ALIVE);
            if state.version != seen || state.stopped {
                break;
            }
            // A comment line keeps proxies and the client's idle timer happy
            // and notices a client that went away.
            if stream
                .write_all(b": keep-alive\n\n")
                .and_then(|_| stream.flush())
                .is_err()
            {
                return;
            }
        }
    }
}
