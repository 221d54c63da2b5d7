// The `deltagi` command interrupted: a signal while it works, or just before its outputs are renamed into
// place, leaves the previous outputs whole and no temporary behind; an interrupted quality suite goes on from
// its last checkpoint.
#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "deltagi/image.h"
#include "test_cli.h"
#include "test_files.h"

namespace fs = std::filesystem;
using deltagi::test::CliResult;
using deltagi::test::CliTest;
using deltagi::test::procStatus;
using deltagi::test::quote;
using deltagi::test::readText;
using deltagi::test::startCli;
using deltagi::test::tinyScene;
using deltagi::test::waitFor;
using deltagi::test::writeText;
using nlohmann::json;

namespace {

// A signal when an output is complete but not yet renamed into place (DELTAGI_TEST_SIGNAL_BEFORE_RENAME):
// exit 128 + signal, the previous file still whole, no temporary left, nor a folder the run created.
TEST_F(CliTest, SignalBeforeRenameLeavesThePreviousOutput) {
    const fs::path scene = writeScene(tinyScene());
    const fs::path output = dir_ / "out.png";
    deltagi::writeImage(deltagi::Image(4, 4, 3, 0.1f), output);
    const std::string previous = readText(output);
    fs::create_directories(dir_ / "aov");
    writeText(dir_ / "aov" / "timings.json", "{\"previous\": true}\n");
    const auto signalling = [](int signal) {
        return "DELTAGI_TEST_SIGNAL_BEFORE_RENAME=" + std::to_string(signal) + " ";
    };
    for (int signal : {SIGTERM, SIGINT}) {
        CliResult result =
            run(renderArgs(scene) + " --aov " + quote((dir_ / "aov").string()), signalling(signal));
        EXPECT_EQ(result.exitCode, 128 + signal) << result.err;
        EXPECT_NE(result.err.find("interrupted"), std::string::npos) << result.err;
        // The outputs are renamed into place together, after all are written: none is replaced.
        EXPECT_EQ(readText(output), previous);
        EXPECT_EQ(readText(dir_ / "aov" / "timings.json"), "{\"previous\": true}\n");
        EXPECT_FALSE(fs::exists(dir_ / "aov" / "composite.exr"));
        EXPECT_TRUE(temporaries().empty());
        // Into folders that do not exist yet: they go again.
        const fs::path fresh = dir_ / "fresh";
        result = run("render " + quote(scene.string()) + " -o " + quote((fresh / "out.png").string()) +
                         " --aov " + quote((fresh / "aov").string()),
                     signalling(signal));
        EXPECT_EQ(result.exitCode, 128 + signal) << result.err;
        EXPECT_FALSE(fs::exists(fresh));
    }
    // bench's JSON alike.
    const fs::path figures = dir_ / "bench.json";
    writeText(figures, "{\"previous\": true}\n");
    const CliResult bench =
        run("bench " + quote(scene.string()) + " --frames 1 --warmup 0 -q --json " + quote(figures.string()),
            signalling(SIGTERM));
    EXPECT_EQ(bench.exitCode, 128 + SIGTERM) << bench.err;
    EXPECT_EQ(readText(figures), "{\"previous\": true}\n");
    EXPECT_TRUE(temporaries().empty());
    // SIGKILL cannot be caught: its temporary stays behind, but the output is still the previous one.
    const CliResult killed = run(renderArgs(scene), signalling(SIGKILL));
    EXPECT_TRUE(killed.exitCode == -1 || killed.exitCode == 128 + SIGKILL) << killed.exitCode;
    EXPECT_EQ(readText(output), previous);
}

// SIGTERM or SIGINT while `reference` path-traces (once it catches the signal and its worker threads run):
// exit 143 or 130, the previous output untouched, no temporary, no AOV folder.
TEST_F(CliTest, InterruptedReferenceWritesNothing) {
    const fs::path scene = writeScene(tinyScene());
    const fs::path output = dir_ / "ref.exr", aov = dir_ / "aov";
    writeText(output, "the previous output\n");
    for (int signal : {SIGTERM, SIGINT}) {
        const pid_t pid = startCli({"reference", scene.string(), "-o", output.string(), "--aov", aov.string(),
                                    "--spp", "1000000", "--threads", "2"},
                                   dir_);
        ASSERT_GT(pid, 0);
        EXPECT_TRUE(waitFor([&] {
            const std::string caught = procStatus(pid, "SigCgt");
            return !caught.empty() && (std::stoull(caught, nullptr, 16) >> (SIGTERM - 1) & 1) != 0;
        }));
        EXPECT_TRUE(waitFor([&] {
            const std::string threads = procStatus(pid, "Threads");
            return threads.empty() || std::stoi(threads) >= 2;
        }));
        kill(pid, signal);
        int status = 0;
        waitpid(pid, &status, 0);
        ASSERT_TRUE(WIFEXITED(status)) << "status " << status;
        EXPECT_EQ(WEXITSTATUS(status), 128 + signal) << readText(dir_ / "stderr.txt");
        EXPECT_NE(readText(dir_ / "stderr.txt").find("interrupted"), std::string::npos);
        EXPECT_EQ(readText(output), "the previous output\n");
        EXPECT_FALSE(fs::exists(aov));
        EXPECT_TRUE(temporaries().empty());
    }
}

// A suite stopped by SIGTERM while it path-traces leaves its last checkpoint in the cache (a reference of the
// samples done, with its sums); the next run goes on from it and removes it.
TEST_F(CliTest, AnInterruptedSuiteGoesOnFromItsCheckpoint) {
    writeScene(tinyScene(), "tiny.json");
    writeText(dir_ / "suite.json", R"({"fit_spp": [1], "scenes": [{"scene": "tiny.json", "spp": 1000000}]})");
    const fs::path refs = dir_ / "refs";
    const std::vector<std::string> args = {"eval",
                                           "--suite",
                                           (dir_ / "suite.json").string(),
                                           "--cache",
                                           refs.string(),
                                           "--checkpoint-minutes",
                                           "0.002",
                                           "--json",
                                           (dir_ / "q.json").string(),
                                           "--markdown",
                                           (dir_ / "q.md").string()};
    // The complete checkpoint folders (full-NNNspp-seed0 marked "checkpoint"): (samples, folder), the most
    // samples last.
    const auto checkpoints = [&] {
        std::vector<std::pair<int, fs::path>> found;
        std::error_code error;
        for (auto it = fs::recursive_directory_iterator(refs, error); !error && it != fs::end(it);
             it.increment(error)) {
            if (it->path().filename() != "reference.json") continue;
            try {
                const json meta = json::parse(readText(it->path()));
                if (meta.value("checkpoint", false))
                    found.emplace_back(meta.at("spp").get<int>(), it->path().parent_path());
            } catch (const std::exception&) {
            }
        }
        std::sort(found.begin(), found.end());
        return found;
    };
    const pid_t pid = startCli(args, dir_);
    ASSERT_GT(pid, 0);
    const bool made = waitFor([&] { return !checkpoints().empty(); });
    kill(pid, SIGTERM);
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(made) << readText(dir_ / "stderr.txt");
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
    const auto kept = checkpoints();
    ASSERT_FALSE(kept.empty());
    const auto [done, newest] = kept.back();
    EXPECT_TRUE(fs::is_regular_file(newest / "sums.bin"));
    EXPECT_EQ(newest.filename(), "full-" + std::to_string(done) + "spp-seed0");
    ASSERT_GT(done, 1);

    // Two samples more than it has: the next run renders only those.
    std::vector<std::string> more = args;
    more.insert(more.end(), {"--spp", std::to_string(done + 2)});
    const pid_t again = startCli(more, dir_);
    ASSERT_GT(again, 0);
    waitpid(again, &status, 0);
    const std::string err = readText(dir_ / "stderr.txt");
    ASSERT_TRUE(WIFEXITED(status));
    ASSERT_EQ(WEXITSTATUS(status), 0) << err;
    EXPECT_NE(err.find("went on from the samples of " + newest.string()), std::string::npos) << err;
    EXPECT_TRUE(checkpoints().empty());
}

}  // namespace
