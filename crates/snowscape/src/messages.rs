//! Error messages that echo what the user gave without echoing megabytes of it.
//!
//! A parser or a check that names the offending value (`unknown variant "…"`, `--to "…"`,
//! `start_date = "…"`) would copy a 10 MB value into the message whole. Every front end
//! passes its messages through [`clip_values`] before showing them: each quoted value
//! (`"…"` or `` `…` ``; an apostrophe is not a quote) and each unquoted word longer than [`MAX_VALUE_CHARS`] is cut to
//! its start and its end around an ellipsis and the count of characters left out.

/// The longest value shown whole, characters.
pub const MAX_VALUE_CHARS: usize = 80;

/// `value`, cut to about [`MAX_VALUE_CHARS`] characters when longer: the first 50 and the
/// last 20, with `…(N more chars)…` between them.
pub fn clip(value: &str) -> String {
    let n = value.chars().count();
    if n <= MAX_VALUE_CHARS {
        return value.to_string();
    }
    let head: String = value.chars().take(50).collect();
    let tail: String = value.chars().skip(n - 20).collect();
    format!("{head}…({} more chars)…{tail}", n - 70)
}

/// `message` with every over-long quoted value and unquoted word clipped by [`clip`].
pub fn clip_values(message: &str) -> String {
    if message.chars().count() <= MAX_VALUE_CHARS {
        return message.to_string();
    }
    let mut out = String::with_capacity(message.len().min(4096));
    let mut rest = message;
    while let Some(c) = rest.chars().next() {
        if matches!(c, '"' | '`') {
            // A quoted value up to its closing quote (or the end of the line).
            let body = &rest[1..];
            let end = body.find([c, '\n']).unwrap_or(body.len());
            let closed = body[end..].starts_with(c);
            out.push(c);
            out.push_str(&clip(&body[..end]));
            if closed {
                out.push(c);
                rest = &body[end + 1..];
            } else {
                rest = &body[end..];
            }
        } else if c.is_whitespace() {
            out.push(c);
            rest = &rest[c.len_utf8()..];
        } else {
            // An unquoted word: up to whitespace or a quote.
            let end = rest
                .find(|ch: char| ch.is_whitespace() || matches!(ch, '"' | '`'))
                .unwrap_or(rest.len());
            let end = end.max(c.len_utf8());
            out.push_str(&clip(&rest[..end]));
            rest = &rest[end..];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_values_are_clipped_and_short_ones_kept() {
        let short = "--to \"xyz\": unknown format (one of asc, tif)";
        assert_eq!(clip_values(short), short);
        // Apostrophes are words' own: a long sentence between two stays whole.
        let prose = format!("the run's {} isn't clipped", "report ".repeat(20));
        assert_eq!(clip_values(&prose), prose);
        let big = "x".repeat(10_000_000);
        let msg = format!(
            "scenario s.toml: unknown variant `{big}`, expected one of `a`, `b` and more words here"
        );
        let clipped = clip_values(&msg);
        assert!(clipped.len() < 300, "{}", clipped.len());
        assert!(
            clipped.starts_with("scenario s.toml: unknown variant `xxxxx"),
            "{clipped}"
        );
        assert!(clipped.contains("(9999930 more chars)"), "{clipped}");
        assert!(
            clipped.ends_with("expected one of `a`, `b` and more words here"),
            "{clipped}"
        );
        // Unquoted and unterminated values too; multi-byte characters are cut on boundaries.
        let word = "é".repeat(1000);
        let clipped = clip_values(&format!("value {word} is bad, and \"{word}"));
        assert!(clipped.chars().count() < 250, "{clipped}");
        assert!(clipped.starts_with("value ééé") && clipped.contains("is bad, and \"ééé"));
        assert_eq!(clip(&"a".repeat(80)), "a".repeat(80));
        assert_eq!(
            clip(&"a".repeat(81)).chars().count(),
            50 + 20 + "…(11 more chars)…".chars().count()
        );
    }
}
