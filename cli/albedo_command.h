// `deltagi estimate-albedo`: the real scene's diffuse albedo from its photo
// (include/deltagi/albedo_estimation.h), written into a copy of the scene file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "deltagi/albedo_estimation.h"

namespace deltagi::cli {

struct AlbedoArgs {
    std::filesystem::path scene;
    std::filesystem::path output;  // the scene file to write (.json)
    std::string per = "mesh";      // "mesh" or "vertex"
    std::vector<std::string> overrides;
    AlbedoOptions options;
    int threads = 0;  // 0: all cores
    bool quiet = false;
};

CLI::App* addAlbedoCommand(CLI::App& app, AlbedoArgs& args, int maxThreads);

// The table on stdout, warnings on stderr; throws InputError on bad input.
int runAlbedo(const AlbedoArgs& args);

}  // namespace deltagi::cli
