// `deltagi eval --suite FILE_OR_FOLDER`: the quality suite (src/evaluation/quality_suite.h).
#pragma once

#include <filesystem>

#include <CLI/CLI.hpp>

#include "evaluation/quality_suite.h"

namespace deltagi::cli {

struct SuiteArgs {
    std::filesystem::path suite;                                // empty: a plain `eval` of one scene
    std::filesystem::path markdown = "out/quality/quality.md";  // the table as Markdown
    std::filesystem::path cache = "out/quality/refs";           // the cached references
    double checkpointMinutes = kDefaultCheckpointMinutes;       // between a reference's checkpoints
};

// Adds --suite, --markdown, --cache and --checkpoint-minutes to the `eval` subcommand.
void addSuiteOptions(CLI::App& eval, SuiteArgs& args);

// Runs the suite with the `eval` subcommand's other flags (--json, --set, --spp, --seed, --threads, -q;
// a scene, --aov, --reference and --time-limit are refused). Throws InputError on bad input.
int runSuite(const CLI::App& eval, const SuiteArgs& args);

}  // namespace deltagi::cli
