//! The HTTP/1.1 the viewer speaks, over [`std::net`]: one request per connection, its head read
//! with a size limit and a deadline, the answer sent with `Connection: close`. A body is read only
//! where a route takes one ([`read_body`]: a `Content-Length` of at most a given size, within a
//! deadline); what a client sends that is not read is drained for a moment before the socket
//! closes, so that the answer is not lost to a reset.

use std::io::{ErrorKind, Read, Write};
use std::net::{Shutdown, TcpStream};
use std::time::{Duration, Instant};

/// How long [`finish`] waits for the client to close after the answer, and how much it reads.
const LINGER: Duration = Duration::from_secs(1);
const LINGER_BYTES: usize = 64 * 1024;

/// The parts of a request head the viewer uses.
#[derive(Debug, PartialEq, Eq)]
pub struct Request {
    /// The method, as sent (methods are case-sensitive).
    pub method: String,
    /// The request target, as sent.
    pub target: String,
    /// The `Host` header's value, if there is one.
    pub host: Option<String>,
    /// Every header line but `Host`, as (name, value) with the value's blanks trimmed, in the
    /// order sent (bounded by the head's size).
    pub headers: Vec<(String, String)>,
    /// What arrived after the head in the same reads: the start of a body.
    pub rest: Vec<u8>,
}

/// A header of a request, by the number of times it was sent.
#[derive(Debug, PartialEq, Eq)]
pub enum Header<'a> {
    /// Not sent.
    Absent,
    /// Sent once, with this value.
    One(&'a str),
    /// Sent more than once.
    Repeated,
}

impl Request {
    /// The header `name` (compared without regard to case).
    pub fn header(&self, name: &str) -> Header<'_> {
        let mut values = self
            .headers
            .iter()
            .filter(|(n, _)| n.eq_ignore_ascii_case(name));
        match (values.next(), values.next()) {
            (None, _) => Header::Absent,
            (Some((_, v)), None) => Header::One(v),
            (Some(_), Some(_)) => Header::Repeated,
        }
    }
}

/// Why a request body could not be read.
#[derive(Debug, PartialEq, Eq)]
pub enum BodyError {
    /// No `Content-Length` (or a `Transfer-Encoding`, which is not read).
    LengthRequired,
    /// A `Content-Length` that is not one decimal number.
    BadLength,
    /// Longer than the limit.
    TooLarge,
    /// The deadline passed before the whole body arrived.
    Timeout,
    /// The client closed before the whole body arrived.
    Closed,
}

impl BodyError {
    /// The status and text that refuse a body read with limit `max`; `None` for
    /// [`BodyError::Closed`] (no one to answer).
    pub fn refusal(self, max: usize) -> Option<(u16, String)> {
        Some(match self {
            Self::Closed => return None,
            Self::LengthRequired => (411, "a body with a Content-Length".into()),
            Self::BadLength => (400, "a bad Content-Length".into()),
            Self::TooLarge => (413, format!("the body is longer than {max} bytes")),
            Self::Timeout => (408, "the body took too long".into()),
        })
    }
}

/// Why no request could be read.
#[derive(Debug, PartialEq, Eq)]
pub enum HeadError {
    /// The client closed (or the connection broke) before a whole head arrived.
    Closed,
    /// The deadline passed; `partial` says whether any byte had arrived.
    Timeout {
        /// Some of a head had arrived.
        partial: bool,
    },
    /// The head is longer than the limit.
    TooLarge,
    /// Not HTTP/1.x.
    Version,
    /// Not a well-formed request head.
    Malformed(&'static str),
}

/// Reads one request head of at most `max` bytes (the blank line included), within `timeout`
/// from now, however the client spreads its bytes.
pub fn read_head(
    stream: &mut TcpStream,
    max: usize,
    timeout: Duration,
) -> Result<Request, HeadError> {
    let deadline = Instant::now() + timeout;
    let mut buf = vec![0; max];
    let mut len = 0;
    loop {
        if let Some(end) = head_end(&buf[..len]) {
            let mut request = parse_head(&buf[..end])?;
            request.rest = buf[end..len].to_vec();
            return Ok(request);
        }
        if len == max {
            return Err(HeadError::TooLarge);
        }
        let left = deadline.saturating_duration_since(Instant::now());
        let timed_out = HeadError::Timeout { partial: len > 0 };
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return Err(timed_out);
        }
        match stream.read(&mut buf[len..]) {
            Ok(0) => return Err(HeadError::Closed),
            Ok(n) => len += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                return Err(timed_out);
            }
            Err(_) => return Err(HeadError::Closed),
        }
    }
}

