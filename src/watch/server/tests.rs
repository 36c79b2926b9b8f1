//! The server through real sockets on 127.0.0.1: what a client sends can
//! refuse, time out or stall only that client (issue 36).

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use super::*;

/// A server on a free loopback port.
fn serve(limits: Limits) -> (Server, Arc<Live>) {
    let live = Arc::new(Live::default());
    let addr = SocketAddr::from(([127, 0, 0, 1], 0));
    let server = Server::start_with(addr, live.clone(), limits).unwrap();
    (server, live)
}

fn connect(server: &Server) -> TcpStream {
    let s = TcpStream::connect(server.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    s
}

/// Sends `request` on a new connection and reads until the server closes
/// it: the whole answer, and how long it took.
fn exchange(server: &Server, request: &[u8]) -> (String, Vec<u8>, Duration) {
    let t0 = Instant::now();
    let mut s = connect(server);
    s.write_all(request).unwrap();
    let (head, body) = read_answer(&mut s);
    (head, body, t0.elapsed())
}

/// Reads to the end of the connection: the head (as text) and the body.
fn read_answer(s: &mut TcpStream) -> (String, Vec<u8>) {
    let mut all = Vec::new();
    let _ = s.read_to_end(&mut all);
    let split = all
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .map_or(all.len(), |p| p + 4);
    let body = all.split_off(split);
    (String::from_utf8_lossy(&all).into_owned(), body)
}

/// Waits (up to 5 s) until `pred` holds.
fn eventually(what: &str, mut pred: impl FnMut() -> bool) {
    let end = Instant::now() + Duration::from_secs(5);
    while !pred() {
        assert!(Instant::now() < end, "never: {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

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
fn get_and_head_on_the_routes() {
    let (server, live) = serve(Limits::default());
    let (head, body, _) = exchange(&server, b"GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 200 OK\r\n"), "{head}");
    assert!(head.contains("Content-Type: text/html"), "{head}");
    assert_eq!(body, page::PAGE.as_bytes());

    let (head, body, _) = exchange(&server, b"GET /image.png HTTP/1.1\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 404 "), "no image yet: {head}");
    assert_eq!(body, b"no image yet\n");

    live.set_image(b"\x89PNG not really".to_vec());
    let (head, body, _) = exchange(&server, b"GET /image.png?v=1 HTTP/1.1\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 200 OK\r\n"), "{head}");
    assert!(head.contains("Content-Type: image/png"), "{head}");
    assert_eq!(body, b"\x89PNG not really");

    let (head, body, _) = exchange(&server, b"HEAD /image.png HTTP/1.1\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 200 OK\r\n"), "{head}");
    assert!(head.contains("Content-Length: 15\r\n"), "{head}");
    assert!(body.is_empty(), "HEAD has no body");
    let (head, body, _) = exchange(&server, b"HEAD / HTTP/1.0\r\n\r\n");
    assert!(head.contains(&format!("Content-Length: {}\r\n", page::PAGE.len())));
    assert!(body.is_empty());
}

#[test]
fn other_paths_and_methods_get_small_fixed_answers() {
    let (server, _live) = serve(Limits::default());
    for (request, status) in [
        (&b"GET /etc/passwd HTTP/1.1\r\n\r\n"[..], "404"),
        (b"GET /../../Cargo.toml HTTP/1.1\r\n\r\n", "404"),
        (b"DELETE / HTTP/1.1\r\n\r\n", "405"),
        (b"OPTIONS * HTTP/1.1\r\n\r\n", "405"),
        (b"GET / HTTP/9.9\r\n\r\n", "400"),
        (
            b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03\r\n\r\n",
            "400",
        ),
    ] {
        let (head, body, _) = exchange(&server, request);
        let want = format!("HTTP/1.1 {status} ");
        assert!(head.starts_with(&want), "{request:?}: {head}");
        assert!(body.len() < 64, "{request:?}: a small body");
        if status == "405" {
            assert!(head.contains("Allow: GET, HEAD\r\n"), "{head}");
        }
    }
}

