// Tracked camera sequences: lens distortion, the transforms.json reader (nerfstudio / instant-ngp) and
// `deltagi render` over a sequence, at once and in chunks.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "deltagi/scene_io.h"
#include "test_errors.h"
#include "test_files.h"
#include "test_paths.h"
#include "test_scene_json.h"
#include "test_sequence.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::expectContains;
using test::inputErrorOf;

// distort() and undistort() invert each other over the image of a wide lens, for both models.
TEST(LensDistortion, UndistortInvertsDistort) {
    LensDistortion opencv{LensDistortion::Model::OpenCV, -0.28f, 0.09f, -0.01f, 0.0f, 0.001f, -0.0005f};
    LensDistortion fisheye{LensDistortion::Model::Fisheye, 0.05f, -0.01f, 0.002f, -0.0003f, 0.0f, 0.0f};
    for (const LensDistortion& d : {opencv, fisheye})
        for (float x = -0.8f; x <= 0.81f; x += 0.2f)
            for (float y = -0.6f; y <= 0.61f; y += 0.2f) {
                const glm::vec2 u(x, y);
                const glm::vec2 back = d.undistort(d.distort(u));
                EXPECT_NEAR(back.x, x, 1e-5f);
                EXPECT_NEAR(back.y, y, 1e-5f);
            }
    // Barrel distortion pulls a corner in.
    EXPECT_LT(glm::length(opencv.distort({0.6f, 0.45f})), glm::length(glm::vec2(0.6f, 0.45f)));
}

// A camera ray through a pixel of the distorted photo meets the world point that the calibration's forward
// model (pinhole projection, then distortion) images at that pixel: rendered layers line up with the photo.
TEST(LensDistortion, CameraRaysGoThroughTheDistortion) {
    Camera camera;
    camera.width = 640, camera.height = 480, camera.fx = 500, camera.fy = 505, camera.cx = 322,
    camera.cy = 238;
    camera.distortion = {LensDistortion::Model::OpenCV, -0.3f, 0.1f, 0.0f, 0.0f, 0.002f, 0.001f};
    for (const glm::vec3 p :
         {glm::vec3(0.4f, 0.2f, -2.0f), glm::vec3(-0.9f, -0.6f, -1.5f), glm::vec3(0, 0, -3)}) {
        // OpenCV's frame: x right, y down, z forward.
        const glm::vec2 normalized(p.x / -p.z, -p.y / -p.z);
        const glm::vec2 d = camera.distortion.distort(normalized);
        const float px = camera.cx + camera.fx * d.x, py = camera.cy + camera.fy * d.y;
        const glm::vec3 ray = glm::normalize(camera.rayDirection(px, py));
        EXPECT_NEAR(glm::dot(ray, glm::normalize(p)), 1.0f, 1e-6f) << p.x << ", " << p.y;
    }
}

// A single camera takes its distortion from the scene file too.
TEST(LensDistortion, TheSceneFilesCameraReadsIt) {
    json doc = test::tinySceneJson(32, 24, {0.5, 0.5, 0.5});
    doc["camera"]["distortion"] = {{"model", "opencv"}, {"k1", -0.2}, {"p2", 0.001}};
    const Scene scene = loadScene(doc, "scene.json");
    EXPECT_EQ(scene.camera.distortion.model, LensDistortion::Model::OpenCV);
    EXPECT_FLOAT_EQ(scene.camera.distortion.k1, -0.2f);
    EXPECT_FLOAT_EQ(scene.camera.distortion.p2, 0.001f);
    doc["camera"]["distortion"] = {{"model", "division"}};
    expectContains(inputErrorOf([&] { loadScene(doc, "scene.json"); }),
                   {"scene.json: camera.distortion.model", "division"});
    doc["camera"]["distortion"] = {{"model", "fisheye"}, {"p1", 0.1}};
    expectContains(inputErrorOf([&] { loadScene(doc, "scene.json"); }), {"camera.distortion", "p1"});
}

using test::SequenceTest;

