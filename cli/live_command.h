// `deltagi live`: the paper's live system (§4, Fig. 2). A scene camera's frames are registered by the
// scene's markers and each is augmented over itself as it arrives; a light camera's frames, when given,
// become the environment that lights the scene (smoothed over time). Frames come from video files,
// numbered images or V4L2 devices; the augmented frames go to numbered images and/or an MP4, and each
// frame's latency (arrival to composite), dropped frames, pose and stage times are reported.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "live/marker_registration.h"
#include "video_output.h"

namespace deltagi::cli {

struct LiveArgs {
    std::filesystem::path scene;
    std::string camera;       // the scene camera: a video file, /dev/videoN or frame_####.png
    std::string lightCamera;  // the light camera (optional): through the scene's "environment" projection
    std::filesystem::path output;  // frame_####.png (optional)
    std::filesystem::path video;   // .mp4 (optional)
    std::filesystem::path json;    // per-frame statistics (optional)
    bool realtime = false;  // replay files at their frames' pace, dropping what rendering cannot keep up with
    double patternFps = 30.0;
    int maxFrames = 0;
    double lightSmoothingSeconds = 0.15;
    TrackingOptions tracking;
    std::vector<std::string> overrides;
    VideoSettings videoSettings;
    bool quiet = false;
    // --serve: the frames in the browser page instead (`deltagi serve` with this camera), on this address.
    bool serve = false;
    std::string host = "127.0.0.1";
    int port = 8080;
};

CLI::App* addLiveCommand(CLI::App& app, LiveArgs& args);

int runLive(const LiveArgs& args);

}  // namespace deltagi::cli
