// `deltagi serve SCENE.json [--port 8080] [--host 127.0.0.1]`: a live session in the browser (README, "Live
// session"). A web server (web_server.h, on Boost.Beast) serves the page of web/, embedded at build time, and
// streams the frames to it as JPEGs over a WebSocket; the page's messages change the scene
// (src/live/live_session.h).
// The scene camera's frames come from the page's camera or, for `deltagi live --serve`, from a source the
// server reads (docs/live.md).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "live/marker_registration.h"

namespace deltagi::cli {

struct ServeArgs {
    std::filesystem::path scene;
    std::vector<std::string> overrides;
    std::string host = "127.0.0.1";
    int port = 8080;  // 0: any free port (printed)
    int threads = 0;
    int jpegQuality = 85;
    int interactiveScale = 2;  // the frames while something changes at 1 / this of the width and height
    std::vector<std::string>
        allowedHosts;  // names the page may be opened by, besides addresses and localhost

    // `deltagi live --serve`: a scene camera (and a light camera) the server reads itself, as `live` does,
    // instead of the page's; empty: none (the page may send its own).
    std::string camera, lightCamera;
    double patternFps = 30.0;
    double lightSmoothingSeconds = 0.15;
    TrackingOptions tracking;
};

CLI::App* addServeCommand(CLI::App& app, ServeArgs& args, int maxThreads);
int runServe(const ServeArgs& args);

}  // namespace deltagi::cli
