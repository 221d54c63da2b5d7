// `deltagi marker`: a printable AprilTag tag36h11 marker for the scene file's "markers" — a PDF whose black
// square prints at its true size, or a PNG.
#pragma once

#include <filesystem>

#include <CLI/CLI.hpp>

namespace deltagi::cli {

struct MarkerArgs {
    int id = 0;
    double size = 0.12;  // the black square's side, metres (the scene's "size" in its units)
    int margin = 1;      // cells of white around the tag's own white ring
    int pixelsPerCell = 32;
    std::filesystem::path output;
    bool quiet = false;
};

CLI::App* addMarkerCommand(CLI::App& app, MarkerArgs& args);
int runMarker(const MarkerArgs& args);

}  // namespace deltagi::cli
