#!/usr/bin/env bash
# The performance figures of docs/performance.md: the benchmark scene's stage timings next to the paper's
# Table 1 (warm frames, where only the virtual object moves; live frames, where the real light, the camera
# and the object change every frame; cold frames), and the scaling with volume resolution and image size. Writes docs/benchmark/*.json and prints the tables as Markdown.
# Needs ../shared/data/meshes/happy-buddha.obj and a Release build (scripts/test.sh or scripts/render-example.sh).
#   scripts/bench.sh [FRAMES]     (default 10 measured frames per figure)
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-10}
scene=examples/bench-cornell-buddha.json
out=docs/benchmark
mkdir -p "$out"
run() {  # name, extra args...
  local name=$1
  shift
  build/deltagi bench "$scene" --frames "$frames" --quiet --json "$out/$name.json" "$@" >/dev/null
}
run warm
run live --live
run cold --cold
for r in 64 256; do run "volume-$r" --set options.volume.resolution=$r; done
run image-320x240 --set camera.width=320 --set camera.height=240
run image-1280x960 --set camera.width=1280 --set camera.height=960
python3 - "$out" <<'PY'
import json, sys, os
out = sys.argv[1]
load = lambda n: json.load(open(os.path.join(out, n + ".json")))
warm, live, cold = load("warm"), load("live"), load("cold")
rows = [k for k in warm if k.endswith("_ms")]
print(f"{warm['width']}x{warm['height']}, {warm['volume_resolution']}^3, {warm['triangles']['virtual']} virtual "
      f"triangles, {warm['threads']} threads, {warm['frames']} frames\n")
print("| stage | warm median ms | warm max ms | live median ms | live max ms | cold median ms | paper (GTX 660) ms |")
print("|---|---:|---:|---:|---:|---:|---:|")
for k in rows:
    p = warm[k]["paper"]
    print(f"| {k} | {warm[k]['median']:.1f} | {warm[k]['max']:.1f} | {live[k]['median']:.1f} | "
          f"{live[k]['max']:.1f} | {cold[k]['median']:.1f} | {'' if p is None else p} |")
print("\n| volume resolution | total ms (median) | diffuse | shadow | voxelize | inject | mipmap |")
print("|---:|---:|---:|---:|---:|---:|---:|")
for r, name in ((64, "volume-64"), (128, "warm"), (256, "volume-256")):
    d = load(name)
    print(f"| {r}^3 | {d['total_ms']['median']:.1f} | {d['diffuse_ms']['median']:.1f} | "
          f"{d['shadow_ms']['median']:.1f} | {d['voxelize_ms']['median']:.1f} | {d['inject_ms']['median']:.1f} | "
          f"{d['mipmap_ms']['median']:.1f} |")
print("\n| image | total ms (median) | diffuse | shadow | specular | gbuffer |")
print("|---:|---:|---:|---:|---:|---:|")
for name in ("image-320x240", "warm", "image-1280x960"):
    d = load(name)
    print(f"| {d['width']}x{d['height']} | {d['total_ms']['median']:.1f} | {d['diffuse_ms']['median']:.1f} | "
          f"{d['shadow_ms']['median']:.1f} | {d['specular_ms']['median']:.1f} | {d['gbuffer_ms']['median']:.1f} |")
PY
