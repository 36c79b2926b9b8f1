//! The `request` target: the live page's request parser
//! (`penumbra::watch::server::request`) on request heads as clients send
//! them, whole and in pieces as a connection reads them.

use penumbra::watch::server::request::{head_len, parse_request, Refusal, Request, MAX_TARGET};

use super::mutate::{self, Rng};
use super::seeds::Seed;
use super::targets::Target;

/// Heads a browser, curl and the tester's attacks send.
const SEEDS: &[&str] = &[
    "GET / HTTP/1.1\r\nHost: 127.0.0.1:8737\r\nConnection: keep-alive\r\nUser-Agent: Mozilla/5.0 (X11; Linux x86_64) Chrome/131.0\r\nAccept: text/html,application/xhtml+xml,*/*;q=0.8\r\nAccept-Encoding: gzip, deflate, br\r\nAccept-Language: en-GB,en;q=0.9\r\n\r\n",
    "GET /image.png?v=12 HTTP/1.1\r\nHost: localhost\r\nAccept: image/avif,image/webp,*/*\r\nReferer: http://localhost/\r\n\r\n",
    "GET /events HTTP/1.1\r\nHost: localhost\r\nAccept: text/event-stream\r\nCache-Control: no-cache\r\n\r\n",
    "HEAD /image.png HTTP/1.0\r\n\r\n",
    "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000000000\r\n\r\n",
    "PUT /events HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n5\r\nhello\r\n0\r\n\r\n",
    "GET /image.png HTTP/1.1\r\n\r\nGET /image.png HTTP/1.1\r\n\r\nGET / HTTP/1.1\r\n\r\n",
    "GET /../../etc/passwd HTTP/1.1\nHost: x\n\n",
];

/// The seeds of the target.
pub fn seeds() -> Vec<Seed> {
    SEEDS
        .iter()
        .enumerate()
        .map(|(i, s)| Seed {
            target: Target::Request,
            name: format!("request {i}"),
            data: s.as_bytes().to_vec(),
        })
        .collect()
}

/// A mutated head: on most cases one to four HTTP-aware changes (a header
/// with a value at an edge, a header repeated up to 100 times, a target
/// near [`MAX_TARGET`], another method or version, line ends changed), on a
/// third byte-level ones as well.
pub fn mutate(seed: &[u8], donors: &[Vec<u8>], rng: &mut Rng) -> Vec<u8> {
    let mut text = String::from_utf8_lossy(seed).into_owned();
    for _ in 0..1 + rng.below(4) {
        match rng.below(6) {
            0 => {
                let name = *rng.pick(&[
                    "Content-Length",
                    "content-length",
                    "Transfer-Encoding",
                    "Host",
                    "Cookie",
                    "X",
                ]);
                let value = rng
                    .pick(&[
                        "0".to_string(),
                        "1".to_string(),
                        "-1".to_string(),
                        "18446744073709551616".to_string(),
                        "9".repeat(400),
                        "chunked".to_string(),
                        " 0 ".to_string(),
                        "1, 1".to_string(),
                        "\u{e9}\u{1F600}".to_string(),
                        "c".repeat(20_000),
                    ])
                    .clone();
                insert_line(&mut text, &format!("{name}: {value}"), rng);
            }
            1 => {
                let line = format!("X-{}: {}", rng.below(100), rng.below(1000));
                for _ in 0..1 + rng.below(100) {
                    insert_line(&mut text, &line, rng);
                }
            }
            2 => {
                let n = MAX_TARGET - 2 + rng.below(5);
                let target = format!("/{}", "a".repeat(n));
                text = text.replacen('/', &target, 1);
            }
            3 => {
                let method = *rng.pick(&[
                    "GET", "HEAD", "POST", "get", "CONNECT", "G\u{e9}T", "", "GET GET",
                ]);
                let rest = text.split_once(' ').map_or("", |(_, r)| r).to_string();
                text = format!("{method} {rest}");
            }
            4 => {
                let version =
                    *rng.pick(&["HTTP/1.0", "HTTP/2", "HTTP/1.1 ", "http/1.1", "HTTP/1.10"]);
                text = text.replacen("HTTP/1.1", version, 1);
            }
            _ => {
                let (from, to) = *rng.pick(&[("\r\n", "\n"), ("\r\n", "\r"), ("\r\n\r\n", "\r\n")]);
                text = text.replacen(from, to, 1 + rng.below(4));
            }
        }
    }
    let mut data = text.into_bytes();
    if rng.one_in(3) {
        mutate::mutate_bytes(&mut data, donors, rng);
    }
    data
}

/// Inserts a header line after a random line of the head.
fn insert_line(text: &mut String, line: &str, rng: &mut Rng) {
    let ends: Vec<usize> = text.match_indices('\n').map(|(i, _)| i + 1).collect();
    let at = if ends.is_empty() {
        text.len()
    } else {
        *rng.pick(&ends)
    };
    text.insert_str(at, &format!("{line}\r\n"));
}

/// One case: the head delimited and parsed as a connection would, once
/// from the whole input and once from pieces of 1 to 2048 bytes as reads
/// return them; the two must decide alike (a difference panics, which the
/// harness reports). Ok when the request is served, Err with the refusal.
pub fn run(data: &[u8]) -> Result<(), String> {
    let whole = decide(head_len(data, 0), data);
    let mut buf = Vec::new();
    let mut pieced = None;
    let mut piece = 1;
    while pieced.is_none() && buf.len() < data.len() {
        let from = buf.len();
        let take = piece.min(data.len() - from);
        buf.extend_from_slice(&data[from..from + take]);
        piece = piece * 3 % 2047 + 1;
        match head_len(&buf, from) {
            Ok(None) => {}
            other => pieced = Some(decide(other, &buf)),
        }
    }
    let pieced = pieced.unwrap_or(None);
    let same = match (&whole, &pieced) {
        (Some(Ok(a)), Some(Ok(b))) => a == b,
        (Some(Err(_)), Some(Err(_))) | (None, None) => true,
        _ => false,
    };
    assert!(same, "whole: {whole:?}, in pieces: {pieced:?}");
    match whole {
        Some(Ok(_)) => Ok(()),
        Some(Err(r)) => Err(format!("{} {:?}", r.status().0, r)),
        None => Err("incomplete head".into()),
    }
}

/// What a connection does with a head search's result on `buf`.
fn decide(found: Result<Option<usize>, Refusal>, buf: &[u8]) -> Option<Result<Request, Refusal>> {
    match found {
        Ok(Some(len)) => Some(parse_request(&buf[..len])),
        Ok(None) => None,
        Err(r) => Some(Err(r)),
    }
}
