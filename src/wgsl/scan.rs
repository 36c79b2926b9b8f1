//! The checks of a user's shader file that run before naga sees it: one
//! pass over its tokens ([`super::lexer`]) that refuses what would make the
//! parse slow, deep or unbounded ([`super::limits`]), and what a shader
//! file must not declare: resources (`@group`, `@binding`) and variables
//! outside the function and private address spaces (`var<workgroup>`,
//! `var<storage>`...). A file reaches the scene only through what the
//! interface gives it (`Surface`, `LightSample`, `Params`,
//! `texture_sample`, `texture_at`).

use std::ops::Range;

use super::lexer::{tokens, Kind, Token};
use super::limits::{MAX_FUNCTIONS, MAX_NESTING, MAX_SOURCE_BYTES, MAX_STATEMENT_TOKENS};

/// Why a file is refused, and where (a byte range of the file).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refusal {
    /// The bytes the message is about.
    pub range: Range<usize>,
    /// What is wrong, with the limit's value where a limit is exceeded.
    pub message: String,
}

/// The address spaces a shader file may declare variables in.
const ALLOWED_SPACES: [&str; 2] = ["private", "function"];

/// Checks `source` against the limits and the declarations a shader file
/// must not make, in one pass, before any parse.
pub fn check(source: &str) -> Result<(), Refusal> {
    if source.len() > MAX_SOURCE_BYTES {
        let at = floor_char_boundary(source, MAX_SOURCE_BYTES);
        let end = source[at..]
            .chars()
            .next()
            .map_or(at, |c| at + c.len_utf8());
        return Err(Refusal {
            range: at..end,
            message: format!(
                "the file has {} bytes; a shader file may have at most {MAX_SOURCE_BYTES} bytes",
                source.len()
            ),
        });
    }
    let refuse = |t: &Token, message: String| {
        Err(Refusal {
            range: t.range.clone(),
            message,
        })
    };
    let mut open: Vec<char> = Vec::new();
    let mut in_statement = 0usize;
    let mut functions = 0usize;
    // The two tokens before the current one.
    let mut before: [Option<Token>; 2] = [None, None];
    for t in tokens(source) {
        let text = t.text(source);
        in_statement += 1;
        if in_statement > MAX_STATEMENT_TOKENS {
            return refuse(
                &t,
                format!("this statement has more than {MAX_STATEMENT_TOKENS} tokens, the limit of one statement or expression; split it into several"),
            );
        }
        match t.kind {
            Kind::Punct(c @ ('(' | '[' | '{')) => {
                open.push(c);
                if open.len() > MAX_NESTING {
                    return refuse(
                        &t,
                        format!("brackets nest more than {MAX_NESTING} deep, the limit of `(`, `[` and `{{` inside one another"),
                    );
                }
            }
            Kind::Punct(')' | ']' | '}') => {
                open.pop();
            }
            Kind::Ident if text == "fn" => {
                functions += 1;
                if functions > MAX_FUNCTIONS {
                    return refuse(
                        &t,
                        format!(
                            "more than {MAX_FUNCTIONS} functions, the limit of one shader file"
                        ),
                    );
                }
            }
            Kind::Ident
                if matches!(text, "group" | "binding")
                    && before[1]
                        .as_ref()
                        .is_some_and(|b| b.kind == Kind::Punct('@')) =>
            {
                return refuse(
                    &t,
                    format!("`@{text}`: a shader file must not declare resources; it reaches the scene only through Surface, LightSample, Params, texture_sample and texture_at"),
                );
            }
            Kind::Ident => {
                let after_var_angle = matches!(
                    (&before[0], &before[1]),
                    (Some(v), Some(a)) if v.text(source) == "var" && a.kind == Kind::Punct('<')
                );
                if after_var_angle && !ALLOWED_SPACES.contains(&text) {
                    return refuse(
                        &t,
                        format!("`var<{text}>`: a shader file may declare variables only in the function and private address spaces (`var` and `var<private>`)"),
                    );
                }
            }
            _ => {}
        }
        // A statement ends at `;`, `{` and `}`, and a struct member (or a
        // module-level list) at a `,` outside parentheses.
        let ends_statement = match t.kind {
            Kind::Punct(';' | '{' | '}') => true,
            Kind::Punct(',') => matches!(open.last(), None | Some('{')),
            _ => false,
        };
        if ends_statement {
            in_statement = 0;
        }
        before = [before[1].take(), Some(t)];
    }
    Ok(())
}

/// The largest char boundary of `s` at or below `i`.
pub fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    i = i.min(s.len());
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(source: &str) -> Refusal {
        check(source).expect_err(source)
    }

    #[test]
    fn size() {
        let big = format!("// é\n{}", "x".repeat(MAX_SOURCE_BYTES));
        let r = refused(&big);
        assert!(r.message.contains("at most 65536 bytes"), "{}", r.message);
        assert!(big.is_char_boundary(r.range.start));
        // Just inside the limit: no refusal from the size.
        check(&format!("{};", " ".repeat(MAX_SOURCE_BYTES - 1))).unwrap();
    }

    #[test]
    fn nesting() {
        let ok = format!("{}{}", "(".repeat(MAX_NESTING), ")".repeat(MAX_NESTING));
        check(&ok).unwrap();
        let deep = format!("let x = {}1{};", "(".repeat(2000), ")".repeat(2000));
        let r = refused(&deep);
        assert!(r.message.contains("more than 32 deep"), "{}", r.message);
        assert_eq!(r.range.start, "let x = ".len() + MAX_NESTING);
    }

    #[test]
    fn statement_length() {
        // The file: a 60 KB sum of 30 000 terms.
        let sum = format!("return {};", vec!["a"; 30_000].join("+"));
        let r = refused(&sum);
        assert!(r.message.contains("more than 1024 tokens"), "{}", r.message);
        // Struct members and statements are counted one by one.
        let fields: String = (0..60).map(|i| format!("f{i}: vec3<f32>,\n")).collect();
        check(&format!("struct Params {{\n{fields}}}")).unwrap();
        let lets: String = (0..1000)
            .map(|i| format!("let a{i} = {i} + 1;\n"))
            .collect();
        check(&format!("fn f() {{\n{lets}}}")).unwrap();
    }

    #[test]
    fn functions() {
        let many: String = (0..=MAX_FUNCTIONS)
            .map(|i| format!("fn f{i}() {{}}\n"))
            .collect();
        let r = refused(&many);
        assert!(
            r.message.contains("more than 64 functions"),
            "{}",
            r.message
        );
        assert_eq!(&many[r.range.clone()], "fn");
    }

    #[test]
    fn resources_and_address_spaces() {
        for (source, what) in [
            (
                "@group(0) @binding(3) var<storage, read_write> counters: array<u32>;",
                "@group",
            ),
            ("@ binding(1) var<uniform> u: f32;", "@binding"),
            ("var<workgroup> w: array<f32, 64>;", "var<workgroup>"),
            ("var <storage> s: f32;", "var<storage>"),
            ("var<uniform> u: f32;", "var<uniform>"),
        ] {
            let r = refused(source);
            assert!(r.message.contains(what), "{source}: {}", r.message);
        }
        check("var<private> p: f32;\nfn f() { var x: f32; var<function> y: f32; }").unwrap();
        // In comments the words are harmless.
        check("// @group(0) var<workgroup>\n/* @binding */").unwrap();
    }
}
