//! Text from outside (a file's layer name, a client's key) quoted in a one-line message.

/// `text` with its control characters (line breaks, escape, NUL) and the line and paragraph
/// separators escaped as in Rust source (`\n`, `\u{1b}`), so that a message quoting it
/// stays on one line.
pub fn printable(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() || matches!(c, '\u{2028}' | '\u{2029}') {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
    }
    out
}

/// [`printable`] `text`, its middle cut out (`...`) when it has more than `max_chars`
/// characters: the start and the end are kept, `max_chars / 2` characters each.
pub fn excerpt(text: &str, max_chars: usize) -> String {
    let count = text.chars().count();
    if count <= max_chars {
        return printable(text);
    }
    let half = max_chars / 2;
    let head: String = text.chars().take(half).collect();
    let tail: String = text.chars().skip(count - half).collect();
    format!("{}...{}", printable(&head), printable(&tail))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("a\nb\r\0\u{1b}[2J"), "a\\nb\\r\\0\\u{1b}[2J");
        assert_eq!(printable("x\u{2028}y"), "x\\u{2028}y");
        assert_eq!(printable("Layer é \"1\""), "Layer é \"1\"");
    }

    #[test]
    fn long_text_loses_its_middle() {
        assert_eq!(excerpt("abcdef", 6), "abcdef");
        assert_eq!(excerpt("abcdefg", 6), "abc...efg");
        let long = format!("{}\n{}", "a".repeat(3000), "b".repeat(3000));
        assert_eq!(
            excerpt(&long, 60),
            format!("{}...{}", "a".repeat(30), "b".repeat(30))
        );
        assert_eq!(excerpt("\n\n\n", 2), "\\n...\\n");
    }
}
