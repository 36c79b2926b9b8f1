//! The command lines the docs show are ones `penumbra` takes: every `--flag`
//! of a `penumbra COMMAND …` line in README.md, scenes/README.md and
//! docs/*.md must be listed
//! by `penumbra COMMAND --help` (the paths, binaries and test modules the
//! docs name are checked by `tests/cpu/docs.rs`).
//!
//! The rules: a command line starts with `penumbra ` followed by a command of
//! `penumbra --help` (`farm` takes its sub-command too: `farm slurm`), in a
//! fenced code block (then lines indented under it that start with `[` or
//! `(` continue it, as in a synopsis) or in a backticked span (up to the
//! closing backtick). Its flags are the words that start with `--` before a
//! `|` pipe, a `;`, `&&` or `#`. `penumbra` preceded by a path character
//! (`target/release/penumbra`, `$PENUMBRA`) counts as well, since the
//! binary is the same, and so does `cargo run [--release] -- COMMAND …`
//! (without `--bin` or `-p`, it runs penumbra).

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The `.md` files under `dir` (relative to the repository), at any depth.
fn markdown_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = fs::read_dir(repo().join(dir)).expect("read docs/");
    for entry in entries {
        let name = entry.expect("read docs/").file_name();
        let path = dir.join(&name);
        if repo().join(&path).is_dir() {
            markdown_files(&path, out);
        } else if path.extension().is_some_and(|ext| ext == "md") {
            out.push(path);
        }
    }
}

/// README.md, scenes/README.md and the Markdown files of docs/ (docs/*.md
/// and the reports in its folders, such as docs/gpu/bench.md), as (path
/// relative to the repository, text).
fn documents() -> Vec<(PathBuf, String)> {
    let mut files = vec![
        PathBuf::from("README.md"),
        PathBuf::from("scenes/README.md"),
    ];
    let mut docs = Vec::new();
    markdown_files(Path::new("docs"), &mut docs);
    docs.sort();
    files.extend(docs);
    files
        .into_iter()
        .map(|file| {
            let text = fs::read_to_string(repo().join(&file)).expect("read a doc");
            (file, text)
        })
        .collect()
}

/// The `--flags` of `penumbra ARGS --help`.
fn help_flags(args: &[&str]) -> BTreeSet<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .arg("--help")
        .output()
        .expect("run penumbra --help");
    assert!(out.status.success(), "penumbra {args:?} --help failed");
    flags(&String::from_utf8_lossy(&out.stdout))
}

/// The words of `text` that start with `--` (without what follows `=`).
fn flags(text: &str) -> BTreeSet<String> {
    text.split(|c: char| c.is_whitespace() || "[](),|`'\"".contains(c))
        .filter(|w| w.starts_with("--") && w.len() > 2)
        .map(|w| {
            w.split('=')
                .next()
                .unwrap()
                .trim_end_matches(['.', ':', ';'])
        })
        .map(str::to_string)
        .collect()
}

/// The commands of `penumbra --help` (the indented words of "Commands:").
fn commands() -> Vec<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("--help")
        .output()
        .expect("run penumbra --help");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// The penumbra command lines of `text`: (line number, the words after
/// `penumbra`).
fn command_lines(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    let mut in_block = false;
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            found.extend(current.take());
            continue;
        }
        if in_block {
            let trimmed = line.trim_start();
            if let Some((_, words)) = current.as_mut() {
                if line.starts_with(' ') && trimmed.starts_with(['[', '(']) {
                    words.push(' ');
                    words.push_str(trimmed);
                    continue;
                }
            }
            found.extend(current.take());
            if let Some(rest) = after_penumbra(line) {
                current = Some((i + 1, rest.to_string()));
            }
        } else {
            // Backticked spans on this line.
            for span in line.split('`').skip(1).step_by(2) {
                if let Some(rest) = after_penumbra(span) {
                    found.push((i + 1, rest.to_string()));
                }
            }
        }
    }
    found.extend(current);
    found
}

/// What follows the first `penumbra ` of `line` (after a path or a variable
/// naming the binary, or at the start).
fn after_penumbra(line: &str) -> Option<&str> {
    if let Some(at) = line.find("cargo run") {
        // `cargo run [--release] -- COMMAND …` runs penumbra, unless it names
        // another binary or package.
        let rest = &line[at..];
        let args = rest.find(" -- ")?;
        let cargo = &rest[..args];
        return (!cargo.contains("--bin") && !cargo.contains("-p ")).then(|| &rest[args + 4..]);
    }
    let at = line.find("penumbra ")?;
    let before = line[..at].chars().next_back();
    let ok = before.is_none_or(|c| c.is_whitespace() || "/$({".contains(c));
    ok.then(|| &line[at + "penumbra ".len()..])
}

#[test]
fn every_flag_of_a_penumbra_command_line_in_the_docs_exists() {
    let commands = commands();
    assert!(commands.iter().any(|c| c == "render"), "{commands:?}");
    let mut known: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut problems = Vec::new();
    let mut checked = 0;
    for (file, text) in documents() {
        for (line, words) in command_lines(&text) {
            let mut parts = words.split_whitespace();
            let Some(command) = parts.next() else {
                continue;
            };
            if !commands.iter().any(|c| c == command) {
                continue; // "penumbra is …" in a sentence, not a command line
            }
            let mut key = vec![command];
            if command == "farm" {
                match parts.next() {
                    Some(sub) if !sub.starts_with('-') => key.push(sub),
                    _ => {}
                }
            }
            let name = key.join(" ");
            let allowed = known
                .entry(name.clone())
                .or_insert_with(|| help_flags(&key));
            let end = words.find(['|', ';', '#']).unwrap_or(words.len());
            let end = words[..end].find("&&").unwrap_or(end);
            for flag in flags(&words[..end]) {
                checked += 1;
                if !allowed.contains(&flag) {
                    problems.push(format!(
                        "{}:{line}: `penumbra {name}` has no {flag}",
                        file.display()
                    ));
                }
            }
        }
    }
    assert!(
        checked > 20,
        "only {checked} flags found: the rules no longer find the command lines"
    );
    assert!(
        problems.is_empty(),
        "the docs show flags that penumbra does not take:\n{}",
        problems.join("\n")
    );
}

/// The rules find a planted bad flag in each kind of command line.
#[test]
fn a_planted_flag_is_found() {
    let text = "Run `penumbra render s.json --no-such-flag` or\n\n```\n\
                penumbra watch SCENE [-o OUT]\n                [--nor-this]\n\
                penumbra render s.json --spp 4 | tee x # --ignored\n\
                tools/setup.sh && cargo run --release -- render s.json --nor-that\n\
                cargo run -p penumbra-tools --bin ab -- s.json --b dir\n```\n\
                and penumbra is fine.\n";
    let lines = command_lines(text);
    let words: Vec<&str> = lines.iter().map(|(_, w)| w.as_str()).collect();
    assert_eq!(
        words,
        [
            "render s.json --no-such-flag",
            "watch SCENE [-o OUT] [--nor-this]",
            "render s.json --spp 4 | tee x # --ignored",
            "render s.json --nor-that",
        ]
    );
    assert!(!help_flags(&["render"]).contains("--no-such-flag"));
    assert!(!help_flags(&["watch"]).contains("--nor-this"));
    assert!(help_flags(&["render"]).contains("--spp"));
}
