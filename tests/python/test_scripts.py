"""The project's Python helper scripts (scripts/), run as a user runs them (CTest Install.Python sets
DELTAGI_SOURCE_DIR and PYTHONPATH)."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import deltagi

SCRIPTS = os.path.join(os.environ.get("DELTAGI_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..")),
                       "scripts")


def test_light_frames_are_an_upward_fisheye_with_a_sun_that_circles(tmp_path):
    out = tmp_path / "light"
    subprocess.run([sys.executable, os.path.join(SCRIPTS, "make-light-frames.py"), str(out), "4", "64"],
                   check=True, capture_output=True)
    assert sorted(os.listdir(out)) == [f"frame_{k:04d}.png" for k in range(4)]
    frames = [np.asarray(deltagi.read_image(str(out / f"frame_{k:04d}.png"))) for k in range(4)]
    assert all(f.shape == (64, 64, 3) for f in frames)
    assert np.all(frames[0][0, 0] == 0.0)  # a corner: outside the 180-degree field of view
    # The sun (clipped white) 30 degrees above the horizon: 60 of the 90 degrees from the centre to the edge.
    # At azimuth 0 it lies towards +x, which the image's left shows; a quarter turn later towards +z (the
    # image's bottom).
    def sun(f):
        ys, xs = np.nonzero(np.all(f >= 0.999, axis=-1))
        assert len(xs) > 0
        return (xs.mean() + 0.5) / 32.0 - 1.0, (ys.mean() + 0.5) / 32.0 - 1.0  # [-1, 1], y down
    for k, (ex, ey) in enumerate([(-1, 0), (0, 1), (1, 0), (0, -1)]):
        x, y = sun(frames[k])
        assert math.hypot(x, y) == pytest.approx(2.0 / 3.0, abs=0.06), k
        assert x * ex + y * ey > 0.6, k


def test_light_frames_refuse_impossible_arguments(tmp_path):
    r = subprocess.run([sys.executable, os.path.join(SCRIPTS, "make-light-frames.py"), str(tmp_path), "0"],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "FRAMES must be >= 1" in r.stderr
