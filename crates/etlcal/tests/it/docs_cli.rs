//! docs/CLI.md against the command line itself: its verb table lists exactly the verbs
//! `etlcal --help` lists (and, for `thermal` and `lens`, their subcommands), and its
//! `calibrate` tables describe exactly the flags `etlcal calibrate --help` lists.

use std::collections::BTreeSet;
use std::path::Path;

use super::common::etlcal;

/// Flags docs/CLI.md describes ahead of the branch that adds them to `calibrate` (the one
/// calibration request shared with Python): they may be missing from `--help` until it is
/// merged, and must be described once it is.
const CALIBRATE_FLAGS_BEING_ADDED: &[&str] = &["--robust", "--robust-k-px", "--sigma-z-mm"];

/// Flags every verb has, documented once under "Conventions" rather than per verb.
const GLOBAL_FLAGS: &[&str] = &["--help", "--version", "--json", "--quiet"];

fn cli_md() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/CLI.md")).unwrap()
}

/// The text of `## {heading}` up to the next `## ` heading.
fn section<'a>(doc: &'a str, heading: &str) -> &'a str {
    let start = doc.find(&format!("\n## {heading}\n")).unwrap_or_else(|| panic!("docs/CLI.md has no ## {heading}"));
    let rest = &doc[start + heading.len() + 5..];
    rest.find("\n## ").map_or(rest, |end| &rest[..end])
}

fn help(args: &[&str]) -> String {
    let out = etlcal(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// The names of clap's `Commands:` list, without clap's own `help`.
fn subcommands(help_text: &str) -> BTreeSet<String> {
    let list = help_text.split("\nCommands:\n").nth(1).expect("a Commands: list");
    let lines = list.lines().take_while(|l| l.starts_with("  "));
    lines.filter_map(|l| l.split_whitespace().next()).filter(|&name| name != "help").map(str::to_owned).collect()
}

/// Every long flag of a `--help` (`  -o, --out <FILE>  ...`), with the aliases clap shows
/// (`[aliases: --a, --b]`).
fn long_flags(help_text: &str) -> BTreeSet<String> {
    let mut flags = BTreeSet::new();
    for line in help_text.lines() {
        let t = line.trim_start();
        // A short flag first (`-o, --out`): the long one follows it.
        let t = if t.len() > 4 && t.starts_with('-') && t.get(2..4) == Some(", ") { &t[4..] } else { t };
        if line.starts_with("  ") && t.starts_with("--") {
            flags.insert(t.split(|c: char| c.is_whitespace() || c == '=').next().unwrap().to_owned());
        }
        if let Some(aliases) = t.split("[aliases: ").nth(1) {
            let aliases = aliases.split(']').next().unwrap();
            flags.extend(aliases.split(", ").map(|a| a.trim().to_owned()).filter(|a| a.starts_with("--")));
        }
    }
    flags
}

/// The first cell of every row of the markdown tables in `text` (header and rule left out).
fn first_cells(text: &str) -> Vec<&str> {
    let rows = text.lines().filter(|l| l.starts_with("| "));
    let cells = rows.filter_map(|l| l.split(" | ").next()).map(|c| c.trim_start_matches("| ").trim());
    cells.filter(|c| c.starts_with('`')).collect()
}

#[test]
fn the_verb_table_lists_exactly_the_verbs_of_the_command_line() {
    let doc = cli_md();
    let table = section(&doc, "Verbs");
    let rows = first_cells(table);
    let documented: Vec<String> =
        rows.iter().map(|c| c.trim_matches('`').split_whitespace().nth(1).unwrap_or("").to_owned()).collect();
    let unique: BTreeSet<String> = documented.iter().cloned().collect();
    assert_eq!(unique.len(), documented.len(), "a verb listed twice in docs/CLI.md: {documented:?}");
    let clap = subcommands(&help(&["--help"]));
    assert!(clap.contains("undistort") && clap.contains("calibrate"), "{clap:?}");
    assert_eq!(unique, clap, "docs/CLI.md's verb table (left) against `etlcal --help` (right)");
    // A verb with subcommands names every one of them in its row.
    for verb in ["thermal", "lens"] {
        let row = rows.iter().find(|c| c.starts_with(&format!("`etlcal {verb} "))).unwrap();
        for sub in subcommands(&help(&[verb, "--help"])) {
            assert!(row.contains(&sub), "docs/CLI.md's {verb} row does not name `{verb} {sub}`: {row}");
        }
    }
}

#[test]
fn the_calibrate_tables_describe_exactly_the_flags_of_calibrate() {
    let doc = cli_md();
    let documented: Vec<String> = first_cells(section(&doc, "calibrate"))
        .iter()
        .map(|c| c.trim_matches('`').split_whitespace().next().unwrap().to_owned())
        .collect();
    let unique: BTreeSet<String> = documented.iter().cloned().collect();
    assert_eq!(unique.len(), documented.len(), "a calibrate flag described twice: {documented:?}");
    let clap: BTreeSet<String> = long_flags(&help(&["calibrate", "--help"]))
        .into_iter()
        .filter(|f| !GLOBAL_FLAGS.contains(&f.as_str()))
        .collect();
    assert!(clap.contains("--huber-px") && clap.contains("--thermal"), "the help was not parsed: {clap:?}");
    let missing: Vec<&String> = clap.difference(&unique).collect();
    assert!(missing.is_empty(), "calibrate flags docs/CLI.md does not describe: {missing:?}");
    let extra: Vec<&String> =
        unique.difference(&clap).filter(|f| !CALIBRATE_FLAGS_BEING_ADDED.contains(&f.as_str())).collect();
    assert!(extra.is_empty(), "docs/CLI.md describes calibrate flags the command line does not have: {extra:?}");
}

#[test]
fn the_help_parsers_read_clap_s_layout() {
    let text = "Usage: x\n\nCommands:\n  demo   The demo\n  lens-sim  Serve\n  help   Print\n\nOptions:\n  \
                -o, --out <FILE>  Out\n      --robust-k-px <PX>  K [aliases: --huber-px]\n      --json\n";
    assert_eq!(subcommands(text), BTreeSet::from(["demo".to_owned(), "lens-sim".to_owned()]));
    let flags: Vec<String> = long_flags(text).into_iter().collect();
    assert_eq!(flags, ["--huber-px", "--json", "--out", "--robust-k-px"]);
    let md = "| verb | what |\n|---|---|\n| `etlcal demo [--out DIR]` | a \\| b |\n| plain | no |\n";
    assert_eq!(first_cells(md), ["`etlcal demo [--out DIR]`"]);
}