#[test]
fn a_huge_body_is_refused_at_once_without_being_read() {
    let (server, _live) = serve(Limits::default());
    // The tester's request (tiny_http aborted the process on it), with the
    // first bytes of a body that will never come in full.
    let (head, _, time) = exchange(
        &server,
        b"POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000000000\r\n\r\nabcd",
    );
    assert!(head.starts_with("HTTP/1.1 413 "), "{head}");
    assert!(time < Duration::from_secs(1), "{time:?}");
    let (head, _, _) = exchange(
        &server,
        b"GET / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\nffffffff\r\n",
    );
    assert!(head.starts_with("HTTP/1.1 413 "), "{head}");
    // Still serving.
    let (head, _, _) = exchange(&server, b"GET / HTTP/1.1\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 200 "), "{head}");
}

#[test]
fn a_client_that_does_not_read_stalls_only_itself() {
    let (server, live) = serve(Limits::default());
    // An image larger than the socket buffers, so that answers to a client
    // that does not read block.
    let png: Vec<u8> = (0..4 << 20)
        .map(|i: u32| (i * 7 + i / 4096) as u8)
        .collect();
    live.set_image(png.clone());
    let mut hog = connect(&server);
    let pipelined = b"GET /image.png HTTP/1.1\r\nHost: x\r\n\r\n".repeat(3000);
    hog.write_all(&pipelined).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    for _ in 0..3 {
        let (head, body, time) = exchange(&server, b"GET /image.png HTTP/1.1\r\n\r\n");
        assert!(head.starts_with("HTTP/1.1 200 "), "{head}");
        assert!(body == png, "the whole image");
        assert!(time < Duration::from_secs(1), "{time:?}");
    }
    drop(hog);
}

#[test]
fn pipelined_requests_get_one_answer_and_the_close() {
    let (server, _live) = serve(Limits::default());
    let (head, body, _) = exchange(
        &server,
        b"GET /image.png HTTP/1.1\r\n\r\nGET / HTTP/1.1\r\n\r\nGET / HTTP/1.1\r\n\r\n",
    );
    assert!(head.starts_with("HTTP/1.1 404 "), "{head}");
    assert!(head.contains("Connection: close\r\n"), "{head}");
    assert_eq!(body, b"no image yet\n", "one answer, then the end");
}

#[test]
fn slow_headers_time_out() {
    let limits = Limits {
        head_timeout: Duration::from_millis(300),
        ..Limits::default()
    };
    let (server, _live) = serve(limits);
    let t0 = Instant::now();
    let mut s = connect(&server);
    s.write_all(b"GET / HTTP/1.1\r\n").unwrap();
    // One byte of a header every 50 ms: each read is quick, the head never ends.
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(50));
        if s.write_all(b"X").is_err() {
            break;
        }
    }
    let (head, _) = read_answer(&mut s);
    assert!(head.starts_with("HTTP/1.1 408 "), "{head}");
    let time = t0.elapsed();
    assert!(time < Duration::from_millis(1500), "{time:?}");
    eventually("the connection's place is given back", || {
        server.connections() == 0
    });
}

#[test]
fn long_targets_and_large_heads_are_refused() {
    let (server, _live) = serve(Limits::default());
    let long = format!("GET /{} HTTP/1.1\r\n\r\n", "a".repeat(request::MAX_TARGET));
    let (head, _, _) = exchange(&server, long.as_bytes());
    assert!(head.starts_with("HTTP/1.1 414 "), "{head}");
    // A request line that never ends is refused once it cannot fit.
    let (head, _, _) = exchange(&server, "G".repeat(64 * 1024).as_bytes());
    assert!(head.starts_with("HTTP/1.1 414 "), "{head}");

    let many: String = (0..100).map(|i| format!("X-{i}: 1\r\n")).collect();
    let (head, _, _) = exchange(&server, format!("GET / HTTP/1.1\r\n{many}\r\n").as_bytes());
    assert!(head.starts_with("HTTP/1.1 431 "), "{head}");
    // Headers that never end: refused at the bound, not read on.
    let mut endless = b"GET / HTTP/1.1\r\nCookie: ".to_vec();
    endless.resize(1 << 20, b'c');
    let mut s = connect(&server);
    let _ = s.write_all(&endless); // the server may close before all is sent
    let (head, _) = read_answer(&mut s);
    assert!(
        head.is_empty() || head.starts_with("HTTP/1.1 431 "),
        "{head}"
    );
    let (head, _, _) = exchange(&server, b"GET / HTTP/1.1\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 200 "), "{head}");
}

