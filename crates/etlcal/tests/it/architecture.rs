//! The layout rules of the workspace, checked on its sources so that CI keeps them:
//! - no two sibling modules of a crate, at any depth, import each other (`a` names a path
//!   into `b` and `b` one into `a`, through `crate::`, `super::` or `self::` and through
//!   re-exports, outside tests and comments): each layer depends on the ones below;
//! - no function outside tests is longer than 100 lines (one screen, read at once);
//! - the command line is the `etlcal` crate's alone (no other crate depends on it, on clap
//!   or on indicatif), and plotting is the report crate's (plotters);
//! - every Python constructor and special method of the extension catches its panics
//!   (`etl-py`'s `errors::guarded`; `etlcal._guard` covers the rest from Python).

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

/// A module of a crate: its path from the crate root (`[]` for the root, `["undistort",
/// "maps"]` for `src/undistort/maps.rs` or `src/undistort/maps/mod.rs`), the file it is
/// read from (for messages) and its code ([`code_lines`] joined).
struct Module {
    path: Vec<String>,
    file: String,
    code: String,
}

/// The module path of the file `rel` (relative to `src/`).
fn module_path(rel: &Path) -> Vec<String> {
    let mut path: Vec<String> =
        rel.components().map(|c| c.as_os_str().to_string_lossy().trim_end_matches(".rs").to_owned()).collect();
    let last = path.last().map(String::as_str);
    if last == Some("mod") || (path.len() == 1 && matches!(last, Some("lib" | "main"))) {
        path.pop();
    }
    path
}

/// The names of the child modules a file declares only for tests (`#[cfg(test)] mod tests;`):
/// their files are tests, not layers.
fn test_only_children(text: &str) -> Vec<String> {
    text.split("#[cfg(test)]")
        .skip(1)
        .filter_map(|rest| {
            let decl = rest.trim_start().strip_prefix("mod ")?;
            let name: String = decl.chars().take_while(|c| is_ident(*c)).collect();
            decl[name.len()..].trim_start().starts_with(';').then_some(name)
        })
        .collect()
}