TEST_F(SequenceTest, ReadsCamerasPhotosAndDistortion) {
    const fs::path file = write(transforms(3));
    const std::vector<SequenceFrame> all = readTransforms(file, {});
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[2].index, 2);
    EXPECT_FLOAT_EQ(all[2].camera.position().x, 0.2f);
    EXPECT_FLOAT_EQ(all[2].camera.position().y, 0.8f);
    EXPECT_EQ(all[1].camera.width, 32);
    EXPECT_FLOAT_EQ(all[1].camera.fx, 30.0f);
    EXPECT_EQ(all[1].camera.distortion.model, LensDistortion::Model::OpenCV);
    EXPECT_FLOAT_EQ(all[1].camera.distortion.k1, -0.1f);
    EXPECT_EQ(all[0].photo, dir_ / "images/frame_0.png");
    const std::vector<SequenceFrame> chunk = readTransforms(file, parseFrameRange("1:3", "--frames"));
    ASSERT_EQ(chunk.size(), 2u);
    EXPECT_EQ(chunk[0].index, 1);
    // A file_path without its extension finds the photo (instant-ngp writes them so).
    json doc = transforms(1);
    doc["frames"][0]["file_path"] = "images/frame_0";
    EXPECT_EQ(readTransforms(write(doc), {})[0].photo, dir_ / "images/frame_0.png");
}

