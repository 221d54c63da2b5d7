#!/usr/bin/env bash
# Fuzzes the scene reader, mesh loading (with the nesting checks before Assimp), the live session's message
# handler (raw bytes, and camera frames' JPEGs), camera frames (video decoding and the marker detector) and image
# files (headers and decoding) with libFuzzer (clang 16 from Debian 12): builds build-fuzz/ with -DDELTAGI_FUZZ=ON,
# seeds each target, runs each for a fixed budget and prints executions and findings.
#   scripts/fuzz.sh [SECONDS_PER_TARGET]      (default 300)
# Seeds: the scenes of examples/ and tests/bad-inputs/ (and ../shared/data/scenes when present) for the scene
# reader; Debian's assimp-testmodels (OBJ, PLY, OFF, glTF 2, STL) and the meshes of tests/bad-inputs/ for
# mesh loading. The corpus grows in build-fuzz/corpus-*/ from run to run; crashes, timeouts and running out of
# memory (4 GB) are written to build-fuzz/findings/. The live session's handler (`deltagi serve`) is seeded with
# one message of each type, camera frames with a short MP4 of a marker. Every crash found becomes a case of
# tests/bad-inputs/.
# Exit status 1 when a target found something. Builds through ccache (scripts/ccache-env.sh). Installs clang 16, libFuzzer and assimp-testmodels when missing
# (as root). Clang 16, not Debian's default 14: the renderer captures structured bindings in lambdas (C++20),
# which clang supports from version 16.
set -euo pipefail
cd "$(dirname "$0")/.."
budget="${1:-300}"

scripts/install-deps.sh clang-16 libclang-rt-16-dev assimp-testmodels

build=build-fuzz
source scripts/ccache-env.sh
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-16 \
  -DDELTAGI_FUZZ=ON -DDELTAGI_BUILD_TESTS=OFF -DDELTAGI_BUILD_BENCHMARKS=OFF "${DELTAGI_LAUNCHER[@]}"
cmake --build "$build" -j2 --target fuzz_scene_reader fuzz_mesh_loader fuzz_live_session fuzz_camera_frames \
  fuzz_image_reader

# Seeds, rebuilt each run (the corpus folders keep what the fuzzer found).
seeds="$build/seeds"
rm -rf "$seeds"
mkdir -p "$seeds/scene" "$seeds/mesh" "$seeds/live" "$seeds/frames" "$seeds/image" "$build/corpus-scene" \
  "$build/corpus-mesh" "$build/corpus-live" "$build/corpus-frames" "$build/corpus-image" "$build/findings"
