//! Syntax of `.scn` files (Quake-map style): blocks `{ ... }` of `"key" "value"`
//! pairs, one pair per line, `//` comments to the end of a line. This module only
//! splits a file into blocks; `scn` gives them meaning.

use super::Diagnostic;
use crate::text::quote;
use std::path::Path;

/// One `"key" "value"` pair and the line it is on.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Pair {
    pub key: String,
    pub value: String,
    pub line: usize,
}

/// One `{ ... }` block: the line of its `{` and its pairs in file order.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Block {
    pub line: usize,
    pub pairs: Vec<Pair>,
}

enum Token {
    Open,
    Close,
    Quoted(String),
}

/// Split one line into tokens, stopping at a `//` comment outside quotes.
fn tokenize(path: &Path, line_no: usize, line: &str) -> Result<Vec<Token>, Diagnostic> {
    let mut tokens = Vec::new();
    let mut chars = line.char_indices().peekable();
    while let Some((at, c)) = chars.next() {
        match c {
            c if c.is_whitespace() => {}
            '{' => tokens.push(Token::Open),
            '}' => tokens.push(Token::Close),
            '/' if line[at..].starts_with("//") => break,
            '"' => {
                let mut text = String::new();
                loop {
                    match chars.next() {
                        Some((_, '"')) => break,
                        Some((_, c)) => text.push(c),
                        None => {
                            return Err(Diagnostic::at(
                                path,
                                line_no,
                                "unterminated quote: a string must end on the line it starts",
                            ))
                        }
                    }
                }
                tokens.push(Token::Quoted(text));
            }
            other => {
                return Err(Diagnostic::at(
                    path,
                    line_no,
                    format!(
                        "unexpected {}: expected '{{', '}}' or a quoted \"key\" \"value\" pair",
                        quote(&other.to_string())
                    ),
                ))
            }
        }
    }
    Ok(tokens)
}

/// Turn the strings gathered on a line into the open block's pair: none is fine,
/// two make a pair, anything else (or a pair outside a block) is an error.
fn flush_pair(
    path: &Path,
    line_no: usize,
    strings: &mut Vec<String>,
    open: Option<&mut Block>,
) -> Result<(), Diagnostic> {
    match (strings.len(), open) {
        (0, _) => Ok(()),
        (_, None) => Err(Diagnostic::at(path, line_no, "\"key\" \"value\" pair outside a block: open one with '{'")),
        (2, Some(block)) => {
            let value = strings.pop().unwrap_or_default();
            let key = strings.pop().unwrap_or_default();
            block.pairs.push(Pair { key, value, line: line_no });
            Ok(())
        }
        (n, Some(_)) => Err(Diagnostic::at(
            path,
            line_no,
            format!("expected one \"key\" \"value\" pair on the line, found {n} strings"),
        )),
    }
}

/// The text of a `.scn` file from its bytes. A scene is UTF-8 (a UTF-8 byte-order
/// mark is skipped); UTF-16 or UTF-32 (a byte-order mark, or the NUL bytes ASCII
/// text has in them) is refused at line 1, and any other invalid UTF-8 or NUL
/// byte at its line and column, with its byte offset. No byte of the file is
/// quoted: it may not be a scene at all.
pub(crate) fn decode_scene_text(path: &Path, bytes: &[u8]) -> Result<String, Diagnostic> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if let Some(encoding) = wide_encoding(bytes) {
        let message = format!("expected UTF-8 text, found {encoding}: save the scene as UTF-8");
        return Err(Diagnostic::at(path, 1, message));
    }
    let bad = |at: usize, what: &str| {
        let before = &bytes[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        // Column in characters: everything before `at` on the line is valid UTF-8.
        let column = String::from_utf8_lossy(&before[line_start..]).chars().count() + 1;
        Diagnostic::at(path, line, format!("{what} at column {column} (byte {at} of the file): expected UTF-8 text"))
    };
    let text = match std::str::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => return Err(bad(e.valid_up_to(), "invalid UTF-8")),
    };
    if let Some(at) = text.bytes().position(|b| b == 0) {
        return Err(bad(at, "a NUL byte"));
    }
    Ok(text.to_owned())
}

/// The wide Unicode encoding `bytes` look like: a UTF-16 or UTF-32 byte-order
/// mark, or (with none) NUL bytes in at least a quarter of the first 256
/// bytes, as ASCII text in UTF-16 has every other byte NUL.
fn wide_encoding(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(&[0xFF, 0xFE, 0, 0]) || bytes.starts_with(&[0, 0, 0xFE, 0xFF]) {
        return Some("UTF-32");
    }
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Some("UTF-16");
    }
    let head = &bytes[..bytes.len().min(256)];
    let nuls = head.iter().filter(|&&b| b == 0).count();
    (head.len() >= 2 && nuls * 4 >= head.len()).then_some("UTF-16 (NUL bytes between the characters)")
}

