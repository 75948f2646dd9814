#!/usr/bin/env bash
# Screenshots of generated HTML reports in a real browser (headless Chromium), to look at
# them as a person would.
#
#   scripts/report-screenshots.sh OUT_DIR REPORT_DIR_OR_HTML...
#
# For each report (a directory holding index.html, or an .html file) writes
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
    [[ -d "$report" ]] && page="$report/index.html"
    if [[ ! -f "$page" ]]; then
        echo "$0: no report at $page" >&2
        exit 1
    fi
    name="$(realpath --relative-to=/ "$report" | tr '/' '_')"
    name="${name%.html}"
    # --no-sandbox: the sandbox needs user namespaces, often absent in containers and CI.
    # The virtual time budget lets the figures load before the shot is taken.
    "$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars \
        --virtual-time-budget=10000 --window-size="1400,$height" \
        --screenshot="$out/$name.png" "file://$(realpath "$page")" >/dev/null 2>&1
    echo "$out/$name.png"
done
