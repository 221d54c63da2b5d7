#!/usr/bin/env bash
# The README's pictures, rendered from the examples with the current build: each composite as an sRGB PNG, the
# Cornell box's background (the real scene alone), and the change to the photo as grey + 4 x delta (linear
# values written as they are: grey 128 is no change). Writes docs/images/; intermediate AOVs in out/readme/.
# Needs build/deltagi, oiiotool (openimageio-tools, installed by scripts/install-deps.sh) and, for the Buddha
# and the bunny, the shared data set next to the repository (../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
deltagi=${DELTAGI:-build/deltagi}
out=out/readme
mkdir -p "$out" docs/images
render() {  # example name, delta picture or not
  "$deltagi" render "examples/$1.json" -o "docs/images/$1.png" --aov "$out/$1" --quiet
  if [ "$2" = delta ]; then
    oiiotool "$out/$1/delta.exr" --ch R,G,B --mulc 4 --addc 0.5 --clamp:min=0:max=1 -d uint8 \
      -o "docs/images/$1-delta.png"
  fi
}
render cornell-box delta
"$deltagi" render examples/cornell-box.json --set 'virtual=[]' -o docs/images/cornell-box-background.png --quiet
render cornell-box-glossy none
render cornell-buddha none
render cornell-textured none
render field-bunny delta
# `deltagi live` on the project's own capture: a camera frame and the same frame augmented.
scripts/make-live-capture.sh 24 256 >/dev/null
"$deltagi" live out/live-capture/scene.json --camera 'out/live-capture/camera/frame_####.png' \
  -o 'out/live-capture/live/frame_####.png' --quiet
cp out/live-capture/camera/frame_0012.png docs/images/live-camera.png
cp out/live-capture/live/frame_0012.png docs/images/live-augmented.png
echo "readme-images.sh: wrote docs/images/{cornell-box,cornell-box-background,cornell-box-delta,cornell-box-glossy,cornell-buddha,cornell-textured,field-bunny,field-bunny-delta,live-camera,live-augmented}.png"