for f in examples/*.json tests/bad-inputs/*.json ../shared/data/scenes/*.json; do
  [ -f "$f" ] && [ "$(stat -c %s "$f")" -le 65536 ] && cp "$f" "$seeds/scene/$(echo "$f" | tr / _)"
done
# fuzz_mesh_loader reads the first byte as the format: 0 obj, 1 ply, 2 off, 3 gltf, 4 glb, 5 stl.
seed_mesh() {  # FILE
  local ext="${1##*.}" byte
  case "${ext,,}" in
    obj) byte='\x00' ;; ply) byte='\x01' ;; off) byte='\x02' ;; gltf) byte='\x03' ;; glb) byte='\x04' ;;
    stl) byte='\x05' ;; *) return 0 ;;
  esac
  [ "$(stat -c %s "$1")" -le 262144 ] || return 0
  { printf "$byte"; cat "$1"; } > "$seeds/mesh/$(echo "$1" | tr / _)"
}
models=/usr/share/assimp/models
for f in "$models"/OBJ/* "$models"/PLY/* "$models"/OFF/* "$models"/glTF2/*/*/* "$models"/STL/* \
         "$models"/invalid/* tests/bad-inputs/mesh-*; do
  [ -f "$f" ] && seed_mesh "$f"
done

n=0
while IFS= read -r message; do
  n=$((n + 1))
  printf '%s' "$message" > "$seeds/live/message-$n.json"
done <<'MESSAGES'
{"type": "drag", "object": 0, "x": 32.5, "y": 30, "seq": 1}
{"type": "rotate", "object": 1, "degrees": -15}
{"type": "select", "object": 1}
{"type": "light", "light": 0, "position": [0.5, 1.4, 0.5], "intensity": 2}
{"type": "light", "light": 1, "intensity": 0.5}
{"type": "options", "values": {"volume.resolution": 32, "diffuse.count": 4, "diffuse.pixel_stride": "auto"}}
{"type": "options", "values": {"shadow.ray_samples": 9, "render.samples_per_pixel": 1}}
{"type": "view", "view": "depth"}
{"type": "ping"}
MESSAGES

# Camera frames: a 3-frame MP4 of a marker (first byte 0: .mp4), written by the Release build's `deltagi`
# when there is one (scripts/test.sh builds it).
if [ -x build/deltagi ]; then
  frames="$build/seed-frames"
  rm -rf "$frames" && mkdir -p "$frames"
  build/deltagi marker 3 -o "$frames/frame_0000.png" --pixels-per-cell 4 --quiet
  cp "$frames/frame_0000.png" "$frames/frame_0001.png" && cp "$frames/frame_0000.png" "$frames/frame_0002.png"
  build/deltagi encode "$frames/frame_####.png" -o "$frames/marker.mp4" --quiet
  { printf '\x00'; cat "$frames/marker.mp4"; } > "$seeds/frames/marker-mp4"
fi

# Images (first byte: 0 .png, 1 .jpg, 2 .exr, 3 .hdr): the bad inputs' photos and maps, and a marker.
for f in tests/bad-inputs/*.png tests/bad-inputs/*.hdr tests/bad-inputs/*.exr tests/bad-inputs/*.jpg; do
  [ -f "$f" ] || continue
  case "${f##*.}" in png) byte='\x00' ;; jpg) byte='\x01' ;; exr) byte='\x02' ;; hdr) byte='\x03' ;; esac
  { printf "$byte"; cat "$f"; } > "$seeds/image/$(basename "$f")"
done
[ -f "${frames:-}/frame_0000.png" ] && { printf '\x00'; cat "$frames/frame_0000.png"; } > "$seeds/image/marker.png"

status=0
for target in scene mesh live frames image; do
  case $target in
    scene) binary="$build/fuzz/fuzz_scene_reader" ;;
    mesh) binary="$build/fuzz/fuzz_mesh_loader" ;;
    live) binary="$build/fuzz/fuzz_live_session" ;;
    frames) binary="$build/fuzz/fuzz_camera_frames" ;;
    image) binary="$build/fuzz/fuzz_image_reader" ;;
  esac
  log="$build/fuzz-$target.log"
  echo "== fuzz_$target: $budget s, $(ls "$seeds/$target" | wc -l) seeds"
  # Inputs that are slow (20 s) or need more than 4 GB are findings too; TBB and Assimp keep caches alive
  # at exit, so leaks are not reported.
  dict=()
  [ $target = scene ] && dict=(-dict=fuzz/scene.dict)  # the format's keys and values
  [ $target = live ] && dict=(-dict=fuzz/live_session.dict)
  set +e
  # One child process at a time (-fork=1) that is restarted after a finding, so that one run collects all.
  ASAN_OPTIONS=detect_leaks=0 "$binary" -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
    -max_total_time="$budget" -timeout=20 -rss_limit_mb=4096 -max_len=262144 \
    -artifact_prefix="$build/findings/$target-" "${dict[@]}" \
    "$build/corpus-$target" "$seeds/$target" > "$log" 2>&1
  result=$?
  set -e
  # The fork parent's last status line: "#RUNS: cov: N ft: N corp: N exec/s N oom/timeout/crash: A/B/C ...".
  last=$(grep -E '^#[0-9]+: cov:' "$log" | tail -1)
  runs=$(echo "$last" | grep -oE '^#[0-9]+' | tr -d '#')
  failures=$(echo "$last" | grep -oE 'oom/timeout/crash: [0-9/]+' || true)
  echo "   executions: ${runs:-?}, $(echo "$last" | grep -oE 'cov: [0-9]+'), ${failures:-no status line}," \
    "exit status $result; findings: $(ls "$build/findings" | grep -c "^$target-" || true) in $build/findings"
  if [ "$result" -ne 0 ] || [ -n "$(ls "$build/findings" | grep "^$target-")" ]; then
    status=1
    grep -E "ERROR: |SUMMARY: |Test unit written" "$log" | sort | uniq -c | head -20 || true
  fi
done
exit $status
