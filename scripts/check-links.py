#!/usr/bin/env python3
"""Link checker: every file a document or a generated report refers to is in the repository.

Usage: scripts/check-links.py PATH...   (files or directories; .md, .html, .txt are read)

It reports, one line each, and exits 1 when there is any:
- a relative link (Markdown `[text](target)`, `![alt](target)`, HTML `href=`/`src=`) whose
  target does not exist next to the file that has it;
- a path in backticks or plain text that names a file of the repository (`docs/...`,
  `crates/...`, `fixtures/...`, `scripts/...`, `benches/...`, `tests/...`, `README.md`) and is
  not in the repository;
- a reference to material that lives outside the repository: the paper's reading notes
  (`NOTES.md`), the design brief (`DESIGN.md`), the `shared/` directory of the development
  machine, or an issue number of the project's tracker (the word issue and a number).

Only the standard library: it runs wherever the tests run.
"""

import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SUFFIXES = {".md", ".html", ".txt"}

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)|(?:href|src)=\"([^\"]+)\"")
REPO_PATH = re.compile(
    r"(?<![\w./-])((?:docs|crates|fixtures|scripts|benches|tests)/[\w./-]*\w|README\.md)(?![\w/-])"
)
OUTSIDE = re.compile(r"\bNOTES\.md\b|\bDESIGN\.md\b|\bshared/(?:paper|protocol|data)\b|\bissues? \d+\b", re.I)


def files_under(paths):
    for p in paths:
        p = pathlib.Path(p)
        if p.is_dir():
            yield from sorted(f for f in p.rglob("*") if f.suffix in SUFFIXES and f.is_file())
        elif p.is_file():
            yield p
        else:
            raise SystemExit(f"check-links: no such file or directory: {p}")


def external(target):
    return re.match(r"^[a-z][a-z0-9+.-]*:", target) is not None or target.startswith("#")


def in_repository(path_text):
    # Globs (`docs/results/*.md`) and placeholders name families of files: the folder must exist.
    if any(c in path_text for c in "*<>{}"):
        return (ROOT / path_text.split("*")[0].split("<")[0].split("{")[0]).parent.exists()
    return (ROOT / path_text.rstrip(".")).exists()


def problems(path):
    text = path.read_text(encoding="utf-8", errors="replace")
    for n, line in enumerate(text.splitlines(), 1):
        where = f"{path}:{n}"
        for m in LINK.finditer(line):
            target = (m.group(1) or m.group(2)).split("#")[0]
            if target and not external(target) and not (path.parent / target).exists():
                yield f"{where}: link to a missing file: {target}"
        for m in REPO_PATH.finditer(line):
            if "://" in line[max(0, m.start() - 80) : m.start()]:
                continue  # part of a URL of another project
            if not in_repository(m.group(1)):
                yield f"{where}: names a file that is not in the repository: {m.group(1)}"
        for m in OUTSIDE.finditer(line):
            yield f"{where}: refers to something outside the repository: {m.group(0)!r}"


def main(argv):
    if not argv:
        raise SystemExit(__doc__.strip().splitlines()[2])
    found = [p for f in files_under(argv) for p in problems(f)]
    for p in found:
        print(p)
    print(f"check-links: {len(found)} problem(s)", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
