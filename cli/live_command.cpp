// `deltagi live` (cli/live_command.h).
#include "live_command.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include <fmt/core.h>
#include <tbb/parallel_invoke.h>
#include <nlohmann/json.hpp>

#include "deltagi/environment.h"
#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "live/frame_source.h"
#include "live/light_camera.h"
#include "messages.h"
#include "outputs.h"
#include "serve_command.h"
#include "track_command.h"
#include "validators.h"

namespace fs = std::filesystem;
using nlohmann::ordered_json;

namespace deltagi::cli {

namespace {

using Clock = std::chrono::steady_clock;

// The share of a light-camera frame's pixels at its white above which `live` warns (once) of a clipped light.
constexpr double kClippedShareWarning = 0.001;

double millisecondsSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

const char* stateName(TrackedFrame::State s) {
    return s == TrackedFrame::State::Registered ? "markers"
           : s == TrackedFrame::State::Held     ? "held"
                                                : "lost";
}

}  // namespace

CLI::App* addLiveCommand(CLI::App& app, LiveArgs& args) {
    CLI::App* command = app.add_subcommand(
        "live",
        "Augment a camera's frames as they come, registered by the scene's markers, lit by a light camera");
    command->add_option("scene", args.scene, "The scene file: the reconstruction, the objects, the markers")
        ->required();
    command
        ->add_option("--camera", args.camera,
                     "The scene camera: a video file, a V4L2 device (/dev/video0) or numbered images "
                     "(frames/frame_####.png), of the scene camera's size")
        ->required();
    command->add_option("--light-camera", args.lightCamera,
                        "The light camera, the same kinds: each frame becomes the environment, through the "
                        "scene's \"environment\" projection, rotation and intensity");
    command->add_option("-o,--output", args.output, "The augmented frames (out/frame_####.png)");
    command->add_option("--video", args.video,
                        "The augmented frames as an H.264 MP4 (.mp4) or uncompressed (.y4m)");
    command->add_option("--json", args.json, "Each frame's latency, drops, pose and stage times (JSON)");
    command->add_flag(
        "--realtime", args.realtime,
        "Replay files at their frames' pace, as a camera would give them: frames that arrive while "
        "one renders are dropped, the newest wins (a device always is)");
    command->add_option("--fps", args.patternFps, "The frame rate of numbered images (default 30)")
        ->check(finiteRange(1e-3, 1000.0));
    command->add_option("--max-frames", args.maxFrames, "Stop after this many frames (default: all)")
        ->check(CLI::Range(1, 100000000));
    command
        ->add_option(
            "--hold", args.tracking.holdSeconds,
            "Seconds a frame without markers keeps the last pose (default 0.5); then the camera image "
            "is shown as it is")
        ->check(finiteRange(0.0, 60.0));
    addMaxSpeedOption(*command, args.tracking);
    command
        ->add_option("--light-smoothing", args.lightSmoothingSeconds,
                     "Time constant of the light camera's averaging, in seconds (default 0.15)")
        ->check(finiteRange(1e-3, 60.0));
    command->add_option("--set", args.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    command->add_flag("-q,--quiet", args.quiet, "Print nothing but errors");
    CLI::Option* serve = command->add_flag(
        "--serve", args.serve,
        "Show the frames in the browser page of `deltagi serve` (objects dragged there, stage "
        "times charted) instead of writing them");
    command
        ->add_option("--port", args.port,
                     "With --serve: the TCP port (default 8080; 0: any free one, printed)")
        ->check(CLI::Range(0, 65535))
        ->needs(serve);
    command->add_option("--host", args.host, "With --serve: the address to listen on (default 127.0.0.1)")
        ->needs(serve);
    return command;
}

int runLive(const LiveArgs& args) {
    if (args.serve) {
        if (!args.output.empty() || !args.video.empty() || !args.json.empty())
            throw InputError("live",
                             "--serve shows the frames in the browser; -o, --video and --json are for a "
                             "run without it");
        ServeArgs serve;
        serve.scene = args.scene;
        serve.overrides = args.overrides;
        serve.host = args.host;
        serve.port = args.port;
        serve.camera = args.camera;
        serve.lightCamera = args.lightCamera;
        serve.patternFps = args.patternFps;
        serve.lightSmoothingSeconds = args.lightSmoothingSeconds;
        serve.tracking = args.tracking;
        return runServe(serve);
    }
    if (args.output.empty() && args.video.empty() && args.json.empty())
        throw InputError("live",
                         "nothing to write: give -o FRAME_####.png, --video OUT.mp4 and/or --json OUT.json");
    if (!args.video.empty()) {
        checkVideoPath(args.video, "--video");
        checkVideoEncoder(args.video, "--video");
    }
    Scene scene = loadAndWarn(args.scene, args.overrides);
    if (scene.markers.empty())
        throw InputError(args.scene.string(),
                         "markers: the scene places no marker to register the camera by");
    if (!scene.sequence.empty())
        throw InputError(args.scene.string(),
                         "sequence: a live scene's frames come from --camera, not a sequence");
    std::vector<fs::path> outputs;
    if (!args.output.empty()) outputs.push_back(framePath(args.output, 0));
    for (const fs::path* p : {&args.video, &args.json})
        if (!p->empty()) outputs.push_back(*p);
    checkOutputs(outputs, sceneInputs(scene));

    FrameFeed camera(openFrameSource(args.camera, args.patternFps), args.realtime);
    const Camera intrinsics = scene.camera;
    checkFrameSize(camera.source(), intrinsics, args.scene);
    std::optional<LightCamera> light;
    std::optional<FrameFeed> lightFeed;
    if (!args.lightCamera.empty()) {
        light.emplace(args.scene, args.overrides, args.lightSmoothingSeconds);
        lightFeed.emplace(openFrameSource(args.lightCamera, args.patternFps), args.realtime);
    }
    MarkerTracker tracker(scene.markers, intrinsics, args.tracking);
    FrameRenderer renderer;
    std::optional<VideoWriter> video;
    if (!args.video.empty()) {
        VideoSettings settings = args.videoSettings;
        if (camera.source().frameRate() > 0.0) settings.fps = camera.source().frameRate();
        createOutputFolder(args.video.parent_path());
        video.emplace(args.video, intrinsics.width, intrinsics.height, settings);
    }

    ordered_json frames = ordered_json::array();
    std::vector<double> latencies, renders, errors;
    int count = 0, registered = 0, held = 0, lost = 0, lightFrames = 0;
    bool wasLost = false, warnedClipped = false;
    while (args.maxFrames == 0 || count < args.maxFrames) {
        std::optional<FrameFeed::Arrival> arrival = camera.take();
        if (!arrival) break;
        ++count;
        const CameraFrame& frame = arrival->frame;
        const double waited =
            std::chrono::duration<double, std::milli>(Clock::now() - arrival->arrived).count();
        // The light: the newest light-camera frame (replayed files: one per scene-camera frame).
        std::optional<FrameFeed::Arrival> lit;
        if (lightFeed) lit = args.realtime ? lightFeed->poll() : lightFeed->take();
        // The frame's pose and its new light do not depend on each other: found side by side (each is
        // mostly one thread's work).
        double environmentMs = 0.0, trackMs = 0.0;
        TrackedFrame tracked;
        tbb::parallel_invoke(
            [&] {
                const Clock::time_point start = Clock::now();
                tracked = tracker.track(frame.image, frame.timeSeconds);
                trackMs = millisecondsSince(start);
            },
            [&] {
                if (!lit) return;
                const Clock::time_point start = Clock::now();
                setEnvironment(scene, light->environment(std::move(lit->frame.image), lit->frame.timeSeconds,
                                                         lightFeed->source().name()));
                environmentMs = millisecondsSince(start);
            });
        if (lit) {
            ++lightFrames;
            if (!warnedClipped && light->clippedShare() > kClippedShareWarning) {
                warnedClipped = true;
                note(
                    "deltagi: warning: {}: frame {}: {:.1f} % of the light camera's pixels are at its white: "
                    "a light brighter than that (the sun, a bare lamp) is recorded too dim and lights the "
                    "scene too weakly; lower the camera's exposure and raise the environment's intensity to "
                    "match\n",
                    lightFeed->source().name(), lit->frame.index, 100.0 * light->clippedShare());
            }
        }
        Image composite;
        std::optional<RenderOutput> rendered;
        if (tracked.state == TrackedFrame::State::Lost) {
            ++lost;
            if (!wasLost && !args.quiet) {
                if (tracked.uncertain)
                    note(
                        "deltagi: frame {} ({:.2f} s): the markers seen fit poses far apart (one small "
                        "marker alone; a second marker or a nearer camera decides): showing the camera image "
                        "as it is\n",
                        frame.index, frame.timeSeconds);
                else
                    note(
                        "deltagi: frame {} ({:.2f} s): no marker for {:g} s: showing the camera image as it "
                        "is\n",
                        frame.index, frame.timeSeconds, args.tracking.holdSeconds);
            }
            wasLost = true;
            composite = frame.image;
        } else {
            if (wasLost && !args.quiet) note("deltagi: frame {}: markers seen again\n", frame.index);
            wasLost = false;
            tracked.state == TrackedFrame::State::Registered ? ++registered : ++held;
            scene.camera.worldFromCamera = tracked.worldFromCamera;
            // The side of each real surface the light is kept on is the one the first registered camera sees
            // (as a sequence's first camera): a hand-held camera would otherwise cross the planes of some
            // surfaces back and forth and have the real scene's light made again in every other frame.
            if (!scene.options.volume.viewpoint) scene.options.volume.viewpoint = scene.camera.position();
            scene.background = frame.image;
            rendered = renderer.render(scene);
            composite = rendered->composite;
        }
        const double latency =
            std::chrono::duration<double, std::milli>(Clock::now() - arrival->arrived).count();
        latencies.push_back(latency);
        if (rendered) renders.push_back(rendered->totalMs);
        if (tracked.state == TrackedFrame::State::Registered) errors.push_back(tracked.reprojectionErrorPx);
        if (!args.output.empty()) {
            OutputFiles out;
            out.image(composite, framePath(args.output, static_cast<int>(frame.index)));
            out.commit();
        }
        if (video) video->add(composite);
        ordered_json row;
        row["index"] = frame.index;
        row["time"] = rounded(frame.timeSeconds, 1e6);
        row["latency_ms"] = rounded(latency, 1e3);
        row["waited_ms"] = rounded(waited, 1e3);  // for the frame before to be done
        row["dropped"] = arrival->dropped;
        row["registration"] = stateName(tracked.state);
        row["markers_seen"] = tracked.markersSeen;
        if (tracked.uncertain) row["uncertain"] = true;
        if (tracked.state == TrackedFrame::State::Registered)
            row["reprojection_error_px"] = rounded(tracked.reprojectionErrorPx, 1e4);
        row["track_ms"] = rounded(trackMs, 1e3);
        row["environment_ms"] = rounded(environmentMs, 1e3);
        if (rendered) {
            row["render_ms"] = rounded(rendered->totalMs, 1e3);
            row["stages_ms"] = stageTimesJson(*rendered, 1e3);
        }
        if (!args.quiet)
            note(
                "frame {}: {:.0f} ms from arrival to composite ({}{}{:.0f} ms tracking{}), {} dropped, "
                "{}{}\n",
                frame.index, latency, waited >= 0.5 ? fmt::format("{:.0f} ms waiting, ", waited) : "",
                rendered ? fmt::format("{:.0f} ms rendering, ", rendered->totalMs) : "", trackMs,
                environmentMs > 0.0 ? fmt::format(", {:.0f} ms new light", environmentMs) : "",
                arrival->dropped, stateName(tracked.state),
                tracked.state == TrackedFrame::State::Registered
                    ? fmt::format(" ({} marker{}, {:.2f} px)", tracked.markersSeen,
                                  tracked.markersSeen == 1 ? "" : "s", tracked.reprojectionErrorPx)
                    : "");
        frames.push_back(std::move(row));
    }
    if (count == 0) throw InputError(camera.source().name(), "holds no frame");
    if (video) video->commit();
    const int dropped = camera.droppedTotal();
    ordered_json summary;
    summary["frames"] = count;
    summary["dropped"] = dropped;
    summary["registered"] = registered;
    summary["held"] = held;
    summary["lost"] = lost;
    summary["light_frames"] = lightFrames;
    summary["latency_ms_median"] = rounded(median(latencies), 1e3);
    summary["render_ms_median"] = rounded(median(renders), 1e3);
    summary["reprojection_error_px_median"] = rounded(median(errors), 1e4);
    if (!args.json.empty()) {
        ordered_json document;
        document["summary"] = summary;
        document["frames"] = std::move(frames);
        writeJson(document, args.json);
    }
    if (!args.quiet)
        note(
            "deltagi: {} frames ({} dropped): {} registered by markers, {} holding the last pose, {} "
            "without; "
            "latency median {:.0f} ms, rendering {:.0f} ms, reprojection error {:.2f} px\n",
            count, dropped, registered, held, lost, median(latencies), median(renders), median(errors));
    return 0;
}

}  // namespace deltagi::cli
