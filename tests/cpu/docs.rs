//! Docs that cannot drift: README.md, scenes/README.md (the scene format) and
//! every Markdown file under docs/ (docs/*.md and reports such as
//! docs/gpu/bench.md) are read as text and what they name in the repository is
//! checked against the repository.
//!
//! The rules:
//!
//! - **Paths.** Every path that starts with a top folder of the repository
//!   (`src/`, `tools/`, `shaders/`, `tests/`, `scenes/`, `docs/`, `.ci/`),
//!   anywhere in the text (backticked, linked or plain), must exist: a file,
//!   or a folder when it ends in `/`. A path that follows another path
//!   character (`DIR/shaders/x.wgsl`, `$OUT/docs/…`, `target/…`) is not a
//!   repository path and is not checked; trailing `.`, `,`, `:` and `;` are
//!   punctuation, not part of the path, and `:LINE:COL` is cut off likewise.
//!   `COMMIT:path` (git's revision syntax, `b43f463:tools/x.patch`) names a
//!   file at that commit, which need not exist now, and is not checked.
//! - **Links.** Every relative Markdown link or image, `[text](target)`, must
//!   name an existing file or folder, resolved from the folder of the file
//!   that holds it; the `#anchor` is cut off; links with a scheme
//!   (`https://…`) are not checked.
//! - **Globs and placeholders.** A `*` matches within one path component, so
//!   `shaders/stages/*.wgsl` must match at least one file. A component with
//!   a placeholder (`<command>`, `{a,b}`, an upper-case word such as `NAME`
//!   or `OUT`, or `foo`, the checklists' new item) counts as `*`:
//!   `src/cli/<command>.rs` needs some `src/cli/*.rs`.
//! - **Quoted values.** A path in double quotes (`"file": "shaders/toon.wgsl"`)
//!   is a value of a scene or a program, relative to the scene: it must exist
//!   from the repository's root or from `scenes/`.
//! - **Outputs** of commands are named under `target/` or a variable, which
//!   the first rule leaves alone; an output committed under `docs/` is a
//!   file like any other and must exist.
//! - **Binaries.** Every `--bin NAME` must name a binary of the workspace: the
//!   `[[bin]]`s of Cargo.toml and tools/measure/Cargo.toml, `src/main.rs`
//!   (`penumbra`) and `src/bin/*.rs`. In a `cargo run` command (up to its
//!   closing backtick or the end of its line, and before ` -- `) a tools
//!   binary needs `-p penumbra-tools` (the root package is the workspace's
//!   only default member), a `-p NAME` must name a workspace package, and a
//!   `cargo test --test NAME` must name a test target of the root package.
//!   An upper-case name (`--bin NAME`) is a placeholder.
//! - **Code names.** Every backticked Rust path (`Renderer::render`,
//!   `compile::shade_override_values`) in README.md and docs/*.md, and every
//!   backticked snake_case name (`load_scene`, `check_bindings()`) in the docs
//!   that describe the code (README.md, docs/architecture.md, docs/design.md),
//!   must consist of identifiers found in the code of the sources (`src/`,
//!   `shaders/`, `tools/`, `tests/`, outside `//` comments, or their file
//!   names). A name with `foo` in it is
//!   a checklist's placeholder.
//! - **No orphans.** Every docs/*.md is reachable from README.md through
//!   relative links between the docs.
//! - **The library example.** README.md's `rust` block is the body of
//!   `library_example` here, which is compiled with the tests.
//! - **Test modules.** docs/tests.md has one table row per test binary,
//!   starting with the binary's file (`tests/gpu/main.rs`); its last cell
//!   must name, backticked, every `mod x;` of that `main.rs`, and every
//!   backticked lower-case identifier there must be such a module. Every
//!   top-level `tests/*.rs` binary must have a row of its own.
//!
//! Run alone: `cargo test --test cpu docs::`.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Component, Path, PathBuf};

/// The repository's top folders whose paths the docs name.
const ROOTS: [&str; 7] = [
    "src/", "tools/", "shaders/", "tests/", "scenes/", "docs/", ".ci/",
];

/// The workspace's package that holds the tools' binaries.
const TOOLS_PACKAGE: &str = "penumbra-tools";

/// The tools' manifest, relative to the repository root.
const TOOLS_MANIFEST: &str = "tools/measure/Cargo.toml";

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
            let text = fs::read_to_string(repo().join(&file))
                .unwrap_or_else(|e| panic!("read {}: {e}", file.display()));
            (file, text)
        })
        .collect()
}