/// The length of the head in `bytes` up to and including its blank line, if it is complete.
/// Blank lines before the request line are skipped (RFC 9112, section 2.2).
fn head_end(bytes: &[u8]) -> Option<usize> {
    let start = bytes.iter().position(|b| !matches!(b, b'\r' | b'\n'))?;
    let mut at = start;
    while let Some(i) = bytes[at..].iter().position(|&b| b == b'\n') {
        let next = at + i + 1;
        match bytes.get(next..) {
            Some([b'\n', ..]) => return Some(next + 1),
            Some([b'\r', b'\n', ..]) => return Some(next + 2),
            _ => at = next,
        }
    }
    None
}

/// Whether `b` may appear in a method or a header name (RFC 9110's `tchar`).
fn token_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b"!#$%&'*+-.^_`|~".contains(&b)
}

fn parse_head(head: &[u8]) -> Result<Request, HeadError> {
    let text = head
        .iter()
        .position(|b| !matches!(b, b'\r' | b'\n'))
        .map_or(head, |s| &head[s..]);
    let mut lines = text
        .split(|&b| b == b'\n')
        .map(|l| l.strip_suffix(b"\r").unwrap_or(l));
    let request_line = lines.next().unwrap_or_default();
    let mut parts = request_line.split(|&b| b == b' ');
    let (Some(method), Some(target), Some(version), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(HeadError::Malformed(
            "the request line is not METHOD TARGET VERSION",
        ));
    };
    if method.is_empty() || !method.iter().copied().all(token_byte) {
        return Err(HeadError::Malformed("bad method"));
    }
    if target.is_empty() || !target.iter().all(|b| b.is_ascii_graphic()) {
        return Err(HeadError::Malformed("bad request target"));
    }
    if !version.starts_with(b"HTTP/1.") || version.len() != 8 || !version[7].is_ascii_digit() {
        return Err(HeadError::Version);
    }
    let mut host = None;
    let mut headers = Vec::new();
    // Both are printable ASCII, checked above; header values other than Host need not be.
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    for line in lines.take_while(|l| !l.is_empty()) {
        let Some(colon) = line.iter().position(|&b| b == b':') else {
            return Err(HeadError::Malformed("a header line without a colon"));
        };
        let (name, value) = (&line[..colon], &line[colon + 1..]);
        // Also refuses obsolete line folding (a line starting with a space).
        if name.is_empty() || !name.iter().copied().all(token_byte) {
            return Err(HeadError::Malformed("bad header name"));
        }
        if name.eq_ignore_ascii_case(b"host") {
            let value = std::str::from_utf8(value.trim_ascii())
                .map_err(|_| HeadError::Malformed("the Host header is not text"))?;
            if host.replace(value.to_string()).is_some() {
                return Err(HeadError::Malformed("more than one Host header"));
            }
        } else {
            headers.push((text(name), text(value.trim_ascii())));
        }
    }
    Ok(Request {
        method: text(method),
        target: text(target),
        host,
        headers,
        rest: Vec::new(),
    })
}

