// `deltagi encode`: frames already written (frame_####.png, .exr) into an H.264 MP4 — the last step of a
// sequence rendered in chunks, e.g. by a cluster's array job (examples/slurm/).
#pragma once

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

#include "video_output.h"

namespace deltagi::cli {

struct EncodeArgs {
    std::filesystem::path frames;  // a pattern: frame_####.png or frame_%04d.png
    std::filesystem::path video;
    std::string range;  // "A:B"; empty: every frame found, which must be consecutive
    VideoSettings settings;
    bool quiet = false;
};

// Adds the subcommand and its options to `app`, storing them in `args`.
CLI::App* addEncodeCommand(CLI::App& app, EncodeArgs& args);

// Runs it. Throws InputError on bad input: a frame missing from the range, frames of different sizes, an
// unreadable image, an output that is one of the frames.
int runEncode(const EncodeArgs& args);

}  // namespace deltagi::cli
