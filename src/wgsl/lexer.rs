//! The tokens of WGSL source, as far as the checks before naga need them:
//! identifiers (and keywords), numbers and single punctuation characters,
//! each with its byte range, comments and white space skipped.
//!
//! Every step moves by whole characters or compares bytes, so no input
//! (multibyte characters in comments, strings, identifiers or at the end of
//! the file, unterminated comments) can slice the text inside a character.

use std::ops::Range;

/// What kind of token.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// An identifier or keyword (letters, digits and `_`, not starting with a
    /// digit; WGSL allows Unicode letters).
    Ident,
    /// A number literal (starts with a digit; `.` and suffixes included).
    Number,
    /// One other character (an operator, bracket, `@`, `;`...).
    Punct(char),
}

/// One token: its kind and byte range in the source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Token {
    /// What it is.
    pub kind: Kind,
    /// Its bytes in the source.
    pub range: Range<usize>,
}

impl Token {
    /// The token's text in `source`.
    pub fn text<'a>(&self, source: &'a str) -> &'a str {
        &source[self.range.clone()]
    }
}

/// Whether `c` continues an identifier or number.
fn word_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The tokens of `source`, in order.
pub fn tokens(source: &str) -> Tokens<'_> {
    Tokens { source, at: 0 }
}

/// The iterator [`tokens`] returns.
pub struct Tokens<'a> {
    source: &'a str,
    at: usize,
}

impl Tokens<'_> {
    /// The end of the comment that starts at `start` (a `/*`): after the
    /// `*/` that closes it (block comments nest in WGSL), or the end of the
    /// text. Compares bytes: `*` and `/` never occur inside a multibyte
    /// character, so the result is always a character boundary.
    fn block_comment_end(&self, start: usize) -> usize {
        let bytes = self.source.as_bytes();
        let mut depth = 0usize;
        let mut i = start;
        while i < bytes.len() {
            if bytes[i..].starts_with(b"/*") {
                depth += 1;
                i += 2;
            } else if bytes[i..].starts_with(b"*/") {
                depth -= 1;
                i += 2;
                if depth == 0 {
                    return i;
                }
            } else {
                i += 1;
            }
        }
        bytes.len()
    }
}

impl Iterator for Tokens<'_> {
    type Item = Token;

    fn next(&mut self) -> Option<Token> {
        loop {
            let rest = &self.source[self.at..];
            let c = rest.chars().next()?;
            if c.is_whitespace() {
                self.at += c.len_utf8();
            } else if rest.starts_with("//") {
                self.at += rest.find('\n').unwrap_or(rest.len());
            } else if rest.starts_with("/*") {
                self.at = self.block_comment_end(self.at);
            } else {
                let start = self.at;
                let (kind, len) = if word_char(c) {
                    let len = rest
                        .char_indices()
                        .find(|&(_, d)| !(word_char(d) || (c.is_ascii_digit() && d == '.')))
                        .map_or(rest.len(), |(k, _)| k);
                    let kind = if c.is_ascii_digit() {
                        Kind::Number
                    } else {
                        Kind::Ident
                    };
                    (kind, len)
                } else if c == '.' && rest[1..].starts_with(|d: char| d.is_ascii_digit()) {
                    // `.5`
                    let len = 1 + rest[1..]
                        .find(|d: char| !(word_char(d) || d == '.'))
                        .unwrap_or(rest.len() - 1);
                    (Kind::Number, len)
                } else {
                    (Kind::Punct(c), c.len_utf8())
                };
                self.at += len;
                return Some(Token {
                    kind,
                    range: start..start + len,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(source: &str) -> Vec<&str> {
        tokens(source).map(|t| t.text(source)).collect()
    }

    #[test]
    fn splits_words_numbers_and_punctuation() {
        assert_eq!(
            texts("fn f(a: f32) -> f32 { return a * 1.5e3 + .5; }"),
            [
                "fn", "f", "(", "a", ":", "f32", ")", "-", ">", "f32", "{", "return", "a", "*",
                "1.5e3", "+", ".5", ";", "}"
            ]
        );
    }

    #[test]
    fn skips_comments_nested_and_unterminated() {
        assert_eq!(texts("a // b\nc /* d /* e */ f */ g /* h"), ["a", "c", "g"]);
    }

    /// The inputs of issue 36 that sliced inside a character, and their
    /// relatives: multibyte characters in block and line comments, nested
    /// comments, unterminated ones, identifiers, stray characters and at
    /// the very end.
    #[test]
    fn multibyte_characters_anywhere() {
        for source in [
            "/* é */ fn",
            "/* 🦀 /* ü */ ß */ fn",
            "/* unterminated ä",
            "/* é",
            "/*é*/",
            "// ä\nfn",
            "// ä",
            "fn f() { let x = \"ü\"; }",
            "@ä fn",
            "é",
            "fn é",
            "x🦀",
            "1.5é",
            ".5é",
            "*/é/*",
            "/",
            "/*",
            "/*/",
        ] {
            let all: Vec<Token> = tokens(source).collect();
            for t in &all {
                assert!(source.is_char_boundary(t.range.start), "{source:?}");
                assert!(source.is_char_boundary(t.range.end), "{source:?}");
            }
        }
        assert_eq!(texts("/* é */ fn"), ["fn"]);
        assert_eq!(texts("é x"), ["é", "x"]);
        assert_eq!(texts("a🦀b"), ["a", "🦀", "b"]);
    }
}
