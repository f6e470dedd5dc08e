//! Sample ranges: read, written, joined, and the gaps between them.

use std::ops::Range;

/// Parses a sample range `A..B` (A < B).
pub fn parse_range(text: &str) -> Result<Range<u32>, String> {
    let bad = || format!("sample range {text:?} must be A..B with whole numbers A < B");
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a >= b {
        return Err(bad());
    }
    Ok(a..b)
}

/// Ranges as `0..256,512..768`.
pub fn format_ranges(ranges: &[Range<u32>]) -> String {
    ranges
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect::<Vec<_>>()
        .join(",")
}

/// Sorts ranges and joins the adjacent ones (they must not overlap).
pub fn normalize(mut ranges: Vec<Range<u32>>) -> Vec<Range<u32>> {
    ranges.sort_by_key(|r| r.start);
    let mut out: Vec<Range<u32>> = Vec::with_capacity(ranges.len());
    for r in ranges {
        match out.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => out.push(r),
        }
    }
    out
}

/// The samples of `0..end` that `ranges` (normalized) do not hold.
pub fn gaps(ranges: &[Range<u32>], end: u32) -> Vec<Range<u32>> {
    let mut out = Vec::new();
    let mut at = 0;
    for r in ranges {
        if r.start > at {
            out.push(at..r.start);
        }
        at = at.max(r.end);
    }
    if at < end {
        out.push(at..end);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_normalize_and_show_gaps() {
        assert_eq!(parse_range("0..256"), Ok(0..256));
        assert!(parse_range("5..5").is_err());
        assert!(parse_range("7..3").is_err());
        assert!(parse_range("1-3").is_err());
        let r = normalize(vec![512..768, 0..256, 256..300]);
        assert_eq!(r, vec![0..300, 512..768]);
        assert_eq!(gaps(&r, 1024), vec![300..512, 768..1024]);
        assert_eq!(format_ranges(&r), "0..300,512..768");
    }
}
