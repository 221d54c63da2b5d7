// `deltagi track`: a video (or numbered images, or a V4L2 camera) in which the scene's markers are seen,
// registered frame by frame (src/live/marker_registration.h) into a nerfstudio transforms file with the
// frames as photos beside it: a sequence for `render`.
#pragma once

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

#include "live/frame_source.h"
#include "live/marker_registration.h"

namespace deltagi::cli {

struct TrackArgs {
    std::string source;                   // a video file, /dev/videoN or frame_####.png
    std::filesystem::path scene;          // the scene file: its markers and its camera's intrinsics
    std::filesystem::path output;         // transforms.json
    std::string framesFolder = "frames";  // the photos, relative to the output's folder
    double patternFps = 30.0;             // the frame rate of a numbered-image source
    int maxFrames = 0;                    // 0: until the source ends
    TrackingOptions tracking;
    bool noSmoothing = false;
    bool quiet = false;
};

CLI::App* addTrackCommand(CLI::App& app, TrackArgs& args);

// --max-speed, shared with `live`: TrackingOptions::maxSpeed.
void addMaxSpeedOption(CLI::App& command, TrackingOptions& tracking);

// Throws InputError naming the source when its frames are not of `camera`'s size (the scene camera's
// intrinsics, from `sceneFile`, must be those of the frames); `live` checks its camera so too.
void checkFrameSize(const FrameSource& source, const Camera& camera, const std::filesystem::path& sceneFile);

// Throws InputError on bad input: a source that cannot be read or changes size, frames not of the scene
// camera's size, a scene without markers, no frame registered.
int runTrack(const TrackArgs& args);

}  // namespace deltagi::cli
