#!/usr/bin/env bash
# A tracked camera sequence to try `deltagi render` over: the Cornell box example (its real part alone)
# path-traced by `deltagi reference` from a camera that pans and turns a little, frame after frame, written as
# a nerfstudio / instant-ngp transforms.json with the photos beside it, and a scene file that puts the
# example's ball and ring into it, the ball rolling 8.5 cm across the floor from the first frame to the last
# ("keyframes"; STILL=1 keeps it where the example has it):
#
#   scripts/make-sequence.sh [FRAMES] [SPP]          # default 8 frames, 64 samples per pixel, 320x240
#   DISTORTION=1 scripts/make-sequence.sh            # photos through an OPENCV lens (k1 -0.15, k2 0.02)
#   build/deltagi render out/sequence/scene.json -o out/sequence/render/frame_####.png --video out/sequence.mp4
#
# Writes out/sequence/{transforms.json,scene.json,images/frame_NNNN.png}. Needs build/deltagi and jq
# (scripts/install-deps.sh). About 1 s per frame at the defaults on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-8}
spp=${2:-64}
width=${WIDTH:-320}
height=${HEIGHT:-240}
deltagi=${DELTAGI:-build/deltagi}
out=out/sequence
example=examples/cornell-box.json
[ -x "$deltagi" ] || { echo "make-sequence.sh: $deltagi not found: build it first (scripts/test.sh)" >&2; exit 1; }
command -v jq >/dev/null || { echo "make-sequence.sh: jq not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
mkdir -p "$out/images"

# The example's vertical field of view gives the focal length in pixels; the principal point is the centre.
fov=$(jq '.camera.fov_y_deg' "$example")
if [ "${DISTORTION:-0}" = 1 ]; then
  lens='{"model": "opencv", "k1": -0.15, "k2": 0.02}'
  model='{"camera_model": "OPENCV", "k1": -0.15, "k2": 0.02, "p1": 0, "p2": 0}'
else
  lens='{"model": "none"}'
  model='{"camera_model": "PINHOLE"}'
fi

# Frame i: the example's camera moved along x by up to +-4 cm and turned about y by up to +-3 degrees; the
# camera looks down its -z axis, so the world-from-camera rotation is a half turn about y plus the yaw.
pose() {  # frame index -> the 4x4 camera-to-world matrix, row-major
  jq -n --argjson i "$1" --argjson n "$frames" --slurpfile scene "$example" '
    ($scene[0].camera.position) as $p
    | (if $n > 1 then $i / ($n - 1) - 0.5 else 0 end) as $t
    | (0.1 * $t) as $yaw
    | [[-($yaw | cos), 0, -($yaw | sin), $p[0] + 0.08 * $t],
       [0, 1, 0, $p[1]],
       [($yaw | sin), 0, -($yaw | cos), $p[2]],
       [0, 0, 0, 1]]'
}

transforms_frames='[]'
for ((i = 0; i < frames; i++)); do
  name=$(printf 'images/frame_%04d.png' "$i")
  matrix=$(pose "$i")
  jq --argjson m "$matrix" --argjson lens "$lens" --argjson w "$width" --argjson h "$height" \
    --argjson fov "$fov" \
    '.camera = {"width": $w, "height": $h, "fov_y_deg": $fov, "world_from_camera": $m, "distortion": $lens}
     | .virtual = [] | del(.background)' "$example" > "$out/frame.json"
  "$deltagi" reference "$out/frame.json" --spp "$spp" -o "$out/$name" --quiet
  transforms_frames=$(jq --arg f "$name" --argjson m "$matrix" '. + [{"file_path": $f, "transform_matrix": $m}]' \
    <<<"$transforms_frames")
  echo "make-sequence.sh: frame $((i + 1))/$frames"
done
rm -f "$out/frame.json"

# fl = (h / 2) / tan(fov / 2)
jq -n --argjson w "$width" --argjson h "$height" --argjson fov "$fov" --argjson model "$model" \
  --argjson frames "$transforms_frames" '
  (($h / 2) / (($fov * 3.141592653589793 / 360) | tan)) as $f
  | {"w": $w, "h": $h, "fl_x": $f, "fl_y": $f, "cx": ($w / 2), "cy": ($h / 2)} + $model + {"frames": $frames}' \
  > "$out/transforms.json"
# The example with its ball and ring, over the sequence instead of its own camera; the ball rolls from its
# place 8.5 cm towards the camera (keyframes at the first and the last frame).
jq 'del(.camera) | del(.background) | .sequence = {"transforms": "transforms.json"}' "$example" > "$out/scene.json"
if [ "${STILL:-0}" != 1 ]; then
  jq --argjson last "$((frames > 1 ? frames - 1 : 1))" '
    (.virtual[] | select(.name == "blue_ball")) |= (
      .transform.translate as $p
      | del(.transform)
      | .keyframes = [{"frame": 0, "translate": $p},
                      {"frame": $last, "translate": [($p[0] + 0.03), $p[1], ($p[2] - 0.08)]}])' \
    "$out/scene.json" > "$out/scene.json.tmp" && mv "$out/scene.json.tmp" "$out/scene.json"
fi
echo "make-sequence.sh: wrote $out/transforms.json, $out/scene.json and $frames photos in $out/images"
