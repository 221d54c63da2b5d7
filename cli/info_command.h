// `deltagi info`: a scene's size, volume region and effective options, as a table or JSON on stdout; or, with
// --options-markdown, the options tables of docs/scene-format.md.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace deltagi::cli {

struct InfoArgs {
    std::filesystem::path scene;
    std::vector<std::string> overrides;
    bool json = false;
    // --options-markdown: "" for the tables alone, or a markdown file to print with its tables made anew.
    std::optional<std::string> optionsMarkdown;
};

CLI::App* addInfoCommand(CLI::App& app, InfoArgs& args);

// Loads the scene (warnings on stderr) and prints, or prints the options' markdown; throws InputError on
// bad input.
int runInfo(const InfoArgs& args);

}  // namespace deltagi::cli
