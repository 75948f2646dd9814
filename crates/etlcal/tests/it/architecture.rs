//! The layout rules of the workspace, checked on its sources so that CI keeps them:
//! - no two top-level modules of a crate import each other (`crate::a` in `b` and
//!   `crate::b` in `a`, outside tests and comments): each layer depends on the ones below;
//! - no function outside tests is longer than 100 lines (one screen, read at once);
//! - the command line is the `etlcal` crate's alone (no other crate depends on it, on clap
//!   or on indicatif), and plotting is the report crate's (plotters).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_FN_LINES: usize = 100;

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

/// Every crate directory under crates/.
fn crates() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(workspace().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    v.sort();
    v
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The source without its `#[cfg(test)]` part (by this workspace's convention the test
/// module ends a file) and with each line's `//` comment removed (string literals are
/// kept whole: a `//` inside quotes is not a comment).
fn code_lines(text: &str) -> Vec<String> {
    let body = text.split("#[cfg(test)]").next().unwrap_or("");
    body.lines().map(strip_comment).collect()
}

fn strip_comment(line: &str) -> String {
    let (mut out, mut in_str, mut prev) = (String::new(), false, ' ');
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        if !in_str && c == '/' && chars.peek() == Some(&'/') {
            break;
        }
        if c == '"' && prev != '\\' && prev != '\'' {
            in_str = !in_str;
        }
        out.push(c);
        prev = if prev == '\\' && c == '\\' { ' ' } else { c };
    }
    out
}

/// The top-level module a file of `src` belongs to (`lib` for the crate root).
fn top_module(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
    first.trim_end_matches(".rs").to_owned()
}

#[test]
fn no_two_modules_of_a_crate_import_each_other() {
    let mut cycles = vec![];
    for krate in crates() {
        let src = krate.join("src");
        let mut files = vec![];
        rust_files(&src, &mut files);
        let mut edges: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
        for f in &files {
            let from = top_module(&src, f);
            let text = std::fs::read_to_string(f).unwrap();
            for (n, line) in code_lines(&text).iter().enumerate() {
                for part in line.split("crate::").skip(1) {
                    let to: String = part.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                    if !to.is_empty() && to != from {
                        let at = format!("{}:{}", f.strip_prefix(&krate).unwrap().display(), n + 1);
                        edges.entry(from.clone()).or_default().entry(to).or_insert(at);
                    }
                }
            }
        }
        for (a, tos) in &edges {
            for (b, at) in tos {
                if let Some(back) = edges.get(b).and_then(|m| m.get(a)).filter(|_| a < b) {
                    cycles.push(format!("{}: {a} -> {b} ({at}), {b} -> {a} ({back})", krate.display()));
                }
            }
        }
    }
    assert!(cycles.is_empty(), "modules importing each other:\n{}", cycles.join("\n"));
}

/// The functions of `lines` longer than [`MAX_FN_LINES`]: from the line of `fn NAME` to
/// the line of its closing brace (braces counted outside string and char literals).
fn long_functions(lines: &[String]) -> Vec<(usize, String, usize)> {
    let mut out = vec![];
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim_start();
        let is_fn = ["fn ", "pub fn ", "pub(crate) fn ", "const fn ", "pub const fn ", "async fn ", "unsafe fn "]
            .iter()
            .any(|p| t.starts_with(p));
        if !is_fn {
            continue;
        }
        let name: String = t.split("fn ").nth(1).unwrap_or("").chars().take_while(|c| *c != '(' && *c != '<').collect();
        let (mut depth, mut opened) = (0i64, false);
        for (j, l) in lines.iter().enumerate().skip(i) {
            for c in braces(l) {
                depth += if c == '{' { 1 } else { -1 };
                opened = true;
            }
            if !opened && l.trim_end().ends_with(';') {
                break; // a declaration without a body (a trait's)
            }
            if opened && depth <= 0 {
                if j + 1 - i > MAX_FN_LINES {
                    out.push((i + 1, name.clone(), j + 1 - i));
                }
                break;
            }
        }
    }
    out
}

/// The braces of a line outside string and char literals.
fn braces(line: &str) -> Vec<char> {
    let (mut out, mut in_str, mut prev) = (vec![], false, ' ');
    let chars: Vec<char> = line.chars().collect();
    for (k, &c) in chars.iter().enumerate() {
        if c == '"' && prev != '\\' {
            in_str = !in_str;
        } else if !in_str && (c == '{' || c == '}') {
            let quoted = k > 0 && chars[k - 1] == '\'' && chars.get(k + 1) == Some(&'\'');
            if !quoted {
                out.push(c);
            }
        }
        prev = if prev == '\\' && c == '\\' { ' ' } else { c };
    }
    out
}

#[test]
fn no_function_outside_tests_is_longer_than_100_lines() {
    let mut long = vec![];
    for krate in crates() {
        let mut files = vec![];
        rust_files(&krate.join("src"), &mut files);
        files.sort();
        for f in files {
            // Generated tables (the ArUco dictionaries) are data, not functions to read.
            if f.ends_with("board/dictionary/data.rs") {
                continue;
            }
            let lines = code_lines(&std::fs::read_to_string(&f).unwrap());
            for (line, name, n) in long_functions(&lines) {
                long.push(format!("{}:{line} fn {name}: {n} lines", f.display()));
            }
        }
    }
    assert!(long.is_empty(), "functions over {MAX_FN_LINES} lines:\n{}", long.join("\n"));
}

/// The names in a Cargo.toml's `[dependencies]` table (not dev- or build-dependencies).
fn normal_dependencies(manifest: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(manifest).unwrap();
    let mut deps = BTreeSet::new();
    let mut in_deps = false;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_deps = t == "[dependencies]";
            continue;
        }
        if in_deps && !t.is_empty() && !t.starts_with('#') {
            let name = t.split(['=', '.', ' ']).next().unwrap().trim();
            deps.insert(name.to_owned());
        }
    }
    deps
}

#[test]
fn the_command_line_and_the_plots_each_have_one_crate() {
    for krate in crates() {
        let name = krate.file_name().unwrap().to_string_lossy().into_owned();
        let deps = normal_dependencies(&krate.join("Cargo.toml"));
        if name != "etlcal" {
            for cli in ["etlcal", "clap", "indicatif"] {
                assert!(!deps.contains(cli), "{name} depends on {cli}: the command line is the etlcal crate's");
            }
        }
        if name != "etl-report" {
            assert!(!deps.contains("plotters"), "{name} depends on plotters: plotting is etl-report's");
        }
    }
}

/// The checks themselves: a cycle, a long function and a brace in a string are seen.
#[test]
fn the_checks_see_what_they_look_for() {
    let body: Vec<String> = std::iter::once("fn long() {".to_owned())
        .chain((0..MAX_FN_LINES).map(|_| "    let s = \"{\"; // }".to_owned()))
        .chain(std::iter::once("}".to_owned()))
        .map(|l| strip_comment(&l))
        .collect();
    assert_eq!(long_functions(&body), vec![(1, "long".to_owned(), MAX_FN_LINES + 2)]);
    let short: Vec<String> = ["fn f() {", "    g('{');", "}"].iter().map(|s| s.to_string()).collect();
    assert!(long_functions(&short).is_empty());
    assert_eq!(strip_comment("let a = \"//x\"; // y"), "let a = \"//x\"; ");
}