/// The 1-based line of byte offset `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text[..at].matches('\n').count() + 1
}

/// A character that may continue a path (a path starting after one is not a
/// repository path).
fn is_path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || "_-./$~*<>{}+".contains(c)
}

/// The repository paths named in `text`, with their byte offsets.
fn named_paths(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (at, _) in text.char_indices() {
        let rest = &text[at..];
        if !ROOTS.iter().any(|root| rest.starts_with(root)) {
            continue;
        }
        if text[..at].chars().next_back().is_some_and(is_path_char) {
            continue;
        }
        if let Some(before) = text[..at].strip_suffix(':') {
            let revision: String = before
                .chars()
                .rev()
                .take_while(char::is_ascii_hexdigit)
                .collect();
            if revision.len() >= 7 {
                continue; // `COMMIT:path`: the file at that commit
            }
        }
        let mut end = 0;
        let mut in_braces = false;
        for (i, c) in rest.char_indices() {
            let ok = match c {
                '{' => {
                    in_braces = true;
                    true
                }
                '}' => {
                    in_braces = false;
                    true
                }
                ',' => in_braces,
                c => is_path_char(c),
            };
            if !ok {
                break;
            }
            end = i + c.len_utf8();
        }
        let path = rest[..end].trim_end_matches(['.', ',', ':', ';']);
        found.push((at, path.to_string()));
    }
    found
}

/// The relative link targets of Markdown links and images in `text`.
fn link_targets(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (at, _) in text.match_indices("](") {
        let start = at + 2;
        let Some(len) = text[start..].find([')', ' ', '\n']) else {
            continue;
        };
        let target = &text[start..start + len];
        let target = target.split('#').next().unwrap_or_default();
        if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        found.push((start, target.to_string()));
    }
    found
}

/// A path component written as a placeholder: `<x>`, an upper-case word.
fn is_placeholder(component: &str) -> bool {
    let stem = component.split('.').next().unwrap_or_default();
    component.contains('<')
        || stem == "foo"
        || (stem.len() > 1
            && stem
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
            && stem.chars().any(|c| c.is_ascii_uppercase())
            && !["README", "CREDITS", "LICENSE"].contains(&stem))
}

/// `*` within one component; nothing else is special.
fn wildcard(pattern: &str, name: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == name;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !name.starts_with(first) || name.len() < first.len() + last.len() || !name.ends_with(last) {
        return false;
    }
    let mut rest = &name[first.len()..name.len() - last.len()];
    for part in &parts[1..parts.len() - 1] {
        match rest.find(part) {
            Some(i) => rest = &rest[i + part.len()..],
            None => return false,
        }
    }
    true
}

/// The alternatives of one component: `{a,b}.rs` gives `a.rs` and `b.rs`; a
/// placeholder gives `*` with its extension kept.
fn alternatives(component: &str) -> Vec<String> {
    if let (Some(open), Some(close)) = (component.find('{'), component.find('}')) {
        if open < close {
            let (head, tail) = (&component[..open], &component[close + 1..]);
            return component[open + 1..close]
                .split(',')
                .map(|alt| format!("{head}{alt}{tail}"))
                .collect();
        }
    }
    if is_placeholder(component) {
        let ext = component
            .rfind('.')
            .filter(|&i| !component[i..].contains('>'))
            .map(|i| &component[i..])
            .unwrap_or("");
        return vec![format!("*{ext}")];
    }
    vec![component.to_string()]
}

/// Whether `path` (relative to `base`, `/`-separated, maybe with globs and
/// placeholders) names something that exists; a trailing `/` asks for a
/// folder.
fn exists(base: &Path, path: &str) -> bool {
    let want_dir = path.ends_with('/');
    let mut current = vec![base.to_path_buf()];
    for component in path.split('/').filter(|c| !c.is_empty()) {
        let mut next = Vec::new();
        for dir in &current {
            for alt in alternatives(component) {
                if alt == "." {
                    next.push(dir.clone());
                } else if alt == ".." {
                    next.push(dir.join(".."));
                } else if alt.contains('*') {
                    let Ok(entries) = fs::read_dir(dir) else {
                        continue;
                    };
                    for entry in entries.flatten() {
                        let name = entry.file_name().to_string_lossy().into_owned();
                        if wildcard(&alt, &name) {
                            next.push(entry.path());
                        }
                    }
                } else {
                    let candidate = dir.join(&alt);
                    if candidate.exists() {
                        next.push(candidate);
                    }
                }
            }
        }
        current = next;
        if current.is_empty() {
            return false;
        }
    }
    current.iter().any(|p| !want_dir || p.is_dir())
}

