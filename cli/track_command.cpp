// `deltagi track` (cli/track_command.h).
#include "track_command.h"

#include <unistd.h>

#include <algorithm>
#include <vector>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "live/frame_source.h"
#include "outputs.h"
#include "validators.h"

namespace fs = std::filesystem;
using nlohmann::ordered_json;

namespace deltagi::cli {

namespace {

// nerfstudio's intrinsics (the keys readTransforms reads).
void writeIntrinsics(const Camera& camera, ordered_json& out) {
    const LensDistortion& d = camera.distortion;
    out["camera_model"] = d.model == LensDistortion::Model::OpenCV    ? "OPENCV"
                          : d.model == LensDistortion::Model::Fisheye ? "OPENCV_FISHEYE"
                                                                      : "PINHOLE";
    out["w"] = camera.width;
    out["h"] = camera.height;
    out["fl_x"] = camera.fx;
    out["fl_y"] = camera.fy;
    out["cx"] = camera.cx;
    out["cy"] = camera.cy;
    if (d.model == LensDistortion::Model::OpenCV) {
        out["k1"] = d.k1, out["k2"] = d.k2, out["k3"] = d.k3, out["p1"] = d.p1, out["p2"] = d.p2;
    } else if (d.model == LensDistortion::Model::Fisheye) {
        out["k1"] = d.k1, out["k2"] = d.k2, out["k3"] = d.k3, out["k4"] = d.k4;
    }
}

ordered_json rows(const glm::mat4& m) {
    ordered_json out = ordered_json::array();
    for (int r = 0; r < 4; ++r)
        out.push_back(
            {rounded(m[0][r], 1e6), rounded(m[1][r], 1e6), rounded(m[2][r], 1e6), rounded(m[3][r], 1e6)});
    return out;
}

std::string markerIds(const Scene& scene) {
    std::string ids;
    for (const Marker& m : scene.markers) ids += (ids.empty() ? "" : ", ") + std::to_string(m.id);
    return ids;
}

}  // namespace

void checkFrameSize(const FrameSource& source, const Camera& camera, const fs::path& sceneFile) {
    if (source.width() != camera.width || source.height() != camera.height)
        throw InputError(source.name(), fmt::format("frames of {}x{}, the scene's camera ({}) is {}x{}: its "
                                                    "intrinsics must be those of these frames",
                                                    source.width(), source.height(), sceneFile.string(),
                                                    camera.width, camera.height));
}

void addMaxSpeedOption(CLI::App& command, TrackingOptions& tracking) {
    command
        .add_option(
            "--max-speed", tracking.maxSpeed,
            "Within the hold time, a pose from no more markers than the last frame's that moves the "
            "camera faster than this (world units per second; default 2) is not trusted: the last pose "
            "stands in. This speed times the time since the last pose also bounds how far a pose is "
            "let move from it (a prior on the camera's position; docs/live.md, Registration) (0: every "
            "pose is taken, no prior)")
        ->check(finiteRange(0.0, 1e6));
}

CLI::App* addTrackCommand(CLI::App& app, TrackArgs& args) {
    CLI::App* command = app.add_subcommand(
        "track", "Register a video by the scene's markers into a transforms file for `render` (a sequence)");
    command
        ->add_option("source", args.source,
                     "The camera's frames: a video file, a V4L2 device (/dev/video0) or numbered images "
                     "(frames/frame_####.png)")
        ->required();
    command->add_option("--scene", args.scene, "The scene file: its \"markers\" and its camera's intrinsics")
        ->required();
    command->add_option("-o,--output", args.output, "The transforms file to write (transforms.json)")
        ->required();
    command->add_option(
        "--frames-folder", args.framesFolder,
        "Where the frames go as PNG photos, relative to the output's folder (default frames)");
    command->add_option("--fps", args.patternFps, "The frame rate of numbered images (default 30)")
        ->check(finiteRange(1e-3, 1000.0));
    command->add_option("--max-frames", args.maxFrames, "Stop after this many frames (default: all)")
        ->check(CLI::Range(1, 1000000));
    command
        ->add_option(
            "--hold", args.tracking.holdSeconds,
            "Seconds a frame without markers keeps the last pose (default 0.5); later ones are left out")
        ->check(finiteRange(0.0, 60.0));
    addMaxSpeedOption(*command, args.tracking);
    command
        ->add_option("--min-cutoff", args.tracking.smoothing.minCutoffHz,
                     "The pose filter's cut-off for a still camera, in Hz (default 1; lower is steadier)")
        ->check(finiteRange(1e-3, 1000.0));
    command
        ->add_option("--beta", args.tracking.smoothing.positionBeta,
                     "How fast the filter's cut-off rises with the camera's speed, per world unit per second "
                     "(default 20; higher follows motion with less lag)")
        ->check(finiteRange(0.0, 1e6));
    command->add_flag("--no-smoothing", args.noSmoothing, "Each frame's own pose, unfiltered");
    command->add_flag("-q,--quiet", args.quiet, "Print nothing but errors");
    return command;
}

int runTrack(const TrackArgs& args) {
    const Scene scene = loadScene(args.scene);
    if (scene.markers.empty())
        throw InputError(args.scene.string(),
                         "markers: the scene places no marker to register the camera by");
    if (args.output.extension() != ".json")
        throw InputError(args.output.string(), "expected a .json file name for the transforms");
    const fs::path folder = args.output.parent_path();
    const fs::path framesFolder(args.framesFolder);
    if (framesFolder.is_absolute() || framesFolder.empty())
        throw InputError("--frames-folder",
                         "expected a folder relative to the output's, got '" + args.framesFolder + "'");
    checkOutputs({args.output}, sceneInputs(scene));

    std::unique_ptr<FrameSource> source = openFrameSource(args.source, args.patternFps);
    const Camera& camera = scene.camera;
    checkFrameSize(*source, camera, args.scene);
    TrackingOptions tracking = args.tracking;
    tracking.smoothing.enabled = !args.noSmoothing;
    MarkerTracker tracker(scene.markers, camera, tracking);

    ordered_json transforms;
    writeIntrinsics(camera, transforms);
    transforms["fps"] = source->frameRate() > 0.0 ? source->frameRate() : args.patternFps;
    ordered_json& frames = transforms["frames"] = ordered_json::array();
    OutputFiles outputs;
    int registered = 0, held = 0, lost = 0, uncertain = 0, unknownTags = 0, tooSmall = 0;
    std::vector<double> errors;
    const bool progress = !args.quiet && isatty(STDERR_FILENO);
    int64_t count = 0;
    while (args.maxFrames == 0 || count < args.maxFrames) {
        std::optional<CameraFrame> frame = source->next();
        if (!frame) break;
        ++count;
        const TrackedFrame tracked = tracker.track(frame->image, frame->timeSeconds);
        unknownTags = std::max(unknownTags, tracked.unknownTags);
        tooSmall = std::max(tooSmall, tracked.tooSmall);
        if (progress) fmt::print(stderr, "\rframe {}   ", frame->index);
        if (tracked.state == TrackedFrame::State::Lost) {
            ++lost;
            uncertain += tracked.uncertain;
            continue;
        }
        const fs::path photo = framesFolder / fmt::format("frame_{:04d}.png", frame->index);
        outputs.image(frame->image, folder / photo);
        ordered_json entry;
        entry["file_path"] = photo.generic_string();
        entry["transform_matrix"] = rows(tracked.worldFromCamera);
        entry["time"] = rounded(frame->timeSeconds, 1e6);
        if (tracked.state == TrackedFrame::State::Registered) {
            ++registered;
            errors.push_back(tracked.reprojectionErrorPx);
            entry["registration"] = "markers";
            entry["markers_seen"] = tracked.markersSeen;
            entry["reprojection_error_px"] = rounded(tracked.reprojectionErrorPx, 1e4);
        } else {
            ++held;
            entry["registration"] = "held";
        }
        frames.push_back(std::move(entry));
    }
    if (progress) fmt::print(stderr, "\n");
    if (count == 0) throw InputError(source->name(), "holds no frame");
    if (registered == 0)
        throw InputError(
            source->name(),
            fmt::format(
                "no frame registered: none of the scene's markers (tag36h11, ids {}) was seen "
                "in {} frames{}{}{}",
                markerIds(scene), count, unknownTags ? fmt::format("; tags of other ids were") : "",
                tooSmall ? fmt::format("; the markers were too small (under {:g} pixels)", kMinMarkerSidePx)
                         : "",
                uncertain ? fmt::format("; in {} the markers seen fit poses far apart (one small marker "
                                        "alone: show a second marker or come nearer)",
                                        uncertain)
                          : ""));
    outputs.json(transforms, args.output);
    outputs.commit();
    if (!args.quiet) {
        std::sort(errors.begin(), errors.end());
        fmt::print(
            stderr,
            "deltagi: wrote {} ({} of {} frames: {} registered by markers, {} holding the last pose; {} "
            "without a pose left out{}); reprojection error median {:.3f} px, max {:.3f} px\n",
            args.output.string(), registered + held, count, registered, held, lost,
            uncertain ? fmt::format(", {} of them of uncertain pose (one small marker alone)", uncertain)
                      : "",
            errors[errors.size() / 2], errors.back());
    }
    return 0;
}

}  // namespace deltagi::cli