#[test]
fn connections_beyond_the_cap_are_refused_without_a_thread() {
    let limits = Limits {
        max_connections: 3,
        ..Limits::default()
    };
    let (server, _live) = serve(limits);
    // Three clients that send nothing hold the three places.
    let idle: Vec<TcpStream> = (0..3).map(|_| connect(&server)).collect();
    eventually("three connections", || server.connections() == 3);
    let (head, body, time) = exchange(&server, b"");
    assert!(head.starts_with("HTTP/1.1 503 "), "{head}");
    assert_eq!(body, b"too many connections\n");
    assert!(time < Duration::from_secs(1), "{time:?}");
    assert_eq!(server.connections(), 3);
    drop(idle);
    eventually("the places given back", || server.connections() == 0);
    let (head, _, _) = exchange(&server, b"GET / HTTP/1.1\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 200 "), "{head}");
}

/// Reads from an event stream until `want` has arrived.
fn read_until(s: &mut TcpStream, seen: &mut String, want: &str) {
    let mut chunk = [0u8; 4096];
    while !seen.contains(want) {
        let n = s.read(&mut chunk).unwrap();
        assert!(n > 0, "the stream ended before {want:?}: {seen}");
        seen.push_str(&String::from_utf8_lossy(&chunk[..n]));
    }
}

#[test]
fn events_stream_each_change_and_end_when_the_server_stops() {
    let (server, live) = serve(Limits::default());
    let mut s = connect(&server);
    s.write_all(b"GET /events HTTP/1.1\r\nAccept: text/event-stream\r\n\r\n")
        .unwrap();
    let mut seen = String::new();
    read_until(&mut s, &mut seen, "\"version\":0");
    assert!(seen.starts_with("HTTP/1.1 200 OK\r\n"), "{seen}");
    assert!(
        seen.contains("Content-Type: text/event-stream\r\n"),
        "{seen}"
    );
    live.set_image(vec![1, 2, 3]);
    live.set_status(Some("oops".into()), "reload 1".into());
    read_until(&mut s, &mut seen, "\"error\":\"oops\"");
    assert!(seen.contains("event: frame\ndata: {"), "{seen}");
    assert!(seen.contains("\"version\":1"), "{seen}");

    let (head, body, _) = exchange(&server, b"HEAD /events HTTP/1.1\r\n\r\n");
    assert!(head.contains("text/event-stream"), "{head}");
    assert!(body.is_empty(), "no stream for HEAD");

    drop(server);
    let mut rest = Vec::new();
    s.read_to_end(&mut rest).unwrap();
}

#[test]
fn garbage_never_takes_the_server_down() {
    let (server, _live) = serve(Limits::default());
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    for i in 0..200 {
        let len = 1 + i * 37 % 3000;
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                // Mostly printable, with line ends, so the parser is reached.
                match x % 16 {
                    0 => b'\n',
                    1 => b'\r',
                    2 => (x >> 8) as u8,
                    _ => b' ' + (x >> 8) as u8 % 95,
                }
            })
            .collect();
        let mut s = connect(&server);
        let _ = s.write_all(&bytes);
        let _ = s.write_all(b"\r\n\r\n");
        let (head, _) = read_answer(&mut s);
        assert!(
            head.is_empty() || head.starts_with("HTTP/1.1 4"),
            "{i}: {head}"
        );
    }
    let (head, _, _) = exchange(&server, b"GET / HTTP/1.1\r\n\r\n");
    assert!(head.starts_with("HTTP/1.1 200 "), "{head}");
}
