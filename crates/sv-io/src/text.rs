//! Small text helpers shared by the readers and writers.

use std::borrow::Cow;

use sv_geom::text::printable;

/// Longest excerpt of an offending line quoted in a message (in characters).
const SNIPPET_CHARS: usize = 40;

/// A short, printable excerpt of `line` for a one-line message: control characters
/// escaped, cut to [`SNIPPET_CHARS`] characters with `...` when longer.
pub(crate) fn snippet(line: &str) -> String {
    let trimmed = line.trim();
    let head: String = trimmed.chars().take(SNIPPET_CHARS).collect();
    let more = if head.len() < trimmed.len() {
        "..."
    } else {
        ""
    };
    format!("{}{more}", printable(&head))
}

/// An `f64` written so that parsing it back gives the same value bit for bit (finite
/// values; `-0` keeps its sign). Uses plain decimals in the usual range and the shortest
/// exponent form (`1e-7`, `1.5e300`) for very small or very large magnitudes.
pub(crate) fn real(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// Decode bytes as UTF-8 text, dropping a byte order mark; invalid sequences become
/// U+FFFD so that a stray Latin-1 byte in a comment does not stop a reader.
pub(crate) fn decode(bytes: &[u8]) -> Cow<'_, str> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    String::from_utf8_lossy(bytes)
}

/// Lines with 1-based numbers, without `\n` / `\r\n` endings.
pub(crate) fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    text.split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

/// True for characters that never occur in a text mesh file (binary data).
pub(crate) fn is_binary_char(c: char) -> bool {
    c.is_control() && !matches!(c, '\t' | '\r' | '\n' | '\x0c')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reals_round_trip_exactly() {
        let samples = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            0.1,
            1.0 / 3.0,
            1e-7,
            -1e-300,
            5e-324,
            1.7976931348623157e308,
            123_456_789.123_456_79,
            1e16,
            9.999999999999998e15,
            300.00000000000006,
        ];
        for x in samples {
            let s = real(x);
            let y: f64 = s.parse().unwrap();
            assert_eq!(x.to_bits(), y.to_bits(), "{x} -> {s}");
            assert!(s.len() < 30, "{s}");
        }
    }

    #[test]
    fn snippets_are_short_and_printable() {
        assert_eq!(snippet("  solid x \r"), "solid x");
        assert_eq!(snippet("a\0b"), "a\\0b");
        let long = "x".repeat(100);
        assert_eq!(snippet(&long), format!("{}...", "x".repeat(40)));
    }

    #[test]
    fn lines_drop_crlf_and_bom() {
        let lines: Vec<_> = numbered_lines("\u{feff}a\r\nb\n\nc").collect();
        assert_eq!(lines, vec![(1, "a"), (2, "b"), (3, ""), (4, "c")]);
        assert_eq!(decode(b"\xEF\xBB\xBFv 1"), "v 1");
        assert_eq!(decode(b"# \xB0\nv"), "# \u{fffd}\nv");
    }
}