/// Parse the text of a `.scn` file into blocks. `path` is only used in messages.
///
/// Errors: unterminated quote or block, a `}` with no block open, a pair outside a
/// block, a line that is not exactly one `"key" "value"` pair, a nested block.
pub(crate) fn parse_blocks(path: &Path, text: &str) -> Result<Vec<Block>, Diagnostic> {
    let mut blocks = Vec::new();
    let mut open: Option<Block> = None;
    for (index, line) in text.lines().enumerate() {
        let line_no = index + 1;
        let mut strings = Vec::new();
        for token in tokenize(path, line_no, line)? {
            match token {
                Token::Quoted(s) => strings.push(s),
                Token::Open => {
                    flush_pair(path, line_no, &mut strings, open.as_mut())?;
                    if open.is_some() {
                        return Err(Diagnostic::at(
                            path,
                            line_no,
                            "'{' inside a block: close the previous block with '}' first",
                        ));
                    }
                    open = Some(Block { line: line_no, pairs: Vec::new() });
                }
                Token::Close => {
                    flush_pair(path, line_no, &mut strings, open.as_mut())?;
                    blocks.push(open.take().ok_or_else(|| Diagnostic::at(path, line_no, "'}' with no block open"))?);
                }
            }
        }
        flush_pair(path, line_no, &mut strings, open.as_mut())?;
    }
    if let Some(block) = open {
        return Err(Diagnostic::at(path, block.line, "unterminated block: '{' is never closed with '}'"));
    }
    Ok(blocks)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<Block>, Diagnostic> {
        parse_blocks(Path::new("t.scn"), text)
    }

    #[test]
    fn blocks_pairs_lines_and_comments() {
        let blocks = parse(
            "// scene\n{\n\"classname\" \"world\" // trailing\n\"url\" \"a//b\"\n}\n{ \"classname\" \"camera\" }\n",
        )
        .unwrap();
        assert_eq!(blocks.len(), 2);
        assert_eq!(blocks[0].line, 2);
        assert_eq!(blocks[0].pairs[0], Pair { key: "classname".into(), value: "world".into(), line: 3 });
        assert_eq!(blocks[0].pairs[1].value, "a//b", "// inside quotes is not a comment");
        assert_eq!(blocks[1].pairs[0].value, "camera");
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            ("{\n\"a\" \"b\n}", 2, "unterminated quote"),
            ("{\n\"a\" \"b\"\n", 1, "unterminated block"),
            ("}\n", 1, "no block open"),
            ("\"a\" \"b\"\n", 1, "outside a block"),
            ("{\n\"a\"\n}", 2, "found 1 strings"),
            ("{\n\"a\" \"b\" \"c\"\n}", 2, "found 3 strings"),
            ("{\n{\n}", 2, "inside a block"),
            ("{\nkey value\n}", 2, "unexpected 'k'"),
        ];
        for (text, line, want) in cases {
            let err = parse(text).unwrap_err();
            assert_eq!(err.line, Some(line), "{text:?}: {err}");
            assert!(err.message.contains(want), "{text:?}: {err}");
        }
    }

    fn decode(bytes: &[u8]) -> Result<String, Diagnostic> {
        decode_scene_text(Path::new("t.scn"), bytes)
    }

    fn utf16(text: &str, big_endian: bool, bom: bool) -> Vec<u8> {
        let units = bom.then_some(0xFEFF).into_iter().chain(text.encode_utf16());
        units.flat_map(|u| if big_endian { u.to_be_bytes() } else { u.to_le_bytes() }).collect()
    }

    #[test]
    fn utf8_text_decodes_and_its_byte_order_mark_is_skipped() {
        let text = "{\n\"classname\" \"material\"\n\"name\" \"žluť\"\n}\n";
        assert_eq!(decode(text.as_bytes()).unwrap(), text);
        let with_bom = [&b"\xEF\xBB\xBF"[..], text.as_bytes()].concat();
        assert_eq!(decode(&with_bom).unwrap(), text);
        assert_eq!(decode(b"").unwrap(), "");
    }

    #[test]
    fn utf16_and_utf32_are_refused_at_line_1() {
        let text = "// a scene\n{\n\"classname\" \"world\"\n}\n";
        for (big_endian, bom) in [(false, true), (true, true), (false, false), (true, false)] {
            let err = decode(&utf16(text, big_endian, bom)).unwrap_err();
            assert_eq!(err.line, Some(1), "{err}");
            assert!(err.message.contains("expected UTF-8 text, found UTF-16"), "{err}");
        }
        let utf32: Vec<u8> =
            std::iter::once('\u{feff}').chain(text.chars()).flat_map(|c| (c as u32).to_le_bytes()).collect();
        let err = decode(&utf32).unwrap_err();
        assert!(err.message.contains("found UTF-32"), "{err}");
    }

    #[test]
    fn invalid_utf8_names_the_line_column_and_byte() {
        // "é" in Latin-1 (0xE9) on line 3, after `"name" "caf`.
        let mut bytes = b"{\n\"classname\" \"material\"\n\"name\" \"caf".to_vec();
        let at = bytes.len();
        bytes.extend_from_slice(b"\xE9\"\n}\n");
        let err = decode(&bytes).unwrap_err();
        assert_eq!(err.line, Some(3), "{err}");
        assert!(err.message.contains("invalid UTF-8 at column 12"), "{err}");
        assert!(err.message.contains(&format!("byte {at} of the file")), "{err}");
        // Columns count characters, not bytes; a truncated sequence at the end is invalid too.
        let err = decode(&["\"ž\" ".as_bytes(), b"\xC5"].concat()).unwrap_err();
        assert_eq!((err.line, err.message.contains("column 5")), (Some(1), true), "{err}");
        let err = decode(b"{\n}\n\xC5").unwrap_err();
        assert_eq!(err.line, Some(3), "{err}");
    }

    #[test]
    fn a_stray_nul_byte_is_an_error_at_its_line() {
        let err = decode(b"{\n\"classname\" \"world\"\n\"ambient\" \"0\x00\"\n}\n").unwrap_err();
        assert_eq!(err.line, Some(3), "{err}");
        assert!(err.message.contains("a NUL byte at column 13"), "{err}");
    }

    #[test]
    fn truncation_at_every_length_never_panics() {
        let text = "{\n\"classname\" \"entity\" // c\n\"mesh\" \"cube\"\n}\n";
        for end in 0..=text.len() {
            let _ = parse(&text[..end]);
        }
    }
}
