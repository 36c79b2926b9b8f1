//! The live page's request parser: a request head (request line and
//! headers, through the blank line) parsed with httparse into one of the
//! page's routes, or a [`Refusal`] with the status that answers it.
//!
//! Pure functions, no I/O: the connection reads at most [`MAX_HEAD`] bytes
//! and hands them here, so the bounds hold whatever a client sends. A
//! request that announces a body is refused from its headers alone; the
//! body is never read.

/// The most bytes a request head may have (request line and headers).
pub const MAX_HEAD: usize = 16 * 1024;
/// The most bytes a request target (path and query) may have.
pub const MAX_TARGET: usize = 2048;
/// The most headers a request may have.
pub const MAX_HEADERS: usize = 64;

/// The longest request line that can hold a target of [`MAX_TARGET`]
/// bytes: the method, the version, the spaces and the line end.
const MAX_REQUEST_LINE: usize = MAX_TARGET + 32;

/// The methods the page answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// `GET`: headers and body.
    Get,
    /// `HEAD`: the same headers, no body.
    Head,
}

/// The page's fixed routes (the query string is ignored).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// `/`: the page.
    Page,
    /// `/image.png`: the latest image.
    Image,
    /// `/events`: the server-sent event stream.
    Events,
}

/// A request the page answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// `GET` or `HEAD`.
    pub method: Method,
    /// Which route.
    pub route: Route,
}

/// Why a request gets no page: each has a status and a small fixed body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// Not HTTP/1.x, or a malformed request line, header or `Content-Length`.
    Malformed,
    /// A body was announced (`Content-Length` above 0, or `Transfer-Encoding`).
    Body,
    /// A method other than `GET` and `HEAD`.
    Method,
    /// A path that is none of the routes.
    NotFound,
    /// A request target longer than [`MAX_TARGET`].
    TargetTooLong,
    /// A head longer than [`MAX_HEAD`], or more than [`MAX_HEADERS`] headers.
    HeadTooLarge,
    /// The head did not arrive within the connection's time (not from the
    /// parser: the connection's read deadline).
    Timeout,
    /// The server has as many connections as it allows (not from the
    /// parser: the accept loop's cap).
    Busy,
}

impl Refusal {
    /// The status code, its reason phrase and the body sent with it.
    pub fn status(self) -> (u16, &'static str, &'static str) {
        match self {
            Refusal::Malformed => (400, "Bad Request", "bad request\n"),
            Refusal::Body => (
                413,
                "Content Too Large",
                "request bodies are not accepted\n",
            ),
            Refusal::Method => (405, "Method Not Allowed", "only GET and HEAD\n"),
            Refusal::NotFound => (404, "Not Found", "not found\n"),
            Refusal::TargetTooLong => (414, "URI Too Long", "request target too long\n"),
            Refusal::HeadTooLarge => (
                431,
                "Request Header Fields Too Large",
                "request headers too large\n",
            ),
            Refusal::Timeout => (408, "Request Timeout", "request timeout\n"),
            Refusal::Busy => (503, "Service Unavailable", "too many connections\n"),
        }
    }
}

/// The length of the request head at the start of `buf` (through its blank
/// line) once it is complete, `None` while more is needed. `from` is where
/// the bytes not yet searched begin (0 searches all): a connection that
/// reads in pieces passes its previous length, so the search stays linear.
/// Refuses a head that cannot fit the bounds, so a connection never reads
/// more than [`MAX_HEAD`] bytes of it.
pub fn head_len(buf: &[u8], from: usize) -> Result<Option<usize>, Refusal> {
    // A blank line ends the head: "\r\n\r\n", or bare "\n\n" as httparse
    // also accepts. Back up so that a line end split across reads is found.
    let start = from.min(buf.len()).saturating_sub(3);
    let end = buf[start..]
        .iter()
        .enumerate()
        .filter(|&(_, &b)| b == b'\n')
        .find_map(|(i, _)| {
            let at = start + i;
            let rest = &buf[at + 1..];
            if rest.starts_with(b"\n") {
                Some(at + 2)
            } else if rest.starts_with(b"\r\n") {
                Some(at + 3)
            } else {
                None
            }
        });
    match end {
        Some(len) if len <= MAX_HEAD => Ok(Some(len)),
        Some(_) => Err(Refusal::HeadTooLarge),
        None if !buf[..buf.len().min(MAX_REQUEST_LINE + 1)].contains(&b'\n')
            && buf.len() > MAX_REQUEST_LINE =>
        {
            Err(Refusal::TargetTooLong)
        }
        None if buf.len() >= MAX_HEAD => Err(Refusal::HeadTooLarge),
        None => Ok(None),
    }
}