TEST_F(SequenceTest, BadTransformsNameTheFileAndTheFrame) {
    auto errorOf = [&](const json& doc, FrameRange range = {}) {
        return inputErrorOf([&] { readTransforms(write(doc), range); });
    };
    json doc = transforms(2);
    doc["frames"][1]["camera_model"] = "EQUIRECTANGULAR";
    expectContains(errorOf(doc), {"transforms.json", "frames[1].camera_model", "EQUIRECTANGULAR"});
    doc = transforms(2);
    doc["frames"][1]["transform_matrix"] = {{1, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    expectContains(errorOf(doc), {"frames[1].transform_matrix", "singular"});
    // A pose with a scale (or a mirror) is no camera pose: refused when the file is read, not at its frame.
    doc = transforms(2);
    doc["frames"][1]["transform_matrix"] = {{2, 0, 0, 0}, {0, 2, 0, 0}, {0, 0, 2, 0}, {0, 0, 0, 1}};
    expectContains(errorOf(doc), {"transforms.json: frames[1].transform_matrix", "orthonormal"});
    doc["frames"][1]["transform_matrix"] = {{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    expectContains(errorOf(doc), {"frames[1].transform_matrix", "reflection"});
    doc["frames"][1]["transform_matrix"] = {{1, 0, 0, 1e39}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    expectContains(errorOf(doc), {"frames[1].transform_matrix", "finite"});
    doc = transforms(2);
    doc["frames"] = json::array();
    expectContains(errorOf(doc), {"transforms.json: frames", "no frames"});
    doc = transforms(2);
    doc["frames"][1].erase("file_path");
    expectContains(errorOf(doc), {"frames[1]", "file_path", "1 of the 2 frames have a photo"});
    doc = transforms(2);
    doc["frames"][0]["file_path"] = "images/missing.png";
    expectContains(errorOf(doc), {"frames[0].file_path", "photo not found"});
    doc = transforms(2);
    doc.erase("w");
    expectContains(errorOf(doc), {"frames[0]", "\"w\""});
    expectContains(errorOf(transforms(2), {3, 5}),
                   {"transforms.json: frames", "outside the file's 2 frames"});
    expectContains(errorOf(json{{"fl_x", 3}}), {"transforms.json", "frames"});
    test::writeText(dir_ / "nan.json", R"({"frames": [{"transform_matrix": [[NaN]]}]})");
    expectContains(inputErrorOf([&] { readTransforms(dir_ / "nan.json", {}); }), {"nan.json"});
    expectContains(inputErrorOf([] { parseFrameRange("3:1", "--frames"); }), {"--frames", "empty"});
    expectContains(inputErrorOf([] { parseFrameRange("a:b", "--frames"); }), {"--frames", "A:B"});
    // A photo of another size than the camera's: found from its header when the file is read ...
    doc = transforms(3);
    write(doc);
    writeImage(Image(8, 8, 3), dir_ / "images/frame_2.png");
    expectContains(inputErrorOf([&] { readTransforms(dir_ / "transforms.json", {}); }),
                   {"transforms.json: frames[2].file_path", "32x24", "8x8"});
    EXPECT_EQ(readTransforms(dir_ / "transforms.json", {0, 2}).size(), 2u);  // not in the range: not read
    // ... and when it is read for its frame (it may have changed since).
    doc = transforms(2);
    const std::vector<SequenceFrame> frames = readTransforms(write(doc), {});
    writeImage(Image(8, 8, 3), dir_ / "images/frame_1.png");
    expectContains(inputErrorOf([&] { readFramePhoto(frames[1], dir_ / "transforms.json"); }),
                   {"frames[1].file_path", "32x24", "8x8"});
}

// deltagi render over a sequence writes one file per frame; 0:3 at once and 1:3 alone give the same frames.
// The volumes light the side of the real surfaces that the transforms file's first camera sees, whatever
// frames are rendered: the camera moves without the real scene's volumes being redone, and chunks agree.
TEST_F(SequenceTest, TheFirstCameraIsTheVolumesViewpoint) {
    write(transforms(3));
    json scene = test::tinySceneJson(32, 24, {0.8, 0.2, 0.1});
    scene.erase("camera");
    scene["sequence"] = {{"transforms", "transforms.json"}, {"frames", "1:3"}};
    Scene loaded = loadScene(scene, dir_ / "scene.json");
    ASSERT_TRUE(loaded.options.volume.viewpoint.has_value());
    EXPECT_EQ(*loaded.options.volume.viewpoint, glm::vec3(0.0f, 0.8f, 2.0f));
    EXPECT_FLOAT_EQ(loaded.camera.position().x, 0.1f);          // the range's first frame
    scene["options"]["volume"]["viewpoint"] = {0.5, 1.0, 1.5};  // given: kept
    loaded = loadScene(scene, dir_ / "scene.json");
    EXPECT_EQ(*loaded.options.volume.viewpoint, glm::vec3(0.5f, 1.0f, 1.5f));
    scene["options"]["volume"]["viewpoint"] = {0.5, "up", 1.5};
    expectContains(inputErrorOf([&] { loadScene(scene, dir_ / "scene.json"); }),
                   {"options.volume.viewpoint"});
}

TEST_F(SequenceTest, RenderingInChunksGivesTheSameFrames) {
    write(transforms(3));
    json scene = test::tinySceneJson(32, 24, {0.8, 0.2, 0.1});
    scene.erase("camera");
    scene["sequence"] = {{"transforms", "transforms.json"}};
    const fs::path sceneFile = write(scene, "scene.json");
    auto run = [&](const std::string& args) {
        const std::string command = std::string(test::kCli) + " render " + sceneFile.string() + " " + args +
                                    " -q 2>" + (dir_ / "err.txt").string();
        const int status = std::system(command.c_str());
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    };
    ASSERT_EQ(run("-o " + (dir_ / "all_####.png").string()), 0) << test::readText(dir_ / "err.txt");
    ASSERT_EQ(run("-o " + (dir_ / "part_%04d.exr").string() + " --frames 1:3 --layers " +
                  (dir_ / "layers_##.exr").string()),
              0)
        << test::readText(dir_ / "err.txt");
    for (int i : {0, 1, 2}) EXPECT_TRUE(fs::exists(dir_ / ("all_000" + std::to_string(i) + ".png")));
    EXPECT_FALSE(fs::exists(dir_ / "part_0000.exr"));
    ASSERT_EQ(run("-o " + (dir_ / "all_####.exr").string()), 0);
    for (int i : {1, 2}) {
        const Image a = readImage(dir_ / ("all_000" + std::to_string(i) + ".exr"));
        const Image b = readImage(dir_ / ("part_000" + std::to_string(i) + ".exr"));
        ASSERT_EQ(a.data().size(), b.data().size());
        for (size_t k = 0; k < a.data().size(); ++k) ASSERT_NEAR(a.data()[k], b.data()[k], 1e-4f) << i;
        EXPECT_TRUE(fs::exists(dir_ / ("layers_0" + std::to_string(i) + ".exr")));
    }
    // Each frame has its photo: the background differs from frame to frame.
    const Image first = readImage(dir_ / "all_0000.exr"), second = readImage(dir_ / "all_0001.exr");
    EXPECT_NE(first.at(0, 0, 0), second.at(0, 0, 0));
    // An output pattern that names a frame's photo is refused before anything is written.
    EXPECT_EQ(run("-o " + (dir_ / "images/frame_#.png").string()), 1);
    EXPECT_NE(test::readText(dir_ / "err.txt").find("is an input of this run"), std::string::npos);
    // ... with a range of frames too.
    EXPECT_EQ(run("-o " + (dir_ / "images/frame_#.png").string() + " --frames 1:3"), 1);
    EXPECT_NE(test::readText(dir_ / "err.txt").find("frame_1.png"), std::string::npos);
    // Without a frame number in the output's name: one clear error.
    EXPECT_EQ(run("-o " + (dir_ / "one.png").string()), 1);
    EXPECT_NE(test::readText(dir_ / "err.txt").find("frame_####.png"), std::string::npos);
}

// A transforms file whose frames have no file_path is a camera path: each frame renders the real scene from
// its camera, as a scene without a photo does.
TEST_F(SequenceTest, FramesWithoutPhotosRenderTheRealScene) {
    json doc = transforms(2);
    for (json& frame : doc["frames"]) frame.erase("file_path");
    write(doc);
    const fs::path sceneFile = writeSequenceScene(test::tinySceneJson(32, 24, {0.8, 0.2, 0.1}));
    Scene scene = loadScene(sceneFile);
    ASSERT_EQ(scene.sequence.size(), 2u);
    EXPECT_TRUE(scene.sequence[1].photo.empty());
    EXPECT_FALSE(scene.background.has_value());
    showFrame(scene, scene.sequence[1]);
    EXPECT_FALSE(scene.background.has_value());
    EXPECT_FLOAT_EQ(scene.camera.position().x, 0.1f);
    ASSERT_EQ(runCli("render " + sceneFile.string() + " -q -o " + (dir_ / "frame_#.exr").string()), 0)
        << test::readText(dir_ / "err.txt");
    // The frames differ where the camera moved, and neither is a photo: the real scene is rendered.
    const Image first = readImage(dir_ / "frame_0.exr"), second = readImage(dir_ / "frame_1.exr");
    ASSERT_EQ(first.data().size(), second.data().size());
    EXPECT_FALSE(std::equal(first.data().begin(), first.data().end(), second.data().begin()));
    // A frame without a photo among frames with one is a mistake, named.
    doc["frames"][0]["file_path"] = "images/frame_0.png";
    write(doc);
    expectContains(inputErrorOf([&] { loadScene(sceneFile); }),
                   {"transforms.json: frames[1]", "no \"file_path\"", "1 of the 2 frames"});
}

// A chunk (--frames A:B) reads and checks the photos of its own frames and of those rendered before it for
// temporal reuse only: a photo missing elsewhere does not stop it. --aov writes a folder per frame.
TEST_F(SequenceTest, AChunkNeedsOnlyItsOwnPhotosAndWritesAnAovFolderPerFrame) {
    write(transforms(5));
    const fs::path scene = writeSequenceScene(test::tinySceneJson(32, 24, {0.8, 0.2, 0.1}));
    fs::remove(dir_ / "images/frame_0.png");
    fs::remove(dir_ / "images/frame_4.png");
    const std::string common = "render " + scene.string() + " -q -o " + (dir_ / "out_####.png").string() +
                               " --set options.render.temporal_frames=2";
    EXPECT_EQ(runCli(common), 1);
    expectContains(errors(), {"frames[0].file_path", "photo not found"});
    // Frame 1 needs frame 0 before it, and says why.
    EXPECT_EQ(runCli(common + " --frames 1:3"), 1);
    expectContains(errors(), {"frames[0].file_path", "photo not found", "temporal_frames 2"});
    ASSERT_EQ(runCli(common + " --frames 2:4 --aov " + (dir_ / "aov_####").string()), 0) << errors();
    for (int i : {2, 3}) {
        const fs::path folder = dir_ / ("aov_000" + std::to_string(i));
        for (const char* name : {"background.exr", "composite.exr", "object_mask.exr", "delta.exr"})
            EXPECT_TRUE(fs::exists(folder / name)) << folder / name;
        const json timings = json::parse(test::readText(folder / "timings.json"));
        EXPECT_GT(timings["total_ms"].get<double>(), 0.0);
        EXPECT_EQ(timings["width"], 32);
        // Each folder holds its own frame: the photos differ.
        EXPECT_NEAR(readImage(folder / "background.exr").at(0, 0, 0), 0.2f + 0.1f * i, 0.01f);
    }
    EXPECT_FALSE(fs::exists(dir_ / "aov_0001"));  // rendered first, not written
    EXPECT_FALSE(fs::exists(dir_ / "aov_0004"));
    // Without a frame number's place, one clear line; --frames without a sequence too.
    EXPECT_EQ(runCli(common + " --frames 2:4 --aov " + (dir_ / "aov").string()), 1);
    expectContains(errors(), {"aov", "folder per frame", "aov_####"});
    EXPECT_EQ(runCli("render " + write(test::tinySceneJson(32, 24, {0.8, 0.2, 0.1}), "still.json").string() +
                     " -q -o " + (dir_ / "still.png").string() + " --frames 1:3"),
              1);
    expectContains(errors(), {"--frames", "no \"sequence\""});
    EXPECT_EQ(runCli(common + " --frames 3:1"), 1);
    expectContains(errors(), {"--frames", "empty"});
}

// `info` says what a sequence holds: its frames, file, rate, lens and the camera's path.
TEST_F(SequenceTest, InfoDescribesTheSequence) {
    write(transforms(3));
    const fs::path scene = writeSequenceScene(test::tinySceneJson(32, 24, {0.8, 0.2, 0.1}));
    ASSERT_EQ(runCli("info " + scene.string() + " --json --set sequence.frames=1:3 >" +
                     (dir_ / "info.json").string()),
              0)
        << errors();
    const json info = json::parse(test::readText(dir_ / "info.json"));
    const json& sequence = info["sequence"];
    EXPECT_EQ(sequence["frames"], 2);
    EXPECT_EQ(sequence["range"], "1:3");
    EXPECT_EQ(sequence["fps"], 30.0);
    EXPECT_NEAR(sequence["camera_path"].get<double>(), 0.1, 1e-6);
    EXPECT_NE(sequence["transforms"].get<std::string>().find("transforms.json"), std::string::npos);
    ASSERT_EQ(sequence["lens"].size(), 1u);
    expectContains(sequence["lens"][0].get<std::string>(), {"opencv", "k1 -0.1", "k2 0.01"});
    EXPECT_EQ(sequence["keyframed_objects"], 0);
    ASSERT_EQ(runCli("info " + scene.string() + " >" + (dir_ / "info.txt").string()), 0) << errors();
    expectContains(test::readText(dir_ / "info.txt"), {"3 frames 0:3", "30 fps", "the first frame's"});
    const fs::path still = write(test::tinySceneJson(32, 24, {0.8, 0.2, 0.1}), "still.json");
    ASSERT_EQ(runCli("info " + still.string() + " --json >" + (dir_ / "still.json.out").string()), 0);
    EXPECT_TRUE(json::parse(test::readText(dir_ / "still.json.out"))["sequence"].is_null());
}

}  // namespace
}  // namespace deltagi
