"""The Python module, as installed (CTest Install.Python sets PYTHONPATH to the installed prefix and
DELTAGI_CLI to the installed command line)."""
import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import deltagi


def tiny_scene(width=48, height=36):
    """A floor, a box as the virtual object and a point light: renders in well under a second."""
    floor = {"type": "triangles", "positions": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]],
             "indices": [[0, 2, 1], [0, 3, 2]]}
    return {
        "camera": {"width": width, "height": height, "fov_y_deg": 45, "position": [0, 0.8, 2],
                   "look_at": [0, 0.1, 0]},
        "scene": [{"name": "floor", "shape": floor, "material": {"albedo": [0.7, 0.7, 0.7]}}],
        "virtual": [{"name": "box", "shape": {"type": "box", "size": [0.3, 0.3, 0.3]},
                     "transform": {"translate": [0, 0.15, 0]}, "material": {"albedo": [0.2, 0.3, 0.8]}}],
        "lights": [{"type": "point", "position": [0.5, 1.5, 0.5], "intensity": 3}],
        "options": {"volume": {"resolution": 16}, "rsm": {"resolution": 64}},
    }


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "tiny.json"
    path.write_text(json.dumps(tiny_scene()))
    return path


def translation(x, y, z):
    m = np.eye(4, dtype=np.float32)
    m[:3, 3] = (x, y, z)
    return m


def test_a_still_is_the_command_lines_bit_for_bit(scene_file, tmp_path):
    aov = tmp_path / "aov"
    subprocess.run([os.environ["DELTAGI_CLI"], "render", str(scene_file), "-o", str(tmp_path / "cli.exr"),
                    "--aov", str(aov), "--quiet"], check=True)
    scene = deltagi.Scene.load(scene_file)
    frames = deltagi.FrameRenderer()
    frames.render(scene)  # a session's frame first: the still keeps its work
    out = frames.render_still(scene)
    for name in ("composite", "background", "delta"):
        expected = deltagi.read_image(aov / f"{name}.exr")
        assert out[name].shape == (36, 48, 3) and out[name].dtype == np.float32
        assert np.array_equal(out[name], expected), name
    mask = deltagi.read_image(aov / "object_mask.exr")  # read back as 3 equal channels
    assert out["object_mask"].shape == (36, 48)
    assert np.array_equal(out["object_mask"], mask[:, :, 0])
    assert out["object_mask"].max() == 1.0  # the box is in the picture
    assert list(out["timings_ms"])[0] == "bvh" and out["total_ms"] > 0


def test_outputs_are_arrays_over_the_renderers_images_without_copies(scene_file):
    out = deltagi.render(deltagi.Scene.load(scene_file))
    composite = out["composite"]
    assert not composite.flags.owndata and composite.base is not None  # a capsule owning the image
    assert composite.flags.c_contiguous and composite.flags.writeable


def test_moving_the_object_changes_the_frame_and_moving_it_back_restores_it(scene_file):
    scene = deltagi.Scene.load(scene_file)
    assert scene.object_names == ["box"]
    placed = scene.object_transform("box")
    assert np.array_equal(placed, translation(0, 0.15, 0))
    renderer = deltagi.FrameRenderer()
    first = renderer.render(scene)["composite"]
    scene.set_object_transform("box", translation(0.4, 0.15, 0.2))
    moved = renderer.render(scene)["composite"]
    assert np.abs(moved - first).sum() > 1.0
    scene.set_object_transform(0, placed)
    # Temporal reuse averages the frame with the moved one; without the frames before it, it is the first
    # frame again, to rounding (a refit BVH may meet the other triangle of a shared edge, renderer.h).
    averaged = renderer.render(scene)["composite"]
    assert np.abs(averaged - first).max() > 1e-4
    renderer.clear_history()
    np.testing.assert_allclose(renderer.render(scene)["composite"], first, rtol=0, atol=1e-6)


