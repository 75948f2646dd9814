#!/usr/bin/env bash
# Screenshots of generated HTML reports in a real browser (headless Chromium), to look at
# them as a person would.
#
#   scripts/report-screenshots.sh OUT_DIR REPORT_DIR_OR_HTML...
#
# For each report (a directory holding index.html, or an .html file; a directory of study
# output without index.html, e.g. `etlcal study fig6 --out DIR`, is shown through a page
# written beside the screenshot: its .md files as text, then each .svg figure) writes
# OUT_DIR/<name>.png, a screenshot of the whole page (the window is made as tall as the
# page is estimated to be: 1400 px wide, height from --height or 14000 px), where <name> is
# the report's path with '/' replaced by '_'. Needs chromium (Debian: apt-get install -y
# chromium) or $CHROMIUM. Exits 1 with a one-line message when a report or the browser is
# missing.
set -euo pipefail

height=14000
if [[ "${1:-}" == "--height" ]]; then
    height="$2"
    shift 2
fi
if [[ $# -lt 2 ]]; then
    echo "usage: $0 [--height PX] OUT_DIR REPORT_DIR_OR_HTML..." >&2
    exit 1
fi
out="$1"
shift
browser="${CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}"
if [[ -z "$browser" ]]; then
    echo "$0: no chromium found (apt-get install -y chromium, or set CHROMIUM)" >&2
    exit 1
fi
mkdir -p "$out"
for report in "$@"; do
    page="$report"
    name="$(realpath --relative-to=/ "$report" | tr '/' '_')"
    name="${name%.html}"
    if [[ -d "$report" && ! -f "$report/index.html" ]] && compgen -G "$report/*.svg" >/dev/null; then
        page="$out/$name.html"
        dir="$(realpath "$report")"
        {
            echo "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>$dir</title>"
            echo "<style>body{font-family:sans-serif;margin:1em}img{max-width:100%;border:1px solid #eee}pre{white-space:pre-wrap}</style></head><body>"
            for md in "$dir"/*.md; do
                [[ -f "$md" ]] || continue
                echo "<h2>$(basename "$md")</h2><pre>"
                sed -e 's/&/\&amp;/g' -e 's/</\&lt;/g' "$md"
                echo "</pre>"
            done
            for svg in "$dir"/*.svg; do
                echo "<h2>$(basename "$svg")</h2><img src=\"file://$svg\">"
            done
            echo "</body></html>"
        } >"$page"
    elif [[ -d "$report" ]]; then
        page="$report/index.html"
    fi
    if [[ ! -f "$page" ]]; then
        echo "$0: no report at $page" >&2
        exit 1
    fi
    # --no-sandbox: the sandbox needs user namespaces, often absent in containers and CI.
    # The virtual time budget lets the figures load before the shot is taken.
    "$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars \
        --virtual-time-budget=10000 --window-size="1400,$height" \
        --screenshot="$out/$name.png" "file://$(realpath "$page")" >/dev/null 2>&1
    echo "$out/$name.png"
done
