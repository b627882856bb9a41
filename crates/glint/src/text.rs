//! Core layer: the message policy every reader follows. A message says where
//! (`file:line`) and what was expected; it never echoes input at length. Names
//! and values a message must show go through [`quote`], lists through
//! [`list`], and [`Diagnostic`](crate::Diagnostic) cuts whatever is left to
//! [`MAX_MESSAGE_CHARS`] (paths to [`MAX_PATH_CHARS`]), saying how much it left out.

/// Most characters of a quoted name or value.
pub const MAX_QUOTED_CHARS: usize = 40;
/// Most items a listed set shows before saying how many more there are.
pub const MAX_LISTED: usize = 8;
/// Most characters of a message.
pub const MAX_MESSAGE_CHARS: usize = 400;
/// Most characters of a path in a message.
pub const MAX_PATH_CHARS: usize = 160;

/// `text` in single quotes, its first [`MAX_QUOTED_CHARS`] characters only
/// (then `…` and the full length), with control characters shown as `?`.
pub fn quote(text: &str) -> String {
    let count = text.chars().count();
    let shown: String = text.chars().take(MAX_QUOTED_CHARS).map(|c| if c.is_control() { '?' } else { c }).collect();
    if count > MAX_QUOTED_CHARS {
        format!("'{shown}…' ({count} characters)")
    } else {
        format!("'{shown}'")
    }
}

/// The first [`MAX_LISTED`] of `items`, each quoted, joined by commas, then
/// how many more there are; `none` for an empty list.
pub fn list<S: AsRef<str>>(items: &[S]) -> String {
    if items.is_empty() {
        return "none".into();
    }
    let shown: Vec<String> = items.iter().take(MAX_LISTED).map(|s| quote(s.as_ref())).collect();
    match items.len().saturating_sub(MAX_LISTED) {
        0 => shown.join(", "),
        more => format!("{} and {more} more", shown.join(", ")),
    }
}

/// `text` cut to `most` characters, keeping its start and end around a note of
/// how many characters were left out.
pub fn shorten(text: &str, most: usize) -> String {
    let count = text.chars().count();
    if count <= most {
        return text.to_string();
    }
    let keep = most / 2;
    let head: String = text.chars().take(keep).collect();
    let tail: String = text.chars().skip(count - keep / 2).collect();
    format!("{head}…[{} characters left out]…{tail}", count - keep - keep / 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_text_is_quoted_whole_and_long_text_with_its_length() {
        assert_eq!(quote("grass"), "'grass'");
        assert_eq!(quote("a\nb"), "'a?b'", "control characters cannot break the line");
        let long = "x".repeat(1 << 20);
        let quoted = quote(&long);
        assert!(quoted.len() < 80, "{quoted}");
        assert!(quoted.ends_with("(1048576 characters)"), "{quoted}");
    }

    #[test]
    fn lists_show_a_few_and_count_the_rest() {
        assert_eq!(list::<&str>(&[]), "none");
        assert_eq!(list(&["a", "b"]), "'a', 'b'");
        let many: Vec<String> = (0..20_000).map(|k| format!("t{k}")).collect();
        let text = list(&many);
        assert!(text.ends_with("and 19992 more"), "{text}");
        assert!(text.len() < 100, "{text}");
    }

    #[test]
    fn shortening_keeps_both_ends_and_counts_the_middle() {
        assert_eq!(shorten("abc", 3), "abc");
        let text = format!("start{}end", "-".repeat(1000));
        let short = shorten(&text, 40);
        assert!(short.starts_with("start") && short.ends_with("end"), "{short}");
        assert!(short.contains("characters left out"), "{short}");
        assert!(short.chars().count() < 80, "{short}");
    }
}