def test_the_camera_pose_and_the_photo_come_from_memory(scene_file):
    scene = deltagi.Scene.load(scene_file)
    pose = scene.camera_pose
    scene.set_camera((0, 0.8, 2), (0, 0.1, 0))
    assert np.array_equal(scene.camera_pose, pose)  # the scene file's position and look_at
    assert scene.background is None
    photo = np.full((36, 48, 3), 0.25, dtype=np.float32)
    photo[:, :24] = 0.75
    scene.background = photo
    out = deltagi.render(scene)
    assert np.array_equal(out["background"], photo)
    # Real pixels are the photo plus the change the box makes: its shadow darkens some.
    real = out["object_mask"] == 0
    assert (out["composite"][real] < photo[real] - 1e-3).any()
    assert np.array_equal(out["composite"] - out["background"], out["delta"])
    view = scene.background
    view[0, 0] = 0.5  # a view of the scene's photo, not a copy
    assert scene.background[0, 0, 0] == 0.5
    scene.camera_pose = translation(0, 0.3, 2.5)
    assert np.array_equal(scene.camera_pose, translation(0, 0.3, 2.5))
    scene.background = None
    assert not np.array_equal(deltagi.render(scene)["composite"], out["composite"])


def one_line_error(action):
    with pytest.raises(deltagi.InputError) as error:
        action()
    message = str(error.value)
    assert "\n" not in message and isinstance(error.value, ValueError)
    return message


def test_bad_input_raises_one_line_input_error(scene_file, tmp_path):
    assert "cannot open scene file" in one_line_error(lambda: deltagi.Scene.load(tmp_path / "missing.json"))
    assert "options.volume.resolution: expected a power of two" in one_line_error(
        lambda: deltagi.Scene.load(scene_file, ["options.volume.resolution=100"]))
    scene = deltagi.Scene.load(scene_file)
    flat = np.diag([1, 0, 1, 1]).astype(np.float32)
    assert "mesh 'box': transform: expected an invertible matrix" in one_line_error(
        lambda: scene.set_object_transform("box", flat))
    assert "no virtual object of that name (there are: 'box')" in one_line_error(
        lambda: scene.set_object_transform("ball", np.eye(4)))
    assert "object 3: out of range" in one_line_error(lambda: scene.set_object_transform(3, np.eye(4)))
    assert "transform: expected a 4x4 matrix, got shape (3, 3)" in one_line_error(
        lambda: scene.set_object_transform(0, np.eye(3)))
    assert "camera_pose: expected an orthonormal rotation" in one_line_error(
        lambda: setattr(scene, "camera_pose", np.diag([2, 2, 2, 1])))
    assert "up: expected a direction not parallel" in one_line_error(
        lambda: scene.set_camera((0, 0, 0), (0, 1, 0), up=(0, 1, 0)))
    assert "background: expected an RGB image" in one_line_error(
        lambda: setattr(scene, "background", np.zeros((36, 48))))
    scene.background = np.zeros((10, 10, 3))  # the size is checked with the camera's, before the frame
    assert "background: expected an RGB image of the camera's size 48x36, got 10x10" in one_line_error(
        lambda: deltagi.render(scene))
    nan = np.zeros((36, 48, 3))
    nan[5, 7, 1] = np.nan
    scene.background = nan
    assert "background: pixel (7, 5) is not finite" in one_line_error(lambda: deltagi.render(scene))
    # The scene is unchanged by the refused calls.
    assert np.array_equal(scene.object_transform(0), translation(0, 0.15, 0))


def test_the_gil_is_released_while_rendering(tmp_path):
    path = tmp_path / "bigger.json"
    document = tiny_scene(160, 120)
    document["options"]["volume"]["resolution"] = 32
    path.write_text(json.dumps(document))
    scene = deltagi.Scene.load(path)
    result = {}
    thread = threading.Thread(target=lambda: result.update(deltagi.render(scene)))
    # The longest pause of this loop while the other thread renders: the whole frame if it held the GIL.
    longest, last = 0.0, time.perf_counter()
    thread.start()
    while thread.is_alive():
        now = time.perf_counter()
        longest, last = max(longest, now - last), now
    thread.join()
    assert longest * 1000 < 0.5 * result["total_ms"], (longest, result["total_ms"])
