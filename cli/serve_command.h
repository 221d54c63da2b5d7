// `deltagi serve SCENE.json [--port 8080] [--host 127.0.0.1]`: a live session in the browser (README, "Live
// session"). A web server (civetweb) serves the page of web/, embedded at build time, and streams the
// frames to it as JPEGs over a WebSocket; the page's messages change the scene (src/live/live_session.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace deltagi::cli {

struct ServeArgs {
    std::filesystem::path scene;
    std::vector<std::string> overrides;
    std::string host = "127.0.0.1";
    int port = 8080;  // 0: any free port (printed)
    int threads = 0;
    int jpegQuality = 85;
    int interactiveScale = 2;  // the frames while something changes at 1 / this of the width and height
};

CLI::App* addServeCommand(CLI::App& app, ServeArgs& args, int maxThreads);
int runServe(const ServeArgs& args);

}  // namespace deltagi::cli