/// Reads the body of `request`, whose head was read from `stream`: `Content-Length` bytes, at
/// most `max`, within `timeout` from now. A length over `max` is refused before anything is
/// read or allocated; so is a body sent with `Transfer-Encoding` (chunked bodies are not read).
pub fn read_body(
    stream: &mut TcpStream,
    request: &Request,
    max: usize,
    timeout: Duration,
) -> Result<Vec<u8>, BodyError> {
    if request.header("transfer-encoding") != Header::Absent {
        return Err(BodyError::LengthRequired);
    }
    let length = match request.header("content-length") {
        Header::Absent => return Err(BodyError::LengthRequired),
        Header::Repeated => return Err(BodyError::BadLength),
        Header::One(v)
            if v.is_empty() || v.len() > 19 || !v.bytes().all(|b| b.is_ascii_digit()) =>
        {
            return Err(BodyError::BadLength);
        }
        Header::One(v) => v.parse::<usize>().map_err(|_| BodyError::BadLength)?,
    };
    if length > max {
        return Err(BodyError::TooLarge);
    }
    let mut body = request.rest.clone();
    if body.len() > length {
        // More than the body: a second request, which is not read.
        body.truncate(length);
    }
    let deadline = Instant::now() + timeout;
    let mut buf = [0; 4096];
    while body.len() < length {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return Err(BodyError::Timeout);
        }
        let want = (length - body.len()).min(buf.len());
        match stream.read(&mut buf[..want]) {
            Ok(0) => return Err(BodyError::Closed),
            Ok(n) => body.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                return Err(BodyError::Timeout);
            }
            Err(_) => return Err(BodyError::Closed),
        }
    }
    Ok(body)
}

/// The reason phrase of the statuses the viewer sends.
fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        409 => "Conflict",
        411 => "Length Required",
        413 => "Content Too Large",
        422 => "Unprocessable Content",
        431 => "Request Header Fields Too Large",
        500 => "Internal Server Error",
        503 => "Service Unavailable",
        505 => "HTTP Version Not Supported",
        _ => "",
    }
}

/// Writes a response head: the status line, `headers`, `Content-Length` if the length is
/// known (without it the body runs until the connection closes), `Connection: close`.
pub fn write_head(
    stream: &mut impl Write,
    status: u16,
    headers: &[(&str, &str)],
    length: Option<usize>,
) -> std::io::Result<()> {
    let mut head = format!("HTTP/1.1 {status} {}\r\n", reason(status));
    for (name, value) in headers {
        head.push_str(&format!("{name}: {value}\r\n"));
    }
    if let Some(length) = length {
        head.push_str(&format!("Content-Length: {length}\r\n"));
    }
    head.push_str("Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n");
    head.push_str("Connection: close\r\n\r\n");
    stream.write_all(head.as_bytes())
}

/// Writes a whole response; the body only if `with_body` (not for `HEAD`).
pub fn respond(
    stream: &mut impl Write,
    status: u16,
    headers: &[(&str, &str)],
    body: &[u8],
    with_body: bool,
) -> std::io::Result<()> {
    write_head(stream, status, headers, Some(body.len()))?;
    if with_body {
        stream.write_all(body)?;
    }
    stream.flush()
}

/// Writes a short `text/plain` response.
pub fn respond_text(
    stream: &mut impl Write,
    status: u16,
    text: &str,
    with_body: bool,
) -> std::io::Result<()> {
    respond(
        stream,
        status,
        &[("Content-Type", "text/plain; charset=utf-8")],
        text.as_bytes(),
        with_body,
    )
}