/// `file`'s folder joined with `target`, without `..` and `.` components,
/// relative to the repository (None when it leaves the repository).
fn resolve(file: &Path, target: &str) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    let joined = file.parent().unwrap_or(Path::new("")).join(target);
    for component in joined.components() {
        match component {
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::CurDir => {}
            Component::Normal(c) => out.push(c),
            _ => return None,
        }
    }
    Some(out)
}

/// The `[[bin]]` names of a manifest (`name = "…"` after each `[[bin]]`).
fn manifest_bins(manifest: &str) -> Vec<String> {
    let mut bins = Vec::new();
    let mut in_bin = false;
    for line in manifest.lines().map(str::trim) {
        if line.starts_with('[') {
            in_bin = line == "[[bin]]";
        } else if in_bin {
            if let Some(name) = line.strip_prefix("name").map(str::trim) {
                if let Some(name) = name.strip_prefix('=') {
                    bins.push(name.trim().trim_matches('"').to_string());
                }
            }
        }
    }
    bins
}

/// The `[package]` name of a manifest.
fn package_name(manifest: &str) -> String {
    let mut in_package = false;
    for line in manifest.lines().map(str::trim) {
        if line.starts_with('[') {
            in_package = line == "[package]";
        } else if in_package {
            if let Some(rest) = line.strip_prefix("name") {
                if let Some(name) = rest.trim().strip_prefix('=') {
                    return name.trim().trim_matches('"').to_string();
                }
            }
        }
    }
    panic!("a manifest without [package] name")
}

fn read(path: &str) -> String {
    fs::read_to_string(repo().join(path)).unwrap_or_else(|e| panic!("read {path}: {e}"))
}

/// The binaries of the workspace: (root package's, tools package's).
fn binaries() -> (BTreeSet<String>, BTreeSet<String>) {
    let root_manifest = read("Cargo.toml");
    let mut root: BTreeSet<String> = manifest_bins(&root_manifest).into_iter().collect();
    if repo().join("src/main.rs").is_file() {
        root.insert(package_name(&root_manifest));
    }
    if let Ok(entries) = fs::read_dir(repo().join("src/bin")) {
        for entry in entries.flatten() {
            let path = entry.path();
            if path.extension().is_some_and(|e| e == "rs") {
                root.insert(path.file_stem().unwrap().to_string_lossy().into_owned());
            } else if path.join("main.rs").is_file() {
                root.insert(entry.file_name().to_string_lossy().into_owned());
            }
        }
    }
    let tools = manifest_bins(&read(TOOLS_MANIFEST)).into_iter().collect();
    (root, tools)
}

/// The word after `flag ` in `command`, if any.
fn flag_values<'a>(command: &'a str, flag: &str) -> Vec<&'a str> {
    let mut values = Vec::new();
    let words: Vec<&str> = command.split_whitespace().collect();
    for pair in words.windows(2) {
        if pair[0] == flag {
            values.push(
                pair[1].trim_matches(|c: char| !c.is_ascii_alphanumeric() && c != '_' && c != '-'),
            );
        }
    }
    values
}

fn is_upper_placeholder(name: &str) -> bool {
    name.chars().any(|c| c.is_ascii_uppercase())
        && name
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
}

/// The root package's test targets: tests/NAME.rs and tests/NAME/main.rs.
fn test_targets() -> BTreeSet<String> {
    let mut targets = BTreeSet::new();
    for entry in fs::read_dir(repo().join("tests"))
        .expect("read tests/")
        .flatten()
    {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "rs") {
            targets.insert(path.file_stem().unwrap().to_string_lossy().into_owned());
        } else if path.join("main.rs").is_file() {
            targets.insert(entry.file_name().to_string_lossy().into_owned());
        }
    }
    targets
}