/// Parses a complete request head (as [`head_len`] delimits it) into the
/// route it asks for, or the refusal that answers it. The checks, in
/// order: the head's size and syntax, the target's length, a body (refused
/// before anything else about the request matters, since it is never
/// read), the method, the path.
pub fn parse_request(head: &[u8]) -> Result<Request, Refusal> {
    if head.len() > MAX_HEAD {
        return Err(Refusal::HeadTooLarge);
    }
    let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut req = httparse::Request::new(&mut headers);
    match req.parse(head) {
        Ok(httparse::Status::Complete(_)) => {}
        Ok(httparse::Status::Partial) => return Err(Refusal::Malformed),
        Err(httparse::Error::TooManyHeaders) => return Err(Refusal::HeadTooLarge),
        Err(_) => return Err(Refusal::Malformed),
    }
    let target = req.path.ok_or(Refusal::Malformed)?;
    if target.len() > MAX_TARGET {
        return Err(Refusal::TargetTooLong);
    }
    check_no_body(req.headers)?;
    let method = match req.method {
        Some("GET") => Method::Get,
        Some("HEAD") => Method::Head,
        _ => return Err(Refusal::Method),
    };
    let path = target.split('?').next().unwrap_or_default();
    let route = match path {
        "/" => Route::Page,
        "/image.png" => Route::Image,
        "/events" => Route::Events,
        _ => return Err(Refusal::NotFound),
    };
    Ok(Request { method, route })
}