/// Ends a connection after its answer: no more writes, then whatever the client still sends is
/// read and dropped (at most [`LINGER_BYTES`] for [`LINGER`]) so that closing a socket with
/// unread bytes does not reset the connection before the client has read the answer.
pub fn finish(mut stream: TcpStream) {
    if stream.shutdown(Shutdown::Write).is_err() {
        return;
    }
    let deadline = Instant::now() + LINGER;
    let mut buf = [0; 4096];
    let mut read = 0;
    while read < LINGER_BYTES {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return;
        }
        match stream.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => read += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(_) => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: impl AsRef<[u8]>) -> Result<Request, HeadError> {
        let bytes = text.as_ref();
        let end = head_end(bytes).ok_or(HeadError::Closed)?;
        parse_head(&bytes[..end])
    }

    #[test]
    fn heads_end_at_the_first_blank_line() {
        assert_eq!(head_end(b"GET / HTTP/1.1\r\nHost: a\r\n\r\nrest"), Some(27));
        assert_eq!(head_end(b"GET / HTTP/1.1\nHost: a\n\n"), Some(24));
        assert_eq!(head_end(b"\r\n\r\nGET / HTTP/1.1\r\n\r\n"), Some(22));
        assert_eq!(head_end(b"GET / HTTP/1.1\r\nHost: a\r\n"), None);
        assert_eq!(head_end(b"\r\n\r\n"), None);
        assert_eq!(head_end(b""), None);
    }

    #[test]
    fn a_request_gives_method_target_and_host() {
        assert_eq!(
            parse("GET /image.png?t=1 HTTP/1.1\r\nUser-Agent: x\r\nhost:  localhost:80 \r\n\r\n"),
            Ok(Request {
                method: "GET".into(),
                target: "/image.png?t=1".into(),
                host: Some("localhost:80".into()),
                headers: vec![("User-Agent".into(), "x".into())],
                rest: Vec::new(),
            })
        );
        assert_eq!(parse("HEAD / HTTP/1.0\r\n\r\n").map(|r| r.host), Ok(None));
    }

    #[test]
    fn headers_are_found_by_name_once_or_repeated() {
        let request = parse("POST / HTTP/1.1\r\nX-Token:  a1 \r\norigin: o\r\nOrigin: p\r\n\r\n")
            .expect("parses");
        assert_eq!(request.header("x-token"), Header::One("a1"));
        assert_eq!(request.header("ORIGIN"), Header::Repeated);
        assert_eq!(request.header("content-length"), Header::Absent);
    }

    #[test]
    fn malformed_heads_are_refused() {
        for bad in [
            "GET / HTTP/1.1 extra\r\n\r\n",
            "GET /\r\n\r\n",
            "GET  / HTTP/1.1\r\n\r\n",
            "G(T / HTTP/1.1\r\n\r\n",
            "GET /\x01 HTTP/1.1\r\n\r\n",
            "GET / HTTP/1.1\r\nno colon\r\n\r\n",
            "GET / HTTP/1.1\r\nHost: a\r\n folded\r\n\r\n",
            "GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n",
        ] {
            assert!(
                matches!(parse(bad), Err(HeadError::Malformed(_))),
                "{bad:?}: {:?}",
                parse(bad)
            );
        }
        assert!(matches!(
            parse(b"GET / HTTP/1.1\r\nHost: \xff\r\n\r\n"),
            Err(HeadError::Malformed(_))
        ));
        assert_eq!(parse("GET / HTTP/2.0\r\n\r\n"), Err(HeadError::Version));
        assert_eq!(parse("GET / HTTP/1.10\r\n\r\n"), Err(HeadError::Version));
        assert_eq!(parse("GET / FTP/1.1\r\n\r\n"), Err(HeadError::Version));
    }

    #[test]
    fn responses_close_and_head_answers_carry_no_body() {
        let mut out = Vec::new();
        respond_text(&mut out, 404, "not found\n", false).expect("write to memory");
        let text = String::from_utf8(out).expect("ASCII");
        assert!(text.starts_with("HTTP/1.1 404 Not Found\r\n"), "{text}");
        assert!(text.contains("\r\nContent-Length: 10\r\n"), "{text}");
        assert!(text.contains("\r\nConnection: close\r\n"), "{text}");
        assert!(text.ends_with("\r\n\r\n"), "no body: {text}");
    }
}
