//! Syntax of `.scn` files (Quake-map style): blocks `{ ... }` of `"key" "value"`
//! pairs, one pair per line, `//` comments to the end of a line. This module only
//! splits a file into blocks; `scn` gives them meaning.

use super::Diagnostic;
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
                    format!("unexpected '{other}': expected '{{', '}}' or a quoted \"key\" \"value\" pair"),
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

    #[test]
    fn truncation_at_every_length_never_panics() {
        let text = "{\n\"classname\" \"entity\" // c\n\"mesh\" \"cube\"\n}\n";
        for end in 0..=text.len() {
            let _ = parse(&text[..end]);
        }
    }
}