/// Refuses a request that announces a body: any `Transfer-Encoding`, or a
/// `Content-Length` other than 0 (checked by its digits, so no length can
/// overflow); a `Content-Length` that is not a number is malformed.
fn check_no_body(headers: &[httparse::Header<'_>]) -> Result<(), Refusal> {
    for h in headers {
        if h.name.eq_ignore_ascii_case("transfer-encoding") {
            return Err(Refusal::Body);
        }
        if h.name.eq_ignore_ascii_case("content-length") {
            let digits = h.value.trim_ascii();
            if digits.is_empty() || !digits.iter().all(u8::is_ascii_digit) {
                return Err(Refusal::Malformed);
            }
            if digits.iter().any(|&d| d != b'0') {
                return Err(Refusal::Body);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(head: &str) -> Result<Request, Refusal> {
        parse_request(head.as_bytes())
    }

    fn get(route: Route) -> Result<Request, Refusal> {
        Ok(Request {
            method: Method::Get,
            route,
        })
    }

    #[test]
    fn the_routes_with_get_and_head() {
        assert_eq!(parse("GET / HTTP/1.1\r\nHost: x\r\n\r\n"), get(Route::Page));
        assert_eq!(
            parse("GET /image.png?v=3 HTTP/1.1\r\n\r\n"),
            get(Route::Image)
        );
        assert_eq!(parse("GET /events HTTP/1.0\r\n\r\n"), get(Route::Events));
        assert_eq!(
            parse("HEAD /image.png HTTP/1.1\r\n\r\n"),
            Ok(Request {
                method: Method::Head,
                route: Route::Image
            })
        );
        // Bare line feeds, as httparse accepts them.
        assert_eq!(parse("GET / HTTP/1.1\nHost: x\n\n"), get(Route::Page));
    }

    #[test]
    fn other_paths_and_methods_are_refused() {
        assert_eq!(
            parse("GET /etc/passwd HTTP/1.1\r\n\r\n"),
            Err(Refusal::NotFound)
        );
        assert_eq!(
            parse("GET /../image.png HTTP/1.1\r\n\r\n"),
            Err(Refusal::NotFound)
        );
        for m in ["POST", "PUT", "DELETE", "OPTIONS", "CONNECT", "get"] {
            let head = format!("{m} / HTTP/1.1\r\n\r\n");
            assert_eq!(parse(&head), Err(Refusal::Method), "{m}");
        }
    }

    #[test]
    fn a_body_is_refused_from_the_headers() {
        let huge = "POST / HTTP/1.1\r\nContent-Length: 1000000000000\r\n\r\n";
        assert_eq!(parse(huge), Err(Refusal::Body));
        let overflow = format!(
            "GET / HTTP/1.1\r\nContent-Length: {}\r\n\r\n",
            "9".repeat(60)
        );
        assert_eq!(parse(&overflow), Err(Refusal::Body));
        let chunked = "GET / HTTP/1.1\r\ntransfer-encoding: chunked\r\n\r\n";
        assert_eq!(parse(chunked), Err(Refusal::Body));
        assert_eq!(
            parse("GET / HTTP/1.1\r\nContent-Length: 000\r\n\r\n"),
            get(Route::Page)
        );
        for bad in ["-1", "1e3", "", "0x10", "1, 2"] {
            let head = format!("GET / HTTP/1.1\r\nContent-Length: {bad}\r\n\r\n");
            assert_eq!(parse(&head), Err(Refusal::Malformed), "{bad:?}");
        }
    }

    #[test]
    fn sizes_are_bounded() {
        let long = format!("GET /{} HTTP/1.1\r\n\r\n", "a".repeat(MAX_TARGET));
        assert_eq!(parse(&long), Err(Refusal::TargetTooLong));
        let fits = format!("GET /?{} HTTP/1.1\r\n\r\n", "a".repeat(MAX_TARGET - 2));
        assert_eq!(parse(&fits), get(Route::Page));

        let many: String = (0..=MAX_HEADERS).map(|i| format!("X-{i}: 1\r\n")).collect();
        let head = format!("GET / HTTP/1.1\r\n{many}\r\n");
        assert_eq!(parse(&head), Err(Refusal::HeadTooLarge));

        let big = format!("GET / HTTP/1.1\r\nX: {}\r\n\r\n", "b".repeat(MAX_HEAD));
        assert_eq!(parse(&big), Err(Refusal::HeadTooLarge));
    }

    #[test]
    fn malformed_heads() {
        for bad in [
            "",
            "\r\n\r\n",
            "GET\r\n\r\n",
            "GET / HTTP/2.0\r\n\r\n",
            "GET / HTTP/1.1\r\nNo colon\r\n\r\n",
            "GET / HTTP/1.1\r\nX: a\0b\r\n\r\n",
            "GET / HTTP/1.1\r\n",
            "GET /\u{e9} HTTP/1.1\r\n\r\n",
        ] {
            assert!(
                matches!(parse(bad), Err(Refusal::Malformed | Refusal::NotFound)),
                "{bad:?}: {:?}",
                parse(bad)
            );
        }
        assert_eq!(parse_request(b"GET /\xff HTTP/1.1\r\n\r\n").ok(), None);
    }

    #[test]
    fn the_head_ends_at_its_blank_line_and_is_bounded() {
        let req = b"GET / HTTP/1.1\r\nHost: x\r\n\r\nGET /events HTTP/1.1\r\n\r\n";
        assert_eq!(head_len(req, 0), Ok(Some(27)));
        assert_eq!(head_len(b"GET / HTTP/1.1\n\nrest", 0), Ok(Some(16)));
        assert_eq!(head_len(b"GET / HTTP/1.1\r\nHost: x\r\n", 0), Ok(None));
        // Split across reads at every byte: found once the last byte is in.
        for cut in 1..req.len() {
            let first = head_len(&req[..cut], 0);
            assert_eq!(first, Ok((cut >= 27).then_some(27)), "cut {cut}");
            if cut < 27 {
                assert_eq!(head_len(req, cut), Ok(Some(27)), "cut {cut}");
            }
        }
        // A request line that cannot hold an allowed target: 414 at once.
        let line = vec![b'a'; MAX_TARGET + 40];
        assert_eq!(head_len(&line, 0), Err(Refusal::TargetTooLong));
        // Headers that never end: 431 once the bound is reached.
        let mut endless = b"GET / HTTP/1.1\r\n".to_vec();
        endless.resize(MAX_HEAD, b'x');
        assert_eq!(head_len(&endless, 0), Err(Refusal::HeadTooLarge));
        assert_eq!(head_len(&endless[..MAX_HEAD - 1], 0), Ok(None));
    }
}
