#!/usr/bin/env python3
"""Writes a light camera's frames for `deltagi live --light-camera`: an upward-looking equidistant fish-eye
(180 degrees, scene-format.md's "fish-eye" convention: +y up the optical axis, the image's top towards -z, its
right towards -x) that sees a blue sky brightening towards the horizon and a sun 30 degrees above it that circles
once over the frames, as 8-bit sRGB PNGs (an LDR webcam's: the sun clips at 1).

    PYTHONPATH=build/python python3 scripts/make-light-frames.py OUT_DIR [FRAMES] [SIZE]
        (default 60 frames of 128 x 128: OUT_DIR/frame_0000.png ...)

Then, for example with the benchmark scene's capture (scripts/make-live-capture.sh):
    build/deltagi live out/bench-capture/scene.json --camera 'out/bench-capture/camera/frame_####.png' \\
        --light-camera 'out/bench-capture/light/frame_####.png' \\
        --set 'environment={"file": "light/frame_0000.png", "projection": "fisheye"}'   # relative to the scene
Needs numpy and the project's Python module (build/python).
"""

import math
import os
import sys

import numpy as np

import deltagi


def frame(size: int, sun_azimuth: float) -> np.ndarray:
    # Pixel centres in [-1, 1], x right, y down; r = 1 at the edge of the 180-degree field of view.
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(c, c)
    r = np.hypot(x, y)
    theta = r * (math.pi / 2.0)  # angle from the zenith (equidistant)
    phi = np.arctan2(y, x)
    # Directions: right is -x, top is -z, the axis +y.
    sin_t = np.sin(theta)
    d = np.stack([-sin_t * np.cos(phi), np.cos(theta), sin_t * np.sin(phi)], axis=-1)
    horizon = np.clip(1.0 - np.cos(theta), 0.0, 1.0)
    sky = np.array([0.25, 0.45, 0.85]) * (0.35 + 0.65 * horizon[..., None])
    elevation = math.radians(30.0)
    sun = np.array([math.cos(elevation) * math.cos(sun_azimuth), math.sin(elevation),
                    math.cos(elevation) * math.sin(sun_azimuth)])
    cos_sun = d @ sun
    disk = cos_sun > math.cos(math.radians(4.0))  # 8 degrees across: a few pixels at 128 x 128
    image = np.where(disk[..., None], 1.0, sky)
    image[r > 1.0] = 0.0  # outside the field of view
    return image.astype(np.float32)


def main() -> int:
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = sys.argv[1]
    frames = int(sys.argv[2]) if len(sys.argv) > 2 else 60
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 128
    if frames < 1 or size < 8:
        print("make-light-frames.py: FRAMES must be >= 1 and SIZE >= 8", file=sys.stderr)
        return 2
    os.makedirs(out, exist_ok=True)
    for k in range(frames):
        deltagi.write_image(os.path.join(out, f"frame_{k:04d}.png"), frame(size, 2.0 * math.pi * k / frames))
    print(f"make-light-frames.py: wrote {frames} frames of {size}x{size} in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
