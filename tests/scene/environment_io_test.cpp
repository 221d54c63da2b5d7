// The scene file's "environment" key and options.environment: good files load (every projection, the rotation
// and intensity, warnings for LDR images and repaired pixels), bad ones raise an InputError naming the file
// and the key.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include <gtest/gtest.h>

#include "core/environment.h"
#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "io/image_codecs.h"
#include "test_errors.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class EnvironmentIoTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("deltagi_environment_io_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        Image map(32, 16, 3, 0.5f);
        map.setRgb(20, 4, glm::vec3(400.0f));  // a sun
        writeImage(map, dir_ / "sky.hdr");
        writeImage(Image(16, 16, 3, 0.5f), dir_ / "square.hdr");
        writeImage(Image(32, 16, 3, 0.5f), dir_ / "sky.png");
    }
    void TearDown() override { fs::remove_all(dir_); }

    // A small scene lit by `environment` only.
    Scene load(const json& environment, const json& options = json::object()) {
        json doc = json::parse(R"({
            "camera": {"width": 32, "height": 24, "fov_y_deg": 60, "position": [0, 1, 3], "look_at": [0, 0, 0]},
            "scene": [{"shape": {"type": "quad", "size": [4, 4]}}],
            "virtual": [{"shape": {"type": "box", "size": [0.5, 0.5, 0.5]}, "transform": {"translate": [0, 0.25, 0]}}]
        })");
        doc["environment"] = environment;
        doc["options"] = options;
        const fs::path file = dir_ / "scene.json";
        std::ofstream(file) << doc.dump(2);
        return loadScene(file);
    }
    std::string errorOf(const json& environment, const json& options = json::object()) {
        try {
            load(environment, options);
        } catch (const InputError& e) {
            return e.what();
        }
        ADD_FAILURE() << "expected an InputError";
        return {};
    }

    fs::path dir_;
};

using test::expectContains;

TEST_F(EnvironmentIoTest, AnEquirectangularMapLoadsItsLightsRotatedAndScaled) {
    const Scene plain = load({{"file", "sky.hdr"}});
    ASSERT_TRUE(plain.environment);
    EXPECT_TRUE(plain.warnings.empty());
    EXPECT_EQ(plain.lights.size(), 16u);
    for (const Light& l : plain.lights) EXPECT_TRUE(l.fromEnvironment && l.type == Light::Type::Directional);
    // The sky is prefiltered for the cones only: with the map traced by rays (the default) it is not needed.
    EXPECT_TRUE(plain.environment->sky.empty());
    const Scene byCones = load({{"file", "sky.hdr"}}, {{"shadow", {{"method", "cones"}}}});
    EXPECT_FALSE(byCones.environment->sky.empty());

    const Scene turned =
        load({{"file", "sky.hdr"}, {"rotate_deg", {0, 90, 0}}, {"intensity", 2}},
             {{"environment", {{"light_count", 4}, {"sky", false}}}, {"shadow", {{"method", "cones"}}}});
    EXPECT_EQ(turned.lights.size(), 4u);
    EXPECT_TRUE(turned.environment->sky.empty());
    EXPECT_FLOAT_EQ(turned.environment->radiance.rgb(0, 0).x, 1.0f);
    // A map direction turned 90 degrees about +y: -z (the map's centre) appears at -x in the world.
    const glm::vec3 centre = turned.environment->worldFromEnvironment * glm::vec3(0, 0, -1);
    EXPECT_NEAR(glm::distance(centre, glm::vec3(-1, 0, 0)), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::distance(environmentRadiance(*turned.environment, centre),
                              environmentRadiance(*plain.environment, glm::vec3(0, 0, -1)) * 2.0f),
                0.0f, 1e-4f);
}

TEST_F(EnvironmentIoTest, FisheyeAndMirrorBallImagesAreConvertedToEquirectangular) {
    const Scene fisheye =
        load({{"file", "square.hdr"},
              {"projection", "fisheye"},
              {"fisheye", {{"model", "equisolid"}, {"center", {8, 8}}, {"radius", 8}, {"fov_deg", 180}}}});
    EXPECT_EQ(fisheye.environment->radiance.width(), 2 * fisheye.environment->radiance.height());
    EXPECT_GT(environmentRadiance(*fisheye.environment, {0, 1, 0}).x, 0.4f);   // the zenith is seen
    EXPECT_EQ(environmentRadiance(*fisheye.environment, {0, -1, 0}).x, 0.0f);  // the nadir is not
    const Scene ball = load({{"file", "square.hdr"}, {"projection", "mirror_ball"}});
    EXPECT_GT(environmentRadiance(*ball.environment, {0, -1, 0}).x, 0.4f);  // a ball sees all around
}

