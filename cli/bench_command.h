// `deltagi bench`: per-stage timings over moving-object frames (src/evaluation/benchmark.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "evaluation/benchmark.h"

namespace deltagi::cli {

struct BenchArgs {
    std::filesystem::path scene;
    std::filesystem::path json;  // empty: no JSON file
    std::vector<std::string> overrides;
    BenchOptions options;
    int threads = 0;  // 0: all cores
    bool quiet = false;
    const CLI::Option* motionOption = nullptr;  // --motion, set by addBenchCommand (not with a sequence)
};

// Adds the subcommand and its options to `app`, storing them in `args`.
CLI::App* addBenchCommand(CLI::App& app, BenchArgs& args, int maxThreads);

// Runs it: the table on stdout, progress on stderr (unless quiet). Throws InputError on bad input.
int runBench(const BenchArgs& args);

}  // namespace deltagi::cli
