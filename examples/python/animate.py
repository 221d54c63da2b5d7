#!/usr/bin/env python3
"""A short animation: the Cornell box's blue ball rolls in a circle on the floor, one PNG per frame.

    python3 examples/python/animate.py [OUT_FOLDER] [FRAMES]      (default: out/animation, 12 frames)

Small on purpose (160x120, 32^3 volumes): 2.3 s in all on 2 cores. The real scene's work (its voxels, shadow
maps and light) is done in the first frame (0.5 s) and kept while only the ball moves (25-55 ms a frame).
"""
import math
import pathlib
import sys

import numpy as np

import deltagi

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent


def main():
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "out/animation")
    frames = int(sys.argv[2]) if len(sys.argv) > 2 else 12
    out.mkdir(parents=True, exist_ok=True)
    scene = deltagi.Scene.load(EXAMPLES / "cornell-box.json",
                               ["camera.width=160", "camera.height=120", "options.volume.resolution=32"])
    renderer = deltagi.FrameRenderer()
    for frame in range(frames):
        angle = 2 * math.pi * frame / frames
        world_from_ball = np.eye(4, dtype=np.float32)
        world_from_ball[:3, 3] = (0.3 + 0.1 * math.cos(angle), 0.08, 0.2 + 0.1 * math.sin(angle))
        scene.set_object_transform("blue_ball", world_from_ball)
        result = renderer.render(scene)
        deltagi.write_image(out / f"frame-{frame:03d}.png", result["composite"])
        print(f"frame {frame}: {result['total_ms']:.0f} ms")


if __name__ == "__main__":
    main()
