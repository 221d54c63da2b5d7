// The `deltagi` command run from the tests (tests/cli/): CliTest's temporary folder and runs of the command,
// and a started command watched and signalled while it works.
#pragma once

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_files.h"
#include "test_paths.h"
#include "test_scene_json.h"

namespace deltagi::test {

namespace fs = std::filesystem;
using nlohmann::json;

struct CliResult {
    int exitCode = -1;
    std::string out;  // stdout
    std::string err;  // stderr
};

// Single-quotes an argument for /bin/sh.
inline std::string quote(const std::string& arg) {
    std::string quoted = "'";
    for (char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

inline size_t lineCount(const std::string& text) {
    return static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
}

// The tiny test scene at 64x48 with a blue box.
inline nlohmann::json tinyScene() {
    return deltagi::test::tinySceneJson(64, 48, {0.1, 0.2, 0.8});
}

class CliTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("deltagi_cli_test_" + std::string(test->name()) + "_" + std::to_string(getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ignored;
        fs::remove_all(dir_, ignored);
    }

    // Runs `deltagi ARGS` (already quoted as needed), capturing stdout and stderr; `environment` is put
    // before the command ("NAME=VALUE ").
    CliResult run(const std::string& args, const std::string& environment = "") const {
        const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
        const std::string command = environment + quote(test::kCli) + " " + args + " >" +
                                    quote(out.string()) + " 2>" + quote(err.string());
        const int status = std::system(command.c_str());
        CliResult result;
        result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        result.out = readText(out);
        result.err = readText(err);
        return result;
    }

    // The temporary output files left anywhere under the test's folder.
    std::vector<fs::path> temporaries() const {
        std::vector<fs::path> found;
        for (const auto& entry : fs::recursive_directory_iterator(dir_))
            if (entry.path().filename().string().find(".tmp-") != std::string::npos) found.push_back(entry);
        return found;
    }

    fs::path writeScene(const json& scene, const std::string& name = "scene.json") const {
        const fs::path path = dir_ / name;
        writeText(path, scene.dump(2));
        return path;
    }

    std::string renderArgs(const fs::path& scene) const {
        return "render " + quote(scene.string()) + " -o " + quote((dir_ / "out.png").string());
    }

    // `deltagi info` on a shipped example: it loads and covers the box with the region it asks for.
    void expectExampleLoads(const std::string& name) const {
        const fs::path scene = fs::path(test::kSourceDir) / "examples" / (name + ".json");
        const CliResult result = run("info --json " + quote(scene.string()));
        ASSERT_EQ(result.exitCode, 0) << name << ": " << result.err;
        const json info = json::parse(result.out);
        EXPECT_EQ(info.at("real").at("meshes"), 7) << name;
        EXPECT_EQ(info.at("lights"), 1) << name;
        EXPECT_EQ(info.at("volume").at("resolution"), 128) << name;
        EXPECT_NEAR(info.at("volume").at("size").get<double>(), 0.6, 1e-6) << name;
    }

    fs::path dir_;
};

// The contract of every input error: a non-zero exit, and one line on stderr that names what was wrong.
inline void expectOneErrorLine(const CliResult& result, std::initializer_list<std::string> mustName) {
    EXPECT_NE(result.exitCode, 0);
    EXPECT_EQ(lineCount(result.err), 1u) << result.err;
    EXPECT_EQ(result.err.rfind("deltagi: error:", 0), 0u) << result.err;
    for (const std::string& name : mustName)
        EXPECT_NE(result.err.find(name), std::string::npos) << result.err;
}

// Starts `deltagi ARGS` with stdout and stderr into files in `dir`; returns its pid.
inline pid_t startCli(const std::vector<std::string>& args, const fs::path& dir) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, (dir / "stdout.txt").c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, (dir / "stderr.txt").c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<std::string> all{test::kCli};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& arg : all) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_t pid = -1;
    if (posix_spawn(&pid, test::kCli, &actions, nullptr, argv.data(), environ) != 0) pid = -1;
    posix_spawn_file_actions_destroy(&actions);
    return pid;
}

// A field of /proc/PID/status ("SigCgt", "Threads"); empty once the process is gone.
inline std::string procStatus(pid_t pid, const std::string& field) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/status");
    for (std::string line; std::getline(in, line);)
        if (line.rfind(field + ":", 0) == 0) return line.substr(field.size() + 1);
    return {};
}

// Polls `done` for up to 10 s.
template <typename Done>
bool waitFor(Done done) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!done()) {
        if (std::chrono::steady_clock::now() > end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
}

}  // namespace deltagi::test
