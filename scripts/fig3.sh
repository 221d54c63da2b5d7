#!/usr/bin/env bash
# Reproduces the paper's Fig. 3 in numbers: DGI against the path-traced ground truth on the Cornell box with the
# Happy Buddha (examples/cornell-buddha.json). Writes docs/images/fig3-dgi.png (a), fig3-reference.png (b),
# fig3-difference.png (c: 2x the squared difference, false colour) and docs/fig3.md (the figures of
# `deltagi eval`, baselines included, and the command). The intermediate images stay in out/fig3/.
#
#   scripts/fig3.sh                      # 640x480, 256 samples per pixel, at most 480 s of path tracing
#   SPP=64 TIME_LIMIT=120 scripts/fig3.sh
#
# Needs build/deltagi (scripts/test.sh builds it), jq, and the Happy Buddha of the shared data set at
# ../shared/data/meshes/happy-buddha.obj (next to the repository). On this project's 2-core machine it takes
# 2 to 4 minutes, nearly all of it the path tracer (70 to 210 s for 256 samples, depending on what else runs).
set -euo pipefail
cd "$(dirname "$0")/.."

deltagi=${DELTAGI:-build/deltagi}
spp=${SPP:-256}
time_limit=${TIME_LIMIT:-480}
scene=examples/cornell-buddha.json
mesh=../shared/data/meshes/happy-buddha.obj
out=out/fig3

fail() {
  echo "fig3.sh: $*" >&2
  exit 1
}
[ -x "$deltagi" ] || fail "$deltagi not found: build it first (scripts/test.sh, or cmake -S . -B build -G Ninja && ninja -C build)"
[ -f "$mesh" ] || fail "missing $mesh: the Happy Buddha mesh of the shared data set (../shared/data/meshes, next to the repository) is needed for Fig. 3"
command -v jq >/dev/null || fail "jq not found (scripts/install-deps.sh installs it)"

mkdir -p "$out" docs/images
eval_command="$deltagi eval $scene --spp $spp --time-limit $time_limit --json $out/eval.json --aov $out/aov"
echo "fig3.sh: $eval_command" >&2
# The summary line also says how many samples the reference took and how many pixels are lit, shadowed, object.
$eval_command 2> >(tee "$out/eval.log" >&2)
summary=$(grep '^deltagi: delta_rel_error' "$out/eval.log")
samples=$(sed -E 's/.*reference ([0-9]+) spp.*/\1/' <<<"$summary")
pixels=$(sed -E 's/.*pixels: (.*)$/\1/' <<<"$summary")

cp "$out/aov/dgi.png" docs/images/fig3-dgi.png
cp "$out/aov/reference.png" docs/images/fig3-reference.png
compare_command="$deltagi compare $out/aov/dgi.exr $out/aov/reference.exr -o docs/images/fig3-difference.png --json"
$compare_command >"$out/compare.json"
full_scale=$(printf "%.4g" "$(jq -r '.difference_max' "$out/compare.json")")

row() {  # name, jq path of the figures
  jq -r --arg name "$1" "$2"' | "| \($name) | \(.delta_rel_error | . * 10000 | round / 10000) | \(.object_rel_rmse | . * 10000 | round / 10000) | \(.composite_rmse | . * 100000 | round / 100000) | \(.bias_lit | . * 100000 | round / 100000) | \(.bias_shadowed | . * 100000 | round / 100000) |"' "$out/eval.json"
}

{
  cat <<EOF
# Fig. 3 of the paper, in numbers

DGI (a) against a path-traced ground truth (b) on the Cornell box with the Happy Buddha
(\`examples/cornell-buddha.json\`, 640×480), and 2× the squared difference (c) in false colour (black 0, pale
yellow at $full_scale and above: the 99th percentile of the image). Written by \`scripts/fig3.sh\`; what each
figure means is in [ground-truth.md](ground-truth.md).

| (a) DGI | (b) path-traced reference | (c) 2 × squared difference |
|---|---|---|
| ![DGI](images/fig3-dgi.png) | ![reference](images/fig3-reference.png) | ![difference](images/fig3-difference.png) |

| method | delta_rel_error | object_rel_rmse | composite_rmse | bias_lit | bias_shadowed |
|---|---|---|---|---|---|
EOF
  row "**DGI**" '.'
  row "no_relight (object pasted in, Δ = 0)" '.baselines.no_relight'
  row "shadow_only (no indirect change)" '.baselines.shadow_only'
  row "single_visibility (one visibility volume)" '.baselines.single_visibility'
  cat <<EOF

DGI took $(jq -r '.dgi_ms | round' "$out/eval.json") ms, the path tracer $(jq -r '.reference_ms / 1000 | round' "$out/eval.json") s for $samples samples per
pixel (asked: $spp, time limit $time_limit s); pixels: $pixels. The difference image compares the two
composites over the same background (the path-traced real scene), so it shows the relighting and the object,
not how DGI would render the empty box.

The figures as \`deltagi eval\` wrote them:

\`\`\`json
$(cat "$out/eval.json")
\`\`\`

Commands (from the repository root; \`scripts/fig3.sh\` runs them):

\`\`\`sh
$eval_command
$compare_command
\`\`\`
EOF
} >docs/fig3.md
echo "fig3.sh: wrote docs/fig3.md and docs/images/fig3-{dgi,reference,difference}.png" >&2
