#!/usr/bin/env bash
# A camera capture to try `deltagi live` and `deltagi track` on, made by the project itself: the Cornell box
# example's real part with two printed AprilTags (tag36h11), one on the back wall and one on the tall block,
# path-traced by `deltagi reference` from a hand-held camera that sways and turns a little, frame after
# frame; and a scene file that places the markers and puts the example's ball and ring into the room for
# `live` to augment.
#
#   scripts/make-live-capture.sh [FRAMES] [SPP]     # default 24 frames, 64 samples per pixel, 320x240
#   OUT=out/bench-capture WIDTH=640 HEIGHT=480 EXAMPLE=examples/bench-cornell-buddha.json \
#       scripts/make-live-capture.sh 60 64   # the benchmark scene at its size
#   (any scene of the same Cornell box: its objects, lights and options)
#   build/deltagi live out/live-capture/scene.json --camera 'out/live-capture/camera/frame_####.png' \
#       -o 'out/live-capture/live/frame_####.png' --json out/live-capture/live.json
#   build/deltagi track 'out/live-capture/camera/frame_####.png' --scene out/live-capture/scene.json \
#       -o out/live-capture/tracked/transforms.json
#
# Writes out/live-capture/{scene.json,marker3.png,marker4.png,truth.json,camera/frame_NNNN.png}: truth.json
# holds the camera's true poses (a nerfstudio transforms file) to compare `track`'s with. Needs build/deltagi and jq
# (scripts/install-deps.sh). About 1 s per frame at the defaults on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-24}
spp=${2:-64}
width=${WIDTH:-320}
height=${HEIGHT:-240}
deltagi=${DELTAGI:-build/deltagi}
out=${OUT:-out/live-capture}
example=${EXAMPLE:-examples/cornell-box.json}
[ -x "$deltagi" ] || { echo "make-live-capture.sh: $deltagi not found: build it first (scripts/test.sh)" >&2; exit 1; }
command -v jq >/dev/null || { echo "make-live-capture.sh: jq not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
rm -rf "$out/camera"
mkdir -p "$out/camera"

# Two markers, as textures of 12 x 12 cells (the tag's 10 and one of paper around) of 32 pixels: id 3 with a
# 12 cm black square on the back wall (z = 0.5592), above what the tall block hides, and id 4 with a 10 cm one
# on the tall block's front face (turned 17.23 degrees from the back wall), each paper 0.5 mm off its
# surface, its top up. One small marker seen head-on leaves the camera's tilt uncertain (docs/live.md); two
# apart, at different depths, fix it. A marker's frame: x to the right as printed (about -x in the world,
# seen from the front), y up, z out of the paper.
"$deltagi" marker 3 --size 0.12 --margin 1 --pixels-per-cell 32 -o "$out/marker3.png" --quiet
"$deltagi" marker 4 --size 0.10 --margin 1 --pixels-per-cell 32 -o "$out/marker4.png" --quiet
papers=$(jq -n '[
  {"name": "marker3_paper", "shape": {"type": "quad", "size": [0.18, 0.18]},
   "transform": {"translate": [0.2, 0.43, 0.5587], "rotate_deg": [90, 180, 0]},
   "material": {"albedo": 1, "base_color_texture": "marker3.png"}},
  {"name": "marker4_paper", "shape": {"type": "quad", "size": [0.15, 0.15]},
   "transform": {"translate": [0.34385, 0.2, 0.27102], "rotate_deg": [90, 197.23, 0]},
   "material": {"albedo": 1, "base_color_texture": "marker4.png"}}]')
markers=$(jq -n '[
  {"id": 3, "size": 0.12, "transform": {"translate": [0.2, 0.43, 0.5587], "rotate_deg": [0, 180, 0]}},
  {"id": 4, "size": 0.10, "transform": {"translate": [0.34385, 0.2, 0.27102], "rotate_deg": [0, 197.23, 0]}}]')
fov=$(jq '.camera.fov_y_deg' "$example")

# Frame i of n: the example's camera swaying on a circle of 5 cm in x and y and turning up to 4 degrees
# about y (a hand-held camera), as a 4x4 camera-to-world matrix, row-major. The camera looks down its -z.
pose() {
  jq -n --argjson i "$1" --argjson n "$frames" --slurpfile scene "$example" '
    ($scene[0].camera.position) as $p
    | (2 * 3.141592653589793 * $i / $n) as $a
    | (0.07 * ($a | sin)) as $yaw
    | [[-($yaw | cos), 0, -($yaw | sin), $p[0] + 0.05 * ($a | cos)],
       [0, 1, 0, $p[1] + 0.05 * ($a | sin)],
       [($yaw | sin), 0, -($yaw | cos), $p[2]],
       [0, 0, 0, 1]]'
}

truth='[]'
for ((i = 0; i < frames; i++)); do
  name=$(printf 'camera/frame_%04d.png' "$i")
  matrix=$(pose "$i")
  jq --argjson m "$matrix" --argjson w "$width" --argjson h "$height" --argjson fov "$fov" \
    --argjson papers "$papers" \
    '.camera = {"width": $w, "height": $h, "fov_y_deg": $fov, "world_from_camera": $m}
     | .scene += $papers | .virtual = [] | del(.background)' "$example" > "$out/frame.json"
  "$deltagi" reference "$out/frame.json" --spp "$spp" -o "$out/$name" --quiet
  truth=$(jq --arg f "$name" --argjson m "$matrix" '. + [{"file_path": $f, "transform_matrix": $m}]' <<<"$truth")
  echo "make-live-capture.sh: frame $((i + 1))/$frames"
done
rm -f "$out/frame.json"

# fl = (h / 2) / tan(fov / 2)
jq -n --argjson w "$width" --argjson h "$height" --argjson fov "$fov" --argjson frames "$truth" '
  (($h / 2) / (($fov * 3.141592653589793 / 360) | tan)) as $f
  | {"camera_model": "PINHOLE", "w": $w, "h": $h, "fl_x": $f, "fl_y": $f, "cx": ($w / 2), "cy": ($h / 2),
     "fps": 30, "frames": $frames}' > "$out/truth.json"
# The live scene: the example with the paper in the real scene, the marker, and the camera's intrinsics (its
# pose is the markers' to find); the example's mesh files by their absolute paths.
jq --argjson w "$width" --argjson h "$height" --argjson fov "$fov" --argjson papers "$papers" \
  --argjson markers "$markers" --arg dir "$(cd "$(dirname "$example")" && pwd)" '
  def rebase: if has("file") and (.file | startswith("/") | not) then .file = ($dir + "/" + .file) else . end;
  .camera = (.camera + {"width": $w, "height": $h, "fov_y_deg": $fov}) | del(.background)
  | .scene += $papers | .markers = $markers | .virtual |= map(rebase) | .scene |= map(rebase)' \
  "$example" > "$out/scene.json"
echo "make-live-capture.sh: wrote $out/scene.json, $out/truth.json and $frames frames in $out/camera"
