"""docs/BENCHMARKS.md is the template rendered with the last run's figures, and the template
states none of its own (run by scripts/test.sh: `python -m pytest benches/test_benchdoc.py`)."""

import pytest

import benchdoc


def test_the_document_is_the_template_rendered_with_the_recorded_run():
    results = benchdoc.load_results()
    rendered = benchdoc.render(benchdoc.TEMPLATE.read_text(), results)
    assert benchdoc.DOCUMENT.read_text() == rendered, "docs/BENCHMARKS.md was edited by hand or not regenerated"


def test_the_recorded_run_is_a_full_one():
    results = benchdoc.load_results()
    quick = [name for name, s in results["sections"].items() if s["quick"]]
    assert not quick, f"sections measured with --quick were committed: {quick}"


def test_the_template_states_no_figure_of_its_own():
    assert benchdoc.template_figures(benchdoc.TEMPLATE.read_text()) == []


def test_the_figure_check_finds_times_and_ratios():
    text = "took 4.2 ms, then 12 us and 3x faster; {{value:a.b}} stays; 2 cores, 0.5 px blur, x86-64"
    assert [f for _, f in benchdoc.template_figures(text)] == ["4.2 ms", "12 us", "3x"]


def test_an_unknown_placeholder_is_an_error_not_a_blank():
    results = {"meta": {}, "sections": {"a": {"tables": {}, "values": {"b": "1 ms"}}}}
    assert benchdoc.render("x {{value:a.b}} y", results) == "x 1 ms y"
    with pytest.raises(KeyError, match="rerun benches/all.sh"):
        benchdoc.render("{{value:a.c}}", results)


def test_tables_render_as_markdown():
    t = {"header": ["a", "b"], "rows": [[1, "2 ms"]]}
    assert benchdoc.table_markdown(t) == "| a | b |\n|---|---|\n| 1 | 2 ms |"
