//! The session's secret: 128 random bits from the operating system, drawn when the server
//! starts, which a request must carry in `X-Rondo-Token` to change anything on disk.
//!
//! The page gets it inside its own HTML (`<meta name="rondo-token" content="…">`, put in when
//! the server starts). A page of another site can neither read that HTML (the same-origin
//! policy; the `Host` check stops DNS rebinding) nor send a custom header to the server without
//! a CORS preflight, which the server never answers with a grant (`OPTIONS` gets `405`), so a
//! cross-site form or `fetch` cannot write.

use super::http::{Header, Request};

/// A 128-bit secret, written as 32 lower-case hex digits.
pub struct Secret(String);

impl Secret {
    /// A fresh secret from the operating system's random source.
    pub fn new() -> Result<Self, String> {
        let mut bytes = [0u8; 16];
        getrandom::fill(&mut bytes)
            .map_err(|e| format!("no random numbers from the system: {e}"))?;
        Ok(Self(bytes.iter().map(|b| format!("{b:02x}")).collect()))
    }

    /// Whether `request` comes from the viewer's own page: an `Origin`, if sent, of
    /// `http://<host>` (`host`: the request's `Host`, already checked), and an `X-Rondo-Token`
    /// holding this secret. `Err` says which is missing, for a `403`.
    pub fn admits(&self, request: &Request, host: &str) -> Result<(), &'static str> {
        match request.header("origin") {
            Header::Absent => {}
            Header::One(origin) if origin.eq_ignore_ascii_case(&format!("http://{host}")) => {}
            _ => return Err("only the viewer's own page may ask (Origin)"),
        }
        match request.header("x-rondo-token") {
            Header::One(token) if self.matches(token) => Ok(()),
            _ => Err("the session's X-Rondo-Token (from the viewer page) is missing or wrong"),
        }
    }

    /// Whether `given` is the secret, compared in a time that does not depend on where they
    /// differ.
    pub fn matches(&self, given: &str) -> bool {
        let (a, b) = (self.0.as_bytes(), given.as_bytes());
        a.len() == b.len() && a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
    }

    /// The page `page` with the secret in a `<meta name="rondo-token">` right after its
    /// `<head>` (at its start if it has none).
    pub fn page_with(&self, page: &str) -> String {
        let meta = format!("<meta name=\"rondo-token\" content=\"{}\">", self.0);
        match page.find("<head>") {
            Some(at) => {
                let at = at + "<head>".len();
                format!("{}\n{meta}{}", &page[..at], &page[at..])
            }
            None => format!("{meta}\n{page}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn secrets_are_fresh_hex_and_match_only_themselves() {
        let (a, b) = (
            Secret::new().expect("random"),
            Secret::new().expect("random"),
        );
        assert_eq!(a.0.len(), 32);
        assert!(
            a.0.bytes()
                .all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase())
        );
        assert_ne!(a.0, b.0);
        assert!(a.matches(&a.0));
        assert!(!a.matches(&b.0));
        assert!(!a.matches(&a.0[..31]));
        assert!(!a.matches(""));
    }

    #[test]
    fn the_page_carries_the_secret_in_its_head() {
        let s = Secret::new().expect("random");
        let page = s.page_with("<html><head><title>x</title></head></html>");
        assert_eq!(
            page,
            format!(
                "<html><head>\n<meta name=\"rondo-token\" content=\"{}\"><title>x</title></head></html>",
                s.0
            )
        );
        assert!(s.page_with("<p>").starts_with("<meta name=\"rondo-token\""));
    }
}