/// What is wrong with the binaries and packages named in `text`.
fn check_commands(file: &Path, text: &str, problems: &mut Vec<String>) {
    let (root_bins, tools_bins) = binaries();
    let packages = [
        package_name(&read("Cargo.toml")),
        package_name(&read(TOOLS_MANIFEST)),
    ];
    let tests = test_targets();
    let at = |offset: usize| format!("{}:{}", file.display(), line_of(text, offset));

    for (offset, _) in text.match_indices("--bin ") {
        let name: String = text[offset + 6..]
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '-')
            .collect();
        if name.is_empty() || is_upper_placeholder(&name) {
            continue;
        }
        if !root_bins.contains(&name) && !tools_bins.contains(&name) {
            problems.push(format!("{}: `--bin {name}`: no such binary", at(offset)));
        }
    }

    for (offset, _) in text.match_indices("cargo run") {
        let rest = &text[offset..];
        let end = rest.find(['`', '\n']).unwrap_or(rest.len());
        let command = rest[..end].split(" -- ").next().unwrap_or_default();
        let mut package = None;
        for name in flag_values(command, "-p")
            .into_iter()
            .chain(flag_values(command, "--package"))
        {
            if !packages.iter().any(|p| p == name) {
                problems.push(format!("{}: `{command}`: no package {name}", at(offset)));
            }
            package = Some(name);
        }
        for bin in flag_values(command, "--bin") {
            if is_upper_placeholder(bin) {
                continue;
            }
            let wanted = if tools_bins.contains(bin) {
                Some(TOOLS_PACKAGE)
            } else if root_bins.contains(bin) {
                None
            } else {
                continue; // reported above
            };
            if wanted.is_some() && package != wanted {
                problems.push(format!(
                    "{}: `{command}`: {bin} is a binary of {TOOLS_PACKAGE}, which needs `-p {TOOLS_PACKAGE}`",
                    at(offset)
                ));
            }
        }
    }

    for (offset, _) in text.match_indices("cargo test") {
        let rest = &text[offset..];
        let end = rest.find(['`', '\n']).unwrap_or(rest.len());
        let command = rest[..end].split(" -- ").next().unwrap_or_default();
        if !flag_values(command, "-p").is_empty() {
            continue;
        }
        for name in flag_values(command, "--test") {
            if !is_upper_placeholder(name) && !tests.contains(name) {
                problems.push(format!(
                    "{}: `{command}`: no test target {name}",
                    at(offset)
                ));
            }
        }
    }
}

/// What is wrong with the paths and links named in `text`.
fn check_paths(file: &Path, text: &str, problems: &mut Vec<String>) {
    for (offset, path) in named_paths(text) {
        let quoted = text[..offset].ends_with('"');
        let found = exists(repo(), &path) || (quoted && exists(&repo().join("scenes"), &path));
        if !found {
            problems.push(format!(
                "{}:{}: `{path}` does not exist",
                file.display(),
                line_of(text, offset)
            ));
        }
    }
    for (offset, target) in link_targets(text) {
        let ok = resolve(file, &target).is_some_and(|p| exists(repo(), &p.to_string_lossy()));
        if !ok {
            problems.push(format!(
                "{}:{}: link `{target}` does not resolve to a file of the repository",
                file.display(),
                line_of(text, offset)
            ));
        }
    }
}

/// The identifiers (words) of every source file under `src/`, `shaders/`,
/// `tools/` and `tests/`, and their file and folder names.
fn source_words() -> BTreeSet<String> {
    fn walk(dir: &Path, words: &mut BTreeSet<String>) {
        let Ok(entries) = fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.ends_with("tests/cpu/docs.rs") {
                continue; // this file names what must not exist
            }
            let name = entry.file_name().to_string_lossy().into_owned();
            words.insert(name.split('.').next().unwrap_or_default().to_string());
            if path.is_dir() {
                walk(&path, words);
            } else if path
                .extension()
                .is_some_and(|e| e == "rs" || e == "wgsl" || e == "sh" || e == "py")
            {
                let text = fs::read_to_string(&path).unwrap_or_default();
                // Code, not comments: a name that only a comment still
                // mentions is gone.
                let text: String = text
                    .lines()
                    .map(|line| line.split("//").next().unwrap_or_default())
                    .collect::<Vec<_>>()
                    .join("\n");
                for word in text.split(|c: char| !c.is_ascii_alphanumeric() && c != '_') {
                    if !word.is_empty() {
                        words.insert(word.to_string());
                    }
                }
            }
        }
    }
    let mut words = BTreeSet::new();
    for root in ["src", "shaders", "tools", "tests"] {
        walk(&repo().join(root), &mut words);
    }
    words
}

