"""docs/BENCHMARKS.md from its template and the results of one run (standard library only).

The document is never edited by hand: `benches/BENCHMARKS.md.in` holds the prose, with
placeholders where figures go, and `docs/benchmarks.json` the figures of the last run of
`benches/all.sh`. Placeholders:

    {{table:SECTION.NAME}}   a Markdown table the section produced
    {{value:SECTION.NAME}}   one figure (already formatted, with its unit)
    {{run:SECTION}}          when, at which commit and under which load the section ran
    {{meta:KEY}}             the run's machine, versions and date

The template must not state a measured figure itself: `template_figures` finds times and
speed ratios outside placeholders (the test suite runs it), so every figure the document
gives is one the command produced.
"""
import json
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parent.parent
TEMPLATE = ROOT / "benches" / "BENCHMARKS.md.in"
RESULTS = ROOT / "docs" / "benchmarks.json"
DOCUMENT = ROOT / "docs" / "BENCHMARKS.md"

PLACEHOLDER = re.compile(r"\{\{(table|value|run|meta):([A-Za-z0-9_.-]+)\}\}")
# A time with its unit, or a speed ratio such as "4.2x": what a benchmark measures.
FIGURE = re.compile(r"(?<![\w.])\d+(?:\.\d+)?\s?(?:ns|us|µs|ms|s)\b|(?<![\w.])\d+(?:\.\d+)?x\b")


def table_markdown(table: dict) -> str:
    """`{"header": [...], "rows": [[...], ...]}` as a Markdown table."""
    lines = ["| " + " | ".join(table["header"]) + " |", "|" + "---|" * len(table["header"])]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in table["rows"]]
    return "\n".join(lines)


def run_line(section: dict) -> str:
    b, a = section["load_average"]
    return (f"Measured {section['date']} at commit `{section['commit']}` in {section['seconds']:.0f} s; "
            f"load average {b:.2f} before, {a:.2f} after.")


def render(template: str, results: dict) -> str:
    """The document: every placeholder replaced; an unknown one is an error, never blank."""
    sections = results["sections"]

    def one(m: re.Match) -> str:
        kind, key = m.group(1), m.group(2)
        if kind == "meta":
            return str(results["meta"][key])
        if kind == "run":
            return run_line(sections[key])
        name, _, item = key.partition(".")
        if kind == "table":
            return table_markdown(sections[name]["tables"][item])
        return str(sections[name]["values"][item])

    try:
        return PLACEHOLDER.sub(one, template)
    except KeyError as e:
        raise KeyError(f"the template names {e} but the results have no such figure: rerun benches/all.sh") from None


def template_figures(template: str) -> list:
    """Measured-looking figures written into the template itself (must be none)."""
    bare = PLACEHOLDER.sub("", template)
    return [(n + 1, m.group(0)) for n, line in enumerate(bare.splitlines()) for m in FIGURE.finditer(line)]


def load_results(path: pathlib.Path = RESULTS) -> dict:
    return json.loads(path.read_text())


def write(results: dict, template_path: pathlib.Path = TEMPLATE, out: pathlib.Path = DOCUMENT) -> None:
    text = render(template_path.read_text(), results)
    tmp = out.with_suffix(".md.tmp")
    tmp.write_text(text)
    tmp.replace(out)


if __name__ == "__main__":
    write(load_results())
