// A tracked camera sequence for tests: a transforms.json with its photos in a temporary folder, and running
// the command line on it (sequence_test.cpp, keyframes_test.cpp, video_test.cpp).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "deltagi/image.h"
#include "test_files.h"
#include "test_paths.h"

namespace deltagi::test {

namespace fs = std::filesystem;
using nlohmann::json;

class SequenceTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ =
            fs::temp_directory_path() / ("deltagi_sequence_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "images");
    }
    void TearDown() override {
        std::error_code ignored;
        fs::remove_all(dir_, ignored);
    }

    // A transforms.json of `count` frames of a camera moving along x at height 0.8, looking down -z at the
    // tiny scene, with grey photos of w x h; OPENCV distortion globally.
    json transforms(int count, int w = 32, int h = 24) const {
        json frames = json::array();
        for (int i = 0; i < count; ++i) {
            const std::string name = "images/frame_" + std::to_string(i) + ".png";
            writeImage(Image(w, h, 3, 0.2f + 0.1f * i), dir_ / name);
            const double x = 0.1 * i;
            frames.push_back(
                {{"file_path", name},
                 {"transform_matrix", {{1, 0, 0, x}, {0, 1, 0, 0.8}, {0, 0, 1, 2}, {0, 0, 0, 1}}}});
        }
        return {{"camera_model", "OPENCV"},
                {"fl_x", 30.0},
                {"fl_y", 30.0},
                {"cx", w / 2.0},
                {"cy", h / 2.0},
                {"w", w},
                {"h", h},
                {"k1", -0.1},
                {"k2", 0.01},
                {"p1", 0.0},
                {"p2", 0.0},
                {"aabb_scale", 16},
                {"frames", frames}};
    }
    fs::path write(const json& document, const std::string& name = "transforms.json") const {
        writeText(dir_ / name, document.dump(1));
        return dir_ / name;
    }

    // `scene` (the camera taken out) over the frames of transforms.json, as scene.json.
    fs::path writeSequenceScene(json scene) const {
        scene.erase("camera");
        scene["sequence"] = {{"transforms", "transforms.json"}};
        return write(scene, "scene.json");
    }

    // `deltagi ARGS` (the paths in ARGS as given), its stderr in err.txt; returns the exit status.
    int runCli(const std::string& args, const std::string& environment = "") const {
        const std::string command =
            environment + " " + std::string(test::kCli) + " " + args + " 2>" + (dir_ / "err.txt").string();
        const int status = std::system(command.c_str());
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    std::string errors() const { return readText(dir_ / "err.txt"); }

    fs::path dir_;
};

}  // namespace deltagi::test
