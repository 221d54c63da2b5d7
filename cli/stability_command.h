// `deltagi stability`: flicker without a reference, over frames in which the objects and the camera move
// (src/evaluation/temporal.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "evaluation/temporal.h"

namespace deltagi::cli {

struct StabilityArgs {
    std::filesystem::path scene;
    std::filesystem::path json;  // empty: no JSON file
    std::vector<std::string> overrides;
    MotionOptions motion;
    std::vector<float> direction;
    int threads = 0;  // 0: all cores
    // Set by addStabilityCommand: the synthetic motion's options (not with a sequence), and --frames.
    std::vector<const CLI::Option*> motionOptions;
    const CLI::Option* framesOption = nullptr;
};

CLI::App* addStabilityCommand(CLI::App& app, StabilityArgs& args, int maxThreads);

// The figures on stdout; throws InputError on bad input.
int runStability(StabilityArgs args);

}  // namespace deltagi::cli