/// Whether `span` is a Rust path (`a::b`, maybe `a::b()`), and, with
/// `snake` set, also a snake_case name (`load_scene`, `load_scene()`).
fn code_name(span: &str, snake: bool) -> bool {
    let name = span.strip_suffix("()").unwrap_or(span);
    let ident = |s: &str| {
        s.chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    if name.contains("::") {
        return name.split("::").all(ident);
    }
    snake
        && ident(name)
        && name.contains('_')
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

/// What is wrong with the code names in `text` (see the module doc).
fn check_code_names(file: &Path, text: &str, words: &BTreeSet<String>, problems: &mut Vec<String>) {
    let snake = ["README.md", "docs/architecture.md", "docs/design.md"]
        .iter()
        .any(|f| file == Path::new(f));
    let mut offset = 0;
    for (i, span) in text.split('`').enumerate() {
        let at = offset;
        offset += span.len() + 1;
        if i % 2 == 0 || span.contains('\n') || span.contains("foo") || !code_name(span, snake) {
            continue;
        }
        let missing: Vec<&str> = span
            .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
            .filter(|w| !w.is_empty() && !words.contains(*w))
            .collect();
        if !missing.is_empty() {
            problems.push(format!(
                "{}:{}: `{span}`: no {} in the sources",
                file.display(),
                line_of(text, at),
                missing.join(", ")
            ));
        }
    }
}

/// Every problem of README.md and docs/*.md.
fn problems() -> Vec<String> {
    let mut problems = Vec::new();
    let words = source_words();
    for (file, text) in documents() {
        check_paths(&file, &text, &mut problems);
        check_commands(&file, &text, &mut problems);
        check_code_names(&file, &text, &words, &mut problems);
    }
    problems
}

#[test]
fn every_path_link_binary_test_target_and_code_name_in_the_docs_exists() {
    let problems = problems();
    assert!(
        problems.is_empty(),
        "{} place(s) in the docs name what the repository does not have:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// The `mod x;` items of a test binary's main.rs.
fn modules(main: &str) -> BTreeSet<String> {
    main.lines()
        .map(str::trim)
        .filter_map(|line| line.strip_prefix("mod "))
        .filter_map(|rest| rest.strip_suffix(';'))
        .map(str::to_string)
        .collect()
}

/// The backticked spans of `text`.
fn backticked(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

#[test]
fn docs_tests_md_lists_every_test_binary_and_module() {
    let tests_md = read("docs/tests.md");
    let row = |binary: &str| {
        tests_md
            .lines()
            .find(|line| line.starts_with(&format!("| `{binary}`")))
            .map(str::to_string)
    };
    let mut problems = Vec::new();
    let mut entries: Vec<PathBuf> = fs::read_dir(repo().join("tests"))
        .expect("read tests/")
        .map(|e| e.expect("read tests/").path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.extension().is_some_and(|e| e == "rs") {
            let binary = format!("tests/{name}");
            if row(&binary).is_none() {
                problems.push(format!("no row for the test binary {binary}"));
            }
        } else if path.join("main.rs").is_file() {
            let binary = format!("tests/{name}/main.rs");
            let Some(row) = row(&binary) else {
                problems.push(format!("no row for the test binary {binary}"));
                continue;
            };
            let cell = row.trim_end().trim_end_matches('|');
            let cell = cell.rsplit('|').next().unwrap_or_default();
            let listed: BTreeSet<String> = backticked(cell)
                .into_iter()
                .filter(|s| {
                    s.chars()
                        .next()
                        .is_some_and(|c| c.is_ascii_lowercase() || c == '_')
                        && s.chars()
                            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
                })
                .map(str::to_string)
                .collect();
            let declared = modules(&fs::read_to_string(path.join("main.rs")).unwrap());
            for missing in declared.difference(&listed) {
                problems.push(format!("{binary}: module `{missing}` is not in its row"));
            }
            for extra in listed.difference(&declared) {
                problems.push(format!(
                    "{binary}: its row names `{extra}`, which is no module"
                ));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "docs/tests.md does not list the test modules as they are:\n{}",
        problems.join("\n")
    );
}

/// The rules catch what they are meant to catch (a planted bad path, a
/// glob, a placeholder, a link, a tools binary run without its package).
#[test]
fn the_rules_find_planted_drift() {
    let file = Path::new("docs/planted.md");
    let mut problems = Vec::new();
    let text = "See `tools/no_such_tool.rs`, [a link](gone.md), src/**/nothing*.rs \
                and `cargo run --release --bin bench`; `--bin nosuch`.\n\
                Fine: `src/lib.rs`, [tests](tests.md#x), `shaders/stages/*.wgsl`, \
                `tests/<binary>/main.rs`, `DIR/shaders/x.wgsl`, `target/x`, docs/, \
                `git show b43f463:tools/gone.patch`.\n";
    check_paths(file, text, &mut problems);
    check_commands(file, text, &mut problems);
    let words = source_words();
    let code = "`Renderer::render_passes` and `Renderer::render`; `intersect_foo`.";
    check_code_names(
        Path::new("docs/architecture.md"),
        code,
        &words,
        &mut problems,
    );
    let joined = problems.join("\n");
    for expected in [
        "`tools/no_such_tool.rs` does not exist",
        "link `gone.md`",
        "nothing*.rs` does not exist",
        "bench is a binary of penumbra-tools",
        "`--bin nosuch`: no such binary",
        "`Renderer::render_passes`: no render_passes in the sources",
    ] {
        assert!(
            joined.contains(expected),
            "not found: {expected}\nin:\n{joined}"
        );
    }
    assert_eq!(problems.len(), 6, "more than the planted drift:\n{joined}");
}

/// The README's test command is the line CI runs (`.ci/run`, after "The
/// README's test command:"), so that what a newcomer runs is what CI runs.
#[test]
fn the_readme_shows_the_test_command_ci_runs() {
    let ci = read(".ci/run");
    let mut lines = ci
        .lines()
        .skip_while(|l| !l.contains("The README's test command"));
    lines.next();
    let command = lines
        .next()
        .expect(".ci/run: a line after \"The README's test command:\"");
    assert!(command.contains("cargo test"), ".ci/run runs {command:?}");
    let readme = read("README.md");
    assert!(
        readme.lines().any(|l| l.trim() == command.trim()),
        "README.md does not show the line CI runs: {command}"
    );
}

/// Every docs/*.md can be found from the README by following links.
#[test]
fn every_doc_is_reachable_from_the_readme() {
    let docs: Vec<(PathBuf, String)> = documents();
    let mut reached = BTreeSet::from([PathBuf::from("README.md")]);
    let mut queue = vec![PathBuf::from("README.md")];
    while let Some(file) = queue.pop() {
        let Some((_, text)) = docs.iter().find(|(f, _)| *f == file) else {
            continue;
        };
        for (_, target) in link_targets(text) {
            if let Some(path) = resolve(&file, &target) {
                if reached.insert(path.clone()) {
                    queue.push(path);
                }
            }
        }
    }
    let orphans: Vec<String> = docs
        .iter()
        .map(|(f, _)| f)
        .filter(|f| !reached.contains(*f))
        .map(|f| f.display().to_string())
        .collect();
    assert!(
        orphans.is_empty(),
        "no link leads from README.md to {orphans:?}"
    );
}

/// The README's library example ("As a library"), compiled here so that it
/// follows the library's API; not run (it needs a device: the GPU tests
/// render the same way).
#[allow(dead_code)]
#[rustfmt::skip]
fn library_example() -> anyhow::Result<()> {
    // README begin
    use penumbra::{loaders, output, render::{Renderer, RendererOptions}};
    let loaded = loaders::load_scene("scenes/showcase.json".as_ref(), &Default::default())?;
    let mut renderer = Renderer::new(&RendererOptions::default())?; // once
    let frame = renderer.render_scene(&loaded.scene)?;               // per scene
    output::write_image("showcase.png".as_ref(), &frame.image)?;
    // README end
    Ok(())
}

/// The README's `rust` block is [`library_example`]'s body, line for line.
#[test]
fn the_readme_library_example_is_the_compiled_one() {
    let source = read("tests/cpu/docs.rs");
    let begin = "// README begin\n";
    let start = source.find(begin).expect("the begin marker") + begin.len();
    let end = start
        + source[start..]
            .find("// README end")
            .expect("the end marker");
    let compiled: Vec<&str> = source[start..end]
        .trim_end()
        .lines()
        .map(str::trim)
        .collect();
    let readme = read("README.md");
    let start = readme
        .find("```rust\n")
        .expect("README.md: a ```rust block")
        + 8;
    let end = start + readme[start..].find("```").expect("the block's end");
    let shown: Vec<&str> = readme[start..end]
        .trim_end()
        .lines()
        .map(str::trim)
        .collect();
    assert_eq!(
        shown, compiled,
        "README.md's library example is not the one compiled here"
    );
}
