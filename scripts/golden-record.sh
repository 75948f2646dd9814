#!/usr/bin/env bash
# Records the golden JSON outputs of the etlcal binary that crates/etlcal/tests/it/golden.rs
# compares against (behaviour unchanged across the architecture move). Run it
# only when a change of output is intended, and say so in the commit.
#   usage: scripts/golden-record.sh PATH/TO/etlcal
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "$1")
g=fixtures/golden
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$g"
# The committed input: the paper rig's simulated corners (seed 3), observations only.
mkdir "$tmp/sim"; "$bin" simulate --out "$tmp/sim" --observations-only --seed 3 >/dev/null
cp "$tmp/sim/observations.json" "$g/observations.json"
while IFS='|' read -r name args; do
  [ -n "$name" ] || continue
  # shellcheck disable=SC2086
  eval "\"$bin\" $args" > "$g/$name.json"
done < "$g/cases.txt"
echo "recorded $(wc -l < "$g/cases.txt") cases into $g"
