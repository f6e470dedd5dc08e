//! The base protocol of LSP: messages framed by a `Content-Length` header, read and written
//! with bounds.
//!
//! ```text
//! Content-Length: 52\r\n
//! \r\n
//! {"jsonrpc":"2.0","id":1,"method":"shutdown"}
//! ```
//!
//! Everything read is bounded before it is allocated: a header line is at most
//! [`MAX_HEADER_LINE`] bytes and a header at most [`MAX_HEADER_LINES`] lines; a body longer
//! than [`MAX_CONTENT_LENGTH`] is read past in small pieces and never stored, so that the next
//! message is still found. (rust-analyzer's `lsp-server` allocates whatever `Content-Length`
//! says before reading it, which is why its transport is not used here.)

use std::io::{self, BufRead, Read, Write};

/// Largest message body read, in bytes: a scene of 10⁵ entities is about 10 MB.
pub const MAX_CONTENT_LENGTH: u64 = 64 << 20;
/// Longest header line, in bytes (the two headers LSP defines need under 100).
pub const MAX_HEADER_LINE: usize = 1024;
/// Most header lines of one message.
pub const MAX_HEADER_LINES: usize = 16;

/// What one read from the input found.
#[derive(Debug, PartialEq, Eq)]
pub enum Frame {
    /// A message body (not yet checked to be JSON).
    Body(Vec<u8>),
    /// A body of this many bytes, over [`MAX_CONTENT_LENGTH`], read past without keeping it.
    TooLarge(u64),
    /// The input ended between messages.
    End,
}

/// Input that cannot be read as framed messages: after it, where the next message starts is
/// unknown, so the server stops.
#[derive(Debug, thiserror::Error)]
pub enum FramingError {
    /// Reading failed, or the input ended inside a message.
    #[error("cannot read the input: {0}")]
    Io(#[from] io::Error),
    /// A header that does not parse.
    #[error("bad message header: {0}")]
    Header(String),
}

/// Reads the next message from `input`.
pub fn read_frame(input: &mut impl BufRead) -> Result<Frame, FramingError> {
    let mut length = None;
    let mut line = Vec::with_capacity(64);
    for n in 0.. {
        if n == MAX_HEADER_LINES {
            return Err(FramingError::Header(format!(
                "more than {MAX_HEADER_LINES} header lines"
            )));
        }
        line.clear();
        let read = input
            .by_ref()
            .take(MAX_HEADER_LINE as u64 + 1)
            .read_until(b'\n', &mut line)?;
        if read == 0 {
            if n == 0 {
                return Ok(Frame::End);
            }
            return Err(FramingError::Io(io::ErrorKind::UnexpectedEof.into()));
        }
        if line.last() != Some(&b'\n') {
            return Err(FramingError::Header(format!(
                "a header line longer than {MAX_HEADER_LINE} bytes"
            )));
        }
        let text = String::from_utf8_lossy(&line);
        let text = text.trim_end_matches(['\r', '\n']);
        if text.is_empty() {
            // Blank lines between messages are skipped (some clients end bodies with one).
            if n == 0 {
                continue;
            }
            break;
        }
        let Some((name, value)) = text.split_once(':') else {
            return Err(FramingError::Header(format!(
                "{:?} is not `Name: value`",
                crate::scene::error::printable(text, 80)
            )));
        };
        if name.trim().eq_ignore_ascii_case("content-length") {
            let value = value.trim();
            length = Some(value.parse::<u64>().map_err(|_| {
                FramingError::Header(format!(
                    "Content-Length {:?} is not a number of bytes",
                    crate::scene::error::printable(value, 80)
                ))
            })?);
        }
    }
    let Some(length) = length else {
        return Err(FramingError::Header("no Content-Length".into()));
    };
    if length > MAX_CONTENT_LENGTH {
        let skipped = io::copy(&mut input.by_ref().take(length), &mut io::sink())?;
        if skipped < length {
            return Err(FramingError::Io(io::ErrorKind::UnexpectedEof.into()));
        }
        return Ok(Frame::TooLarge(length));
    }
    // Bounded above: at most MAX_CONTENT_LENGTH bytes, and only as many as arrive.
    let mut body = Vec::new();
    input.by_ref().take(length).read_to_end(&mut body)?;
    if (body.len() as u64) < length {
        return Err(FramingError::Io(io::ErrorKind::UnexpectedEof.into()));
    }
    Ok(Frame::Body(body))
}

/// Writes `message` to `output` with its header, and flushes.
pub fn write_frame(output: &mut impl Write, message: &serde_json::Value) -> io::Result<()> {
    let body = serde_json::to_vec(message)?;
    write!(output, "Content-Length: {}\r\n\r\n", body.len())?;
    output.write_all(&body)?;
    output.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(input: &[u8]) -> Vec<Result<Frame, String>> {
        let mut r = io::BufReader::new(input);
        let mut out = Vec::new();
        loop {
            match read_frame(&mut r) {
                Ok(Frame::End) => return out,
                Ok(f) => out.push(Ok(f)),
                Err(e) => {
                    out.push(Err(e.to_string()));
                    return out;
                }
            }
        }
    }

    #[test]
    fn messages_are_split_by_their_length() {
        let input = b"Content-Length: 2\r\n\r\n{}content-length:3\r\nContent-Type: x\r\n\r\n[1]";
        assert_eq!(
            frames(input),
            vec![
                Ok(Frame::Body(b"{}".to_vec())),
                Ok(Frame::Body(b"[1]".to_vec()))
            ]
        );
    }

    #[test]
    fn an_oversized_body_is_skipped_and_the_next_message_read() {
        let big = MAX_CONTENT_LENGTH + 1;
        let mut input = format!("Content-Length: {big}\r\n\r\n").into_bytes();
        input.resize(input.len() + big as usize, b' ');
        input.extend_from_slice(b"Content-Length: 2\r\n\r\n{}");
        assert_eq!(
            frames(&input),
            vec![Ok(Frame::TooLarge(big)), Ok(Frame::Body(b"{}".to_vec()))]
        );
    }

    #[test]
    fn bad_headers_are_errors_not_allocations() {
        let huge = frames(b"Content-Length: 18446744073709551615\r\n\r\n{}");
        assert!(matches!(huge[..], [Err(_)]), "{huge:?}");
        let overflow = frames(b"Content-Length: 99999999999999999999999\r\n\r\n");
        assert!(
            overflow[0]
                .as_ref()
                .is_err_and(|e| e.contains("not a number"))
        );
        let long = [b"X-A: ".as_slice(), &[b'a'; 5000]].concat();
        assert!(
            frames(&long)[0]
                .as_ref()
                .is_err_and(|e| e.contains("longer"))
        );
        assert!(frames(b"{}\r\n\r\n")[0].is_err());
        assert!(frames(b"Content-Type: x\r\n\r\n")[0].is_err());
        assert!(frames(b"Content-Length: 10\r\n\r\n{}")[0].is_err());
    }
}
