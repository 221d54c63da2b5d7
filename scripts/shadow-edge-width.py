#!/usr/bin/env python3
"""The width of a shadow's edge, in pixels, in the delta.exr and object_mask.exr of AOV folders (`deltagi render
--aov`, `deltagi reference --aov`): each real pixel's change as a fraction of the darkest change within 4
pixels of it, and the pixels between 10 % and 90 % of it counted per crossing of the 50 % line between
neighbouring pixels. A hard edge that the pixels resolve gives 0 to 1 (anti-aliased); a soft one more.

    build/deltagi render examples/hard-shadow.json -o out/hs.png --aov out/hs-dgi
    build/deltagi reference examples/hard-shadow.json --spp 256 -o out/hs-ref.exr --aov out/hs-ref
    scripts/shadow-edge-width.py out/hs-dgi out/hs-ref

Needs oiiotool (scripts/install-deps.sh); pixels whose window holds no change darker than -0.03, and those next
to the objects, are left out.
"""
import re
import subprocess
import sys

RADIUS = 4


def load(path):
    lines = subprocess.run(["oiiotool", "--dumpdata", path], capture_output=True, text=True,
                           check=True).stdout.splitlines()
    width, height = map(int, re.search(r":\s+(\d+) x\s+(\d+)", lines[0]).groups())
    image = [[0.0] * width for _ in range(height)]
    for line in lines[1:]:
        m = re.match(r"\s*Pixel \((\d+), (\d+)\): (\S+)", line)
        if m:
            image[int(m.group(2))][int(m.group(1))] = float(m.group(3))
    return image


def edge_width(folder):
    delta, mask = load(folder + "/delta.exr"), load(folder + "/object_mask.exr")
    height, width = len(delta), len(delta[0])
    fraction = [[None] * width for _ in range(height)]
    for y in range(RADIUS, height - RADIUS):
        for x in range(RADIUS, width - RADIUS):
            if any(mask[j][i] > 0 for j in range(y - 1, y + 2) for i in range(x - 1, x + 2)):
                continue
            darkest = min(delta[j][i] for j in range(y - RADIUS, y + RADIUS + 1)
                          for i in range(x - RADIUS, x + RADIUS + 1) if mask[j][i] == 0)
            if darkest <= -0.03:
                fraction[y][x] = delta[y][x] / darkest
    partial = sum(1 for row in fraction for f in row if f is not None and 0.1 < f < 0.9)
    crossings = 0
    for y in range(height):
        for x in range(width):
            f = fraction[y][x]
            if f is None:
                continue
            for i, j in ((x + 1, y), (x, y + 1)):
                if i < width and j < height and fraction[j][i] is not None and (f > 0.5) != (fraction[j][i] > 0.5):
                    crossings += 1
    return partial, crossings


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for folder in sys.argv[1:]:
        partial, crossings = edge_width(folder)
        print(f"{folder}: {partial} pixels between 10 % and 90 %, {crossings} crossings: "
              f"edge width {partial / max(crossings, 1):.2f} px")
