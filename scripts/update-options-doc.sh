#!/bin/sh
# Makes the options tables of docs/scene-format.md anew from the one description of each option
# (src/scene/option_table.cpp), through `deltagi info --options-markdown`. The test
# OptionTable.DocsTablesAreTheCodesTables fails until they agree.
#   scripts/update-options-doc.sh [BUILD_DIR]   (default: build)
set -eu
cd "$(dirname "$0")/.."
deltagi="${1:-build}/deltagi"
[ -x "$deltagi" ] || { echo "update-options-doc.sh: no $deltagi; build first (docs/building.md)" >&2; exit 1; }
trap 'rm -f docs/scene-format.md.new' EXIT
"$deltagi" info --options-markdown docs/scene-format.md > docs/scene-format.md.new
mv docs/scene-format.md.new docs/scene-format.md
git diff --stat -- docs/scene-format.md
