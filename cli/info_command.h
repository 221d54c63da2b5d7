// `deltagi info`: a scene's size, volume region and effective options, as a table or JSON on stdout.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace deltagi::cli {

struct InfoArgs {
    std::filesystem::path scene;
    std::vector<std::string> overrides;
    bool json = false;
};

CLI::App* addInfoCommand(CLI::App& app, InfoArgs& args);

// Loads the scene (warnings on stderr) and prints; throws InputError on bad input.
int runInfo(const InfoArgs& args);

}  // namespace deltagi::cli