TEST_F(EnvironmentIoTest, LdrImagesAndBadPixelsLoadWithAWarning) {
    const Scene ldr = load({{"file", "sky.png"}});
    ASSERT_EQ(ldr.warnings.size(), 1u);
    expectContains(ldr.warnings[0], {"scene.json: environment.file", "sky.png", "low-dynamic-range"});

    // An EXR encoded here: writeImage never writes NaN. Rows of 8 pixels, 4 rows.
    std::vector<float> pixels(8 * 4 * 3, 0.25f);
    pixels[0] = NAN;
    pixels[4] = INFINITY;
    pixels[8] = -3.0f;
    const std::string names[] = {"R", "G", "B"};
    std::ofstream(dir_ / "bad.exr", std::ios::binary) << encodeExr(pixels, 8, 4, names);
    const Scene bad = load({{"file", "bad.exr"}});
    ASSERT_EQ(bad.warnings.size(), 1u);
    expectContains(bad.warnings[0], {"environment.file", "3 of 32 pixels", "NaN, infinite or negative"});
    for (float v : bad.environment->radiance.data()) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
    for (const Light& l : bad.lights) ASSERT_TRUE(std::isfinite(l.color.x) && l.color.x >= 0.0f);
    Scene small = bad;
    small.options.volume.resolution = 16;
    small.options.rsm.resolution = 32;
    const RenderOutput rendered = render(small);
    for (float v : rendered.composite.data()) ASSERT_TRUE(std::isfinite(v));
}

TEST_F(EnvironmentIoTest, BadEnvironmentKeysNameTheFileAndTheKey) {
    expectContains(errorOf({{"file", "sky.hdr"}, {"rotation", 1}}),
                   {"scene.json: environment.rotation", "unknown"});
    expectContains(errorOf({{"file", "missing.hdr"}}),
                   {"scene.json: environment.file", "file not found", "missing.hdr"});
    expectContains(errorOf({{"projection", "fisheye"}}), {"scene.json: environment.file", "missing"});
    expectContains(errorOf({{"file", "sky.hdr"}, {"intensity", "bright"}}),
                   {"environment.intensity", "a number"});
    expectContains(errorOf({{"file", "sky.hdr"}, {"intensity", -1}}), {"environment.intensity"});
    expectContains(errorOf({{"file", "sky.hdr"}, {"projection", "cube"}}),
                   {"environment.projection", "\"cube\""});
    expectContains(errorOf({{"file", "square.hdr"}}), {"environment.file", "twice as wide as high", "16x16"});
    expectContains(errorOf({{"file", "sky.hdr"}, {"fisheye", {{"radius", 3}}}}),
                   {"environment.fisheye", "only allowed with \"projection\": \"fisheye\""});
    expectContains(
        errorOf({{"file", "square.hdr"}, {"projection", "fisheye"}, {"fisheye", {{"model", "stereo"}}}}),
        {"environment.fisheye.model", "equidistant"});
    expectContains(
        errorOf({{"file", "square.hdr"}, {"projection", "fisheye"}, {"fisheye", {{"center", {1, 2, 3}}}}}),
        {"environment.fisheye.center", "[x, y]"});
    expectContains(
        errorOf({{"file", "square.hdr"}, {"projection", "mirror_ball"}, {"mirror_ball", {{"radius", 0}}}}),
        {"environment.mirror_ball.radius"});
    expectContains(errorOf({{"file", "sky.hdr"}, {"rotate_deg", {0, 1}}}), {"environment.rotate_deg"});
    expectContains(errorOf("sky.hdr"), {"scene.json: environment", "expected an object"});
    const json file = {{"file", "sky.hdr"}};
    expectContains(errorOf(file, {{"environment", {{"light_count", 1000}}}}),
                   {"options.environment.light_count"});
    expectContains(errorOf(file, {{"environment", {{"extraction", "k-means"}}}}),
                   {"options.environment.extraction", "median_cut"});
    expectContains(errorOf(file, {{"environment", {{"sky", 1}}}}), {"options.environment.sky"});
    expectContains(errorOf(file, {{"environment", {{"glow", 1}}}}), {"options.environment.glow"});
}

}  // namespace
}  // namespace deltagi