/// The modules of a crate given as (path relative to `src/`, source text) pairs.
fn modules_of(sources: &[(PathBuf, String)]) -> Vec<Module> {
    let mut test_only = BTreeSet::new();
    for (rel, text) in sources {
        for child in test_only_children(text) {
            let mut p = module_path(rel);
            p.push(child);
            test_only.insert(p);
        }
    }
    sources
        .iter()
        .map(|(rel, text)| Module {
            path: module_path(rel),
            file: rel.display().to_string(),
            code: code_lines(text).join("\n"),
        })
        .filter(|m| !test_only.contains(&m.path))
        .collect()
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// A path of a use tree and its alias (`as NAME`).
type Leaf = (Vec<String>, Option<String>);

/// Each module's re-exports: module path -> (name -> the absolute path it stands for).
type Exports = BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>>;

/// Parses the use tree (or plain path) that starts at `at` in `code`: segments joined by
/// `::`, possibly ending in a `{...}` group of trees, `*`, or `as NAME`. Returns every leaf
/// path with its alias (`as`), and the position after the tree.
fn parse_tree(code: &[char], mut at: usize) -> (Vec<Leaf>, usize) {
    let skip_ws = |i: &mut usize| {
        while *i < code.len() && code[*i].is_whitespace() {
            *i += 1;
        }
    };
    let mut path = vec![];
    loop {
        skip_ws(&mut at);
        if at < code.len() && code[at] == '{' {
            let mut leaves = vec![];
            at += 1;
            loop {
                skip_ws(&mut at);
                if at >= code.len() || code[at] == '}' {
                    return (leaves, at + 1);
                }
                let (sub, next) = parse_tree(code, at);
                for (mut p, alias) in sub {
                    p = path.iter().cloned().chain(p.into_iter().filter(|s| s != "self")).collect();
                    leaves.push((p, alias));
                }
                at = next;
                skip_ws(&mut at);
                if at < code.len() && code[at] == ',' {
                    at += 1;
                } else if at >= code.len() || code[at] != '}' {
                    return (leaves, at); // not a use group (e.g. a struct literal): stop here
                }
            }
        }
        let start = at;
        while at < code.len() && (is_ident(code[at]) || code[at] == '$' || code[at] == '*') {
            at += 1;
        }
        if at > start {
            path.push(code[start..at].iter().collect::<String>());
        }
        if at + 1 < code.len() && code[at] == ':' && code[at + 1] == ':' {
            at += 2;
            continue;
        }
        break;
    }
    let mut alias = None;
    let mut after = at;
    skip_ws(&mut after);
    if code[after..].starts_with(&['a', 's', ' ']) {
        let (named, next) = parse_tree(code, after + 3);
        alias = named.into_iter().next().and_then(|(p, _)| p.into_iter().next());
        at = next;
    }
    (vec![(path, alias)], at)
}

/// `path` as written in the module `from` (starting with `crate`, `$crate`, `super` or
/// `self`) made absolute: the segments from the crate root. None for other paths.
fn absolute(from: &[String], path: &[String]) -> Option<Vec<String>> {
    let (mut base, mut rest) = match path.first().map(String::as_str) {
        Some("crate" | "$crate") => (vec![], &path[1..]),
        Some("self") => (from.to_vec(), &path[1..]),
        Some("super") => (from.to_vec(), path),
        _ => return None,
    };
    while rest.first().map(String::as_str) == Some("super") {
        base.pop()?;
        rest = &rest[1..];
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// The paths a module's code names through `crate::`, `super::` or `self::` (use groups
/// expanded), made absolute, with the line they are on.
fn named_paths(m: &Module) -> Vec<(Vec<String>, usize)> {
    let code: Vec<char> = m.code.chars().collect();
    let (mut out, mut i) = (vec![], 0);
    while i < code.len() {
        let starts =
            ["crate::", "super::", "self::"].iter().any(|p| code[i..].starts_with(&p.chars().collect::<Vec<_>>()));
        if !starts || (i > 0 && is_ident(code[i - 1])) {
            i += 1;
            continue;
        }
        let line = code[..i].iter().filter(|c| **c == '\n').count() + 1;
        let (leaves, next) = parse_tree(&code, i);
        out.extend(leaves.iter().filter_map(|(p, _)| absolute(&m.path, p)).map(|p| (p, line)));
        i = next.max(i + 1);
    }
    out
}

/// Each module's re-exports (`pub use` and `pub(crate) use`, not globs): name -> the
/// absolute path it stands for (a first segment naming a child module is relative to the
/// module; one naming anything else is another crate's, left out).
fn re_exports(modules: &[Module]) -> Exports {
    let known: BTreeSet<&Vec<String>> = modules.iter().map(|m| &m.path).collect();
    let mut out = Exports::new();
    for m in modules {
        let code: Vec<char> = m.code.chars().collect();
        for (k, _) in m.code.match_indices("pub use ").chain(m.code.match_indices("pub(crate) use ")) {
            let at = m.code[..k].chars().count() + m.code[k..].find("use ").unwrap() + 4;
            for (p, alias) in parse_tree(&code, at).0 {
                let child: Vec<String> = m.path.iter().chain(p.first()).cloned().collect();
                let abs =
                    absolute(&m.path, &p).or_else(|| known.contains(&child).then(|| [&m.path[..], &p[..]].concat()));
                if let (Some(abs), Some(name)) = (abs, alias.or_else(|| p.last().cloned())) {
                    if name != "*" {
                        out.entry(m.path.clone()).or_default().insert(name, abs);
                    }
                }
            }
        }
    }
    out
}

/// The module an absolute path lands in: the longest prefix that is a module, following
/// re-exports (`crate::undistort::Sample` is `undistort::remap`'s `Sample`).
fn resolve(path: &[String], known: &BTreeSet<&Vec<String>>, exports: &Exports, depth: usize) -> Vec<String> {
    let mut cur: Vec<String> = vec![];
    for (k, seg) in path.iter().enumerate() {
        let mut next = cur.clone();
        next.push(seg.clone());
        if known.contains(&next) {
            cur = next;
        } else if let Some(target) = exports.get(&cur).and_then(|e| e.get(seg)).filter(|_| depth < 8) {
            let rest: Vec<String> = target.iter().chain(&path[k + 1..]).cloned().collect();
            return resolve(&rest, known, exports, depth + 1);
        } else {
            break;
        }
    }
    cur
}

/// Every pair of sibling modules (children of one parent, at any depth) that import each
/// other: `a` names (a path into) `b` and `b` names `a`, each directly or from a module
/// inside it. A module may import its ancestors and descendants freely.
fn sibling_cycles(modules: &[Module]) -> Vec<String> {
    let known: BTreeSet<&Vec<String>> = modules.iter().map(|m| &m.path).collect();
    let exports = re_exports(modules);
    // (a, b) -> where a first names b; a and b siblings.
    let mut edges: BTreeMap<(Vec<String>, Vec<String>), String> = BTreeMap::new();
    for m in modules {
        for (p, line) in named_paths(m) {
            let to = resolve(&p, &known, &exports, 0);
            let common = m.path.iter().zip(&to).take_while(|(a, b)| a == b).count();
            if common < m.path.len() && common < to.len() {
                let key = (m.path[..=common].to_vec(), to[..=common].to_vec());
                edges.entry(key).or_insert_with(|| format!("{}:{line}", m.file));
            }
        }
    }
    let mut cycles = vec![];
    for ((a, b), at) in &edges {
        if let Some(back) = edges.get(&(b.clone(), a.clone())).filter(|_| a < b) {
            cycles.push(format!(
                "{} -> {} ({at}), {} -> {} ({back})",
                a.join("::"),
                b.join("::"),
                b.join("::"),
                a.join("::")
            ));
        }
    }
    cycles
}

#[test]
fn no_two_sibling_modules_import_each_other() {
    let mut cycles = vec![];
    for krate in crates() {
        let src = krate.join("src");
        let mut files = vec![];
        rust_files(&src, &mut files);
        files.sort();
        let sources: Vec<(PathBuf, String)> = files
            .iter()
            .map(|f| (f.strip_prefix(&src).unwrap().to_path_buf(), std::fs::read_to_string(f).unwrap()))
            .collect();
        for c in sibling_cycles(&modules_of(&sources)) {
            cycles.push(format!("{}: {c}", krate.file_name().unwrap().to_string_lossy()));
        }
    }
    assert!(cycles.is_empty(), "sibling modules importing each other:\n{}", cycles.join("\n"));
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

/// The modules of in-memory sources: (path relative to `src/`, text).
fn in_memory(sources: &[(&str, &str)]) -> Vec<Module> {
    let owned: Vec<(PathBuf, String)> = sources.iter().map(|(p, t)| (PathBuf::from(p), t.to_string())).collect();
    modules_of(&owned)
}

/// The cycle check sees the two cycles etl-core's `undistort` had before issue 26 (shaped
/// as that code was: a `super::` use line, a `super::` path in an expression), and not the
/// layout that replaced them, where each former sibling is its partner's child.
#[test]
fn the_cycle_check_sees_the_sibling_cycles_of_before() {
    let before = in_memory(&[
        ("lib.rs", "pub mod model;\npub mod undistort;\n"),
        ("model/mod.rs", "pub mod camera;\npub use camera::Intrinsics;\n"),
        ("model/camera.rs", "pub struct Intrinsics;\n"),
        ("undistort/mod.rs", "mod bilinear;\npub mod camera;\npub mod maps;\nmod opencv_maps;\npub mod remap;\n"),
        ("undistort/camera.rs", "use crate::error::{Error, Result};\nuse crate::model::Intrinsics;\n"),
        ("undistort/bilinear.rs", "// use super::maps::x;\nuse super::remap::{Sample, SourceImage};\n"),
        (
            "undistort/remap.rs",
            "use super::bilinear::{remap_block, Positions,\n    Taps};\nuse super::camera::check_side;\n",
        ),
        (
            "undistort/maps.rs",
            "use super::camera::OutputCamera;\nfn f() {\n    for_each_row(w, &super::opencv_maps::OpenCvRow::new(k, d, out));\n}\n",
        ),
        ("undistort/opencv_maps.rs", "use super::camera::OutputCamera;\nuse super::maps::FillRow;\n"),
    ]);
    assert_eq!(
        sibling_cycles(&before),
        vec![
            "undistort::bilinear -> undistort::remap (undistort/bilinear.rs:2), \
             undistort::remap -> undistort::bilinear (undistort/remap.rs:1)",
            "undistort::maps -> undistort::opencv_maps (undistort/maps.rs:3), \
             undistort::opencv_maps -> undistort::maps (undistort/opencv_maps.rs:2)",
        ]
    );
    let after = in_memory(&[
        ("undistort/mod.rs", "pub mod maps;\npub mod pinhole;\npub mod remap;\npub use remap::Sample;\n"),
        ("undistort/pinhole.rs", "use crate::model::Intrinsics;\n"),
        ("undistort/remap/mod.rs", "mod bilinear;\nuse bilinear::{remap_block};\nuse super::pinhole::check_side;\n"),
        ("undistort/remap/bilinear.rs", "use super::{Sample, SourceImage};\n"),
        (
            "undistort/maps/mod.rs",
            "mod opencv;\nuse super::pinhole::OutputCamera;\nlet r = opencv::OpenCvRow::new();\n",
        ),
        ("undistort/maps/opencv.rs", "use crate::undistort::pinhole::OutputCamera;\nuse super::FillRow;\n"),
    ]);
    assert_eq!(sibling_cycles(&after), Vec::<String>::new());
}

/// The paths the check follows: `crate::` groups over several lines, `self::`,
/// `super::super::`, `$crate::` in macros and re-exports (with `as`); a cycle between two
/// deep modules is reported under their parent; tests and child modules declared for tests
/// only are left out.
#[test]
fn the_cycle_check_follows_every_path_form() {
    let cycle = |a: &str, b: &str| {
        let m = in_memory(&[("lib.rs", ""), ("x/mod.rs", ""), ("x/y/mod.rs", ""), ("x/y/a.rs", a), ("x/y/b.rs", b)]);
        sibling_cycles(&m)
    };
    let back = "use super::a::F;";
    assert_eq!(cycle("use crate::{\n    x::y::b::G,\n    z,\n};", back).len(), 1);
    assert_eq!(cycle("use super::super::y::b;", back).len(), 1);
    assert_eq!(cycle("macro_rules! m { () => { $crate::x::y::b::G } }", back).len(), 1);
    assert_eq!(cycle("use self::super::b::G;", back).len(), 1);
    assert_eq!(cycle("use super::b;", "#[cfg(test)]\nmod tests { use super::super::a; }").len(), 0);
    assert_eq!(cycle("let s = \"crate\"; // crate::x::y::b", back).len(), 0);
    // Through re-exports: `crate::x::y::G` is b's G, `crate::x::B` is module b.
    let via = in_memory(&[
        ("lib.rs", ""),
        ("x/mod.rs", "pub use y::b as bee;\n"),
        ("x/y/mod.rs", "mod a;\nmod b;\npub use b::{G, H as I};\n#[cfg(test)]\nmod tests;\n"),
        ("x/y/a.rs", "fn f() -> crate::x::y::I { crate::x::bee::g() }"),
        ("x/y/b.rs", "use super::a;"),
        ("x/y/tests.rs", "use super::b; use super::a;"),
    ]);
    assert_eq!(sibling_cycles(&via), vec!["x::y::a -> x::y::b (x/y/a.rs:1), x::y::b -> x::y::a (x/y/b.rs:1)"]);
    assert_eq!(module_path(Path::new("lib.rs")), Vec::<String>::new());
    assert_eq!(module_path(Path::new("a/b/mod.rs")), vec!["a", "b"]);
}

/// The Python constructors (`#[new]`) and special methods (`fn __x__`) of `lines` whose body
/// does not start with `guarded(` or `guarded_value(`: (line, name).
fn unguarded_entry_points(lines: &[String]) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut after_new = false;
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim();
        after_new |= t == "#[new]";
        let Some(rest) = t.strip_prefix("fn ") else { continue };
        let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        let entry = std::mem::take(&mut after_new) || (name.starts_with("__") && name.ends_with("__"));
        let Some(open) = (i..lines.len()).find(|&k| lines[k].trim_end().ends_with('{')) else { continue };
        let first = lines[open + 1..].iter().map(|l| l.trim()).find(|l| !l.is_empty()).unwrap_or("");
        if entry && !(first.contains("guarded(") || first.contains("guarded_value(")) {
            out.push((i + 1, name));
        }
    }
    out
}

/// A panic in a constructor or a special method would reach Python as pyo3's
/// PanicException (a BaseException that `except Exception` misses): each one's body goes
/// through `errors::guarded`, which turns it into `etlcal.Error` with a report.
#[test]
fn every_python_constructor_and_special_method_catches_its_panics() {
    let mut files = Vec::new();
    rust_files(&workspace().join("crates/etl-py/src"), &mut files);
    let mut missing = Vec::new();
    for f in &files {
        let lines = code_lines(&std::fs::read_to_string(f).unwrap());
        for (line, name) in unguarded_entry_points(&lines) {
            missing.push(format!("{}:{line} {name}", f.display()));
        }
    }
    assert!(missing.is_empty(), "not through errors::guarded: {missing:?}");
    let sample = |body: &str| -> Vec<String> { body.lines().map(strip_comment).collect() };
    let bad = sample("#[new]\n#[pyo3(signature = (a))]\nfn new(a: u8) -> Self {\n    Self { a }\n}\nfn __len__(&self) -> usize {\n    0\n}\nfn other(&self) {\n}");
    assert_eq!(unguarded_entry_points(&bad), vec![(3, "new".to_owned()), (6, "__len__".to_owned())]);
    let good = sample(
        "fn __repr__(\n    &self,\n) -> PyResult<String> {\n    guarded_value(\"X.__repr__\", || String::new())\n}",
    );
    assert!(unguarded_entry_points(&good).is_empty());
}
