#!/usr/bin/env bash
# Renders a tracked camera sequence on a Slurm cluster: an array job whose tasks render chunks of frames
# (render-frames.sbatch, `deltagi render --frames A:B`), then a job that waits for all of them and encodes the
# frames into an MP4 (encode-video.sbatch, `deltagi encode`).
#
#   examples/slurm/submit.sh SCENE.json OUT_DIR [CHUNK]      # CHUNK frames per task, default 10
#
# Environment: DELTAGI (the deltagi executable; default: the one on PATH), FRAMES=A:B (default: the scene's
# sequence.frames, else all of the transforms file's frames), DELTAGI_ARGS (more render options), NO_VIDEO=1
# (frames only), SBATCH_ARGS (more sbatch options for both jobs, e.g. "--partition=gpu --time=2:00:00").
# Needs jq. The paths may not hold commas (sbatch --export splits on them); the folders must be visible from
# every node (a shared file system).
set -euo pipefail
[ $# -ge 2 ] || { sed -n '2,13p' "$0" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "$1")
out=$(realpath -m "$2")
chunk=${3:-10}
deltagi=$(realpath "${DELTAGI:-$(command -v deltagi)}")
[ -x "$deltagi" ] || { echo "submit.sh: no deltagi executable (set DELTAGI)" >&2; exit 1; }

# The transforms file (relative to the scene's folder), its frame count and the frame rate (the scene's
# sequence.fps, else the transforms file's fps, else 30: as deltagi takes it).
transforms=$(jq -r '.sequence.transforms // empty' "$scene")
[ -n "$transforms" ] || { echo "submit.sh: $scene has no \"sequence\"" >&2; exit 1; }
[[ $transforms = /* ]] || transforms="$(dirname "$scene")/$transforms"
count=$(jq '.frames | length' "$transforms")
range=${FRAMES:-$(jq -r '.sequence.frames // ":"' "$scene")}
first=${range%%:*}
end=${range#*:}
first=${first:-0}
end=${end:-$count}
fps=$(jq -r --slurpfile t "$transforms" '.sequence.fps // $t[0].fps // 30' "$scene")
chunks=$(((end - first + chunk - 1) / chunk))
[ "$chunks" -ge 1 ] || { echo "submit.sh: no frames in $first:$end" >&2; exit 1; }
mkdir -p "$out"

vars="ALL,DELTAGI=$deltagi,SCENE=$scene,OUT=$out,FIRST=$first,END=$end,CHUNK=$chunk,FPS=$fps"
# shellcheck disable=SC2086  # SBATCH_ARGS: options split on spaces
frames_job=$(sbatch --parsable ${SBATCH_ARGS:-} --chdir="$out" --array="0-$((chunks - 1))" --export="$vars" \
  "$here/render-frames.sbatch")
echo "submit.sh: frames $first:$end in $chunks tasks of $chunk: job $frames_job"
if [ "${NO_VIDEO:-0}" != 1 ]; then
  # --kill-on-invalid-dep: when a task fails, the video job is cancelled rather than left pending for ever.
  # shellcheck disable=SC2086
  video_job=$(sbatch --parsable ${SBATCH_ARGS:-} --chdir="$out" --dependency="afterok:$frames_job" \
    --kill-on-invalid-dep=yes --export="$vars" "$here/encode-video.sbatch")
  echo "submit.sh: $out/sequence.mp4 at $fps frames/s after it: job $video_job"
fi
