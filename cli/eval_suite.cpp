#include "eval_suite.h"

#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <fmt/core.h>
#include <tbb/global_control.h>

#include "deltagi/error.h"
#include "evaluation/quality_suite.h"
#include "validators.h"

namespace deltagi::cli {

namespace fs = std::filesystem;

namespace {

void note(const std::string& line) {
    fmt::print(stderr, "{}\n", line);
    std::fflush(stderr);
}

void createParent(const fs::path& file) {
    if (file.parent_path().empty()) return;
    std::error_code error;
    fs::create_directories(file.parent_path(), error);
    if (error) throw InputError(file.parent_path().string(), "cannot create folder: " + error.message());
}

void writeFile(const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out) throw InputError(path.string(), "cannot write file");
}

// Single-quotes an argument for the shell when it needs it, so that the table's command can be pasted.
std::string shellWord(const std::string& word) {
    if (!word.empty() && word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                "0123456789_-./=,:+") == std::string::npos)
        return word;
    std::string quoted = "'";
    for (const char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

}  // namespace

void addSuiteOptions(CLI::App& eval, SuiteArgs& args) {
    eval.add_option("--suite", args.suite,
                    "Evaluate every scene of a suite (a suite file or a folder of scenes) against cached "
                    "references and write one table (see docs/ground-truth.md)")
        ->excludes("scene")
        ->excludes("--aov")
        ->excludes("--reference")
        ->excludes("--time-limit")
        ->excludes("--max-bounces");
    eval.add_option("--markdown", args.markdown,
                    "With --suite: the table as Markdown (default out/quality/quality.md)");
    eval.add_option("--cache", args.cache,
                    "With --suite: the folder of the cached references (default out/quality/refs)");
    eval.add_option("--checkpoint-minutes", args.checkpointMinutes,
                    fmt::format("With --suite: minutes of rendering between a reference's checkpoints, which "
                                "an interrupted suite goes on from (default {:g}; 0: none)",
                                kDefaultCheckpointMinutes))
        ->check(finiteNumber(0.0, false, "a number of minutes >= 0"))
        ->needs("--suite");
}

int runSuite(const CLI::App& eval, const SuiteArgs& args) {
    const QualitySuite suite = loadSuite(args.suite);
    const bool quiet = eval.count("--quiet") > 0;
    const int threads = eval.count("--threads") > 0 ? eval.get_option("--threads")->as<int>() : 0;
    std::optional<tbb::global_control> threadLimit;
    if (threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, threads);

    SuiteRunOptions options;
    options.cacheFolder = args.cache;
    options.checkpointMinutes = args.checkpointMinutes;
    if (eval.count("--set") > 0) options.overrides = eval.get_option("--set")->as<std::vector<std::string>>();
    if (eval.count("--spp") > 0) options.samplesPerPixel = eval.get_option("--spp")->as<int>();
    if (eval.count("--seed") > 0) options.seed = eval.get_option("--seed")->as<uint64_t>();
    if (!quiet) options.log = note;
    const fs::path json = eval.count("--json") > 0 ? fs::path(eval.get_option("--json")->as<std::string>())
                                                   : fs::path("out/quality/quality.json");
    if (json.extension() != ".json") throw InputError(json.string(), "expected a .json file for the table");
    createParent(json);
    createParent(args.markdown);

    // How the table was made, to be pasted again.
    std::string command = "deltagi eval --suite " + shellWord(args.suite.string());
    if (eval.count("--cache") > 0) command += " --cache " + shellWord(args.cache.string());
    for (const std::string& set : options.overrides) command += " --set " + shellWord(set);
    if (options.samplesPerPixel) command += fmt::format(" --spp {}", *options.samplesPerPixel);
    if (options.seed) command += fmt::format(" --seed {}", *options.seed);
    command += " --json " + shellWord(json.string()) + " --markdown " + shellWord(args.markdown.string());

    std::vector<SceneQuality> results;
    // Written after every scene and every frame of a sequence, so that an interrupted suite keeps what it
    // measured.
    options.onScene = [&](const SceneQuality& q) {
        results.push_back(q);
        for (const std::string& warning : q.warnings) note("deltagi: warning: " + warning);
        writeFile(json, suiteToJson(results, command).dump(2) + "\n");
        writeFile(args.markdown, suiteMarkdown(results, command));
    };
    for (const SuiteScene& entry : suite.scenes) {
        if (!quiet) note(fmt::format("deltagi: {} ({})", entry.name, entry.file.string()));
        evaluateSuiteEntry(suite, entry, options);
    }
    if (!quiet)
        note(fmt::format("deltagi: wrote {} and {} ({} scenes; references cached in {})", json.string(),
                         args.markdown.string(), results.size(), args.cache.string()));
    return 0;
}

}  // namespace deltagi::cli
