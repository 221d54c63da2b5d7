#!/usr/bin/env python3
"""How much `deltagi track`'s poses change the augmented frames: each frame of a capture rendered over its photo
from the pose `track` found and from the true pose (scripts/make-live-capture.sh writes truth.json), and the
change to the photo (delta) of the first compared with the second's, as `deltagi eval` compares DGI with the
path tracer: delta_rel_error = |delta_tracked - delta_true| / |delta_true| over the pixels that show the real
scene in both. Also the camera position error. Needs the Python module (build/python, or installed).

    PYTHONPATH=build/python scripts/track-vs-truth.py out/live-capture/scene.json \\
        out/live-capture/tracked/transforms.json out/live-capture/truth.json

With --still instead of the truth file: each frame at the tracked pose rendered as `deltagi live` renders it
(one renderer over the frames, keeping what they share and averaging frames over time) against a still render
of the same frame and pose (a renderer of its own: a frame from scratch with the session's settings, not the
finer still of `deltagi render`), and the objects compared too (object_rel_rmse).

    PYTHONPATH=build/python scripts/track-vs-truth.py out/live-capture/scene.json \\
        out/live-capture/tracked/transforms.json --still

With --still and --reference-spp N as well: frames (every 8th, or --frames 0,8,16) are also path-traced at the
tracked pose (`deltagi reference --spp N`, the binary given by --deltagi, build/deltagi by default), and the live
and the still render are each judged against that reference as `deltagi eval` judges DGI: delta_rel_error over
the pixels that show the real scene in all three, object_rel_rmse over those the objects cover in all three.

    PYTHONPATH=build/python scripts/track-vs-truth.py out/live-capture/scene.json \
        out/live-capture/tracked/transforms.json --still --reference-spp 4096

`--set KEY=VALUE` (as many as needed, as deltagi's) changes the scene of every render.
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

import deltagi


def frames(path):
    with open(path) as f:
        document = json.load(f)
    folder = os.path.dirname(os.path.abspath(path))
    return [(os.path.join(folder, frame["file_path"]), np.array(frame["transform_matrix"], dtype=np.float32))
            for frame in document["frames"]]


def path_traced(deltagi_binary, scene_file, pose, spp, overrides, folder):
    """The reference's composite, the change to the real scene (with - without) and the objects' mask at `pose`
    (world from camera, the camera looking along its -z with +y up)."""
    position, forward, up = pose[:3, 3], -pose[:3, 2], pose[:3, 1]
    look_at = position + forward
    vector = lambda v: "[" + ", ".join(f"{float(x):.9g}" for x in v) + "]"
    command = [deltagi_binary, "reference", scene_file, "--spp", str(spp), "-q", "-o", os.path.join(folder, "ref.exr"),
               "--aov", folder, "--set", f"camera.position={vector(position)}",
               "--set", f"camera.look_at={vector(look_at)}", "--set", f"camera.up={vector(up)}"]
    for o in overrides:
        command += ["--set", o]
    subprocess.run(command, check=True)
    read = lambda name: deltagi.read_image(os.path.join(folder, name + ".exr"))
    return read("composite"), read("with") - read("without"), read("object_mask")[..., 0]


def figures(render, reference):
    """delta_rel_error and object_rel_rmse of a render (a FrameRenderer's result) against a path-traced one."""
    ref_composite, ref_delta, ref_mask = reference
    mask = render["object_mask"][..., 0] if render["object_mask"].ndim == 3 else render["object_mask"]
    real = (mask <= 0.0) & (ref_mask <= 0.0)
    covered = (mask >= 1.0) & (ref_mask >= 1.0)
    d = (render["delta"] - ref_delta)[real]
    o = (render["composite"] - ref_composite)[covered]
    return (float(np.sqrt((d ** 2).sum()) / max(np.sqrt((ref_delta[real] ** 2).sum()), 1e-30)),
            float(np.sqrt((o ** 2).sum()) / max(np.sqrt((ref_composite[covered] ** 2).sum()), 1e-30)))


def live_against_still(scene_file, tracked_file, overrides=(), reference_spp=0, chosen=None,
                       deltagi_binary="build/deltagi"):
    tracked = frames(tracked_file)
    if chosen is None:
        chosen = set(range(0, len(tracked), 8))
    judged = []  # per frame judged: (live delta, still delta, live object, still object) against the reference
    first = tracked[0][1][:3, 3]
    viewpoint = f"options.volume.viewpoint=[{first[0]}, {first[1]}, {first[2]}]"
    live_scene = deltagi.Scene.load(scene_file, [viewpoint, *overrides])
    live = deltagi.FrameRenderer()
    deltas, objects = [], []
    for photo_path, pose in tracked:
        photo = deltagi.read_image(photo_path)
        live_scene.camera_pose = pose
        live_scene.background = photo
        a = live.render(live_scene)
        still_scene = deltagi.Scene.load(scene_file, [viewpoint, *overrides])
        still_scene.camera_pose = pose
        still_scene.background = photo
        b = deltagi.FrameRenderer().render(still_scene)
        real = (a["object_mask"] <= 0.0) & (b["object_mask"] <= 0.0)
        d = (a["delta"] - b["delta"])[real]
        deltas.append(float(np.sqrt((d ** 2).sum()) / max(np.sqrt((b["delta"][real] ** 2).sum()), 1e-30)))
        covered = (b["object_mask"] >= 1.0) & (a["object_mask"] >= 1.0)
        o = (a["composite"] - b["composite"])[covered]
        objects.append(float(np.sqrt((o ** 2).mean()) / max(np.sqrt((b["composite"][covered] ** 2).mean()), 1e-30)))
        print(f"{os.path.basename(photo_path)}: delta_rel_error {deltas[-1]:.4f}, object_rel_rmse {objects[-1]:.4f}",
              flush=True)
        if reference_spp > 0 and len(deltas) - 1 in chosen:
            with tempfile.TemporaryDirectory() as folder:
                reference = path_traced(deltagi_binary, scene_file, pose, reference_spp, overrides, folder)
            (live_delta, live_object), (still_delta, still_object) = figures(a, reference), figures(b, reference)
            judged.append((live_delta, still_delta, live_object, still_object))
            print(f"  against the path tracer ({reference_spp} spp): delta_rel_error live {live_delta:.4f}, still "
                  f"{still_delta:.4f}; object_rel_rmse live {live_object:.4f}, still {still_object:.4f}", flush=True)
    print(f"{len(deltas)} frames, live against still: delta_rel_error median {sorted(deltas)[len(deltas) // 2]:.4f}, "
          f"worst {max(deltas):.4f}; object_rel_rmse median {sorted(objects)[len(objects) // 2]:.4f}, "
          f"worst {max(objects):.4f}")
    if judged:
        gaps = lambda i, j: sorted(abs(row[i] - row[j]) for row in judged)
        delta_gaps, object_gaps = gaps(0, 1), gaps(2, 3)
        print(f"{len(judged)} frames against the path tracer: live minus still, delta_rel_error "
              f"{', '.join(f'{row[0] - row[1]:+.4f}' for row in judged)} (largest gap {delta_gaps[-1]:.4f}); "
              f"object_rel_rmse {', '.join(f'{row[2] - row[3]:+.4f}' for row in judged)} "
              f"(largest gap {object_gaps[-1]:.4f})")


def main():
    # --set KEY=VALUE (any number, as deltagi's --set) changes the scene of every render.
    args, overrides = [], []
    reference_spp, chosen, deltagi_binary = 0, None, "build/deltagi"
    argv = sys.argv[1:]
    while argv:
        arg = argv.pop(0)
        if arg == "--set" and argv:
            overrides.append(argv.pop(0))
        elif arg == "--reference-spp" and argv:
            reference_spp = int(argv.pop(0))
        elif arg == "--frames" and argv:
            chosen = {int(f) for f in argv.pop(0).split(",")}
        elif arg == "--deltagi" and argv:
            deltagi_binary = argv.pop(0)
        else:
            args.append(arg)
    if len(args) == 3 and args[2] == "--still":
        return live_against_still(args[0], args[1], overrides, reference_spp, chosen, deltagi_binary)
    if len(args) != 3:
        sys.exit(__doc__)
    scene_file, tracked_file, truth_file = args
    tracked = {os.path.basename(photo): pose for photo, pose in frames(tracked_file)}
    truth = frames(truth_file)
    # The light kept on the side the first true camera sees, as `deltagi live` keeps it.
    first = truth[0][1][:3, 3]
    viewpoint = f"options.volume.viewpoint=[{first[0]}, {first[1]}, {first[2]}]"
    scenes = {kind: deltagi.Scene.load(scene_file, [viewpoint, *overrides]) for kind in ("tracked", "true")}
    renderers = {kind: deltagi.FrameRenderer() for kind in scenes}
    errors, positions = [], []
    for photo_path, true_pose in truth:
        name = os.path.basename(photo_path)
        if name not in tracked:
            continue
        photo = deltagi.read_image(photo_path)
        results = {}
        for kind, pose in (("tracked", tracked[name]), ("true", true_pose)):
            scenes[kind].camera_pose = pose
            scenes[kind].background = photo
            results[kind] = renderers[kind].render(scenes[kind])
        real = (results["tracked"]["object_mask"] <= 0.0) & (results["true"]["object_mask"] <= 0.0)
        difference = (results["tracked"]["delta"] - results["true"]["delta"])[real]
        reference = results["true"]["delta"][real]
        errors.append(float(np.sqrt((difference ** 2).sum()) / max(np.sqrt((reference ** 2).sum()), 1e-30)))
        positions.append(float(np.linalg.norm(tracked[name][:3, 3] - true_pose[:3, 3])))
        print(f"{name}: delta_rel_error {errors[-1]:.4f}, camera {100 * positions[-1]:.2f} cm off", flush=True)
    if not errors:
        sys.exit("track-vs-truth.py: no frame of the truth is in the tracked transforms")
    errors_sorted = sorted(errors)
    print(f"{len(errors)} frames: delta_rel_error median {errors_sorted[len(errors) // 2]:.4f}, "
          f"worst {errors_sorted[-1]:.4f}; camera median {100 * sorted(positions)[len(positions) // 2]:.2f} cm")


if __name__ == "__main__":
    main()
