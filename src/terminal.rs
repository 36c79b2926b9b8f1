//! Untrusted text on the terminal: what penumbra prints about a file (its
//! name, a field's value, a line of a user's shader) comes from that file, and
//! must not move the cursor, recolour the terminal, hide text or forge lines
//! of its own. [`escape`] writes every control character (C0, DEL, C1) and
//! every bidirectional-formatting character (the "Trojan Source" characters,
//! Unicode TR #9) as a Rust-style escape such as `\u{1b}`; [`diagnostic`]
//! shapes a whole message for an `error:`/`warning:`/`note:` line.

use std::fmt::Write as _;

/// Whether `c` is printed escaped: control characters other than the tab
/// (which [`diagnostic`]'s source lines keep so that carets line up), and the
/// bidirectional embeddings, overrides and isolates.
fn needs_escape(c: char) -> bool {
    (c.is_control() && c != '\t') || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// `text` with every character of [`needs_escape`] written as `\u{…}`
/// (lower-case hexadecimal, as Rust's `char::escape_unicode`); everything
/// else, other scripts included, as it is.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match needs_escape(c) {
            true => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            false => out.push(c),
        }
    }
    out
}

/// Whether `line` is one of the lines that follow a shader error's first
/// line: the source line (` 12 | …`) or the caret line (`    | ^^^`), as
/// [`crate::wgsl::ShaderFileError`] writes them.
fn is_source_line(line: &str) -> bool {
    let Some(rest) = line.strip_prefix(' ') else {
        return false;
    };
    let digits = rest.trim_start_matches(|c: char| c.is_ascii_digit() || c == ' ');
    digits.starts_with("| ") || digits == "|"
}

/// A message as penumbra prints it after `error: ` (or `warning: `,
/// `note: `): the first line and anything that is not a source excerpt of a
/// shader error on one line, with line breaks written as `\u{a}`; source
/// lines (` 12 | …`, `    | ^^`) kept on lines of their own under it. Every
/// character of [`needs_escape`] is escaped, so no text taken from a file can
/// start a line (a forged `error:` line) or send the terminal a control
/// sequence.
pub fn diagnostic(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    for (i, line) in message.split('\n').enumerate() {
        if i > 0 {
            match is_source_line(line) {
                true => out.push('\n'),
                false => out.push_str("\\u{a}"),
            }
        }
        out.push_str(&escape(line));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(escape("a\u{1b}[31mb"), "a\\u{1b}[31mb");
        assert_eq!(
            escape("nul\0 del\u{7f} csi\u{9b}"),
            "nul\\u{0} del\\u{7f} csi\\u{9b}"
        );
        assert_eq!(escape("cr\rlf\n"), "cr\\u{d}lf\\u{a}");
        assert_eq!(escape("rlo\u{202e}txt"), "rlo\\u{202e}txt");
        assert_eq!(escape("tab\tkept"), "tab\tkept");
    }

    #[test]
    fn other_scripts_are_kept() {
        assert_eq!(escape("ünïcødé ✓ 日本"), "ünïcødé ✓ 日本");
    }

    #[test]
    fn a_forged_line_stays_on_the_first_line() {
        let d = diagnostic("scene.json: textures[0]: x.png\nerror: forged\r\n");
        assert_eq!(d.lines().count(), 1, "{d}");
        assert!(d.contains("x.png\\u{a}error: forged\\u{d}\\u{a}"), "{d}");
    }

    #[test]
    fn shader_source_lines_stay_under_the_message() {
        let m = "s.wgsl:3:5: unknown identifier\n 3 |     let x = y\u{1b};\n   |             ^";
        let d = diagnostic(m);
        let lines: Vec<&str> = d.lines().collect();
        assert_eq!(lines.len(), 3, "{d}");
        assert_eq!(lines[1], " 3 |     let x = y\\u{1b};");
        assert_eq!(lines[2], "   |             ^");
    }

    #[test]
    fn a_line_that_only_looks_like_a_source_line_cannot_start_with_error() {
        // Whatever passes as a source line begins with a space and a gutter.
        for forged in ["error: x", "1 | x", "| x", "  error: |"] {
            assert!(!is_source_line(forged), "{forged}");
        }
    }
}
