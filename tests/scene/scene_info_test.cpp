// Scene checks of `deltagi info`: lights placed inside or on a surface are reported.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "deltagi/scene_io.h"
#include "scene/scene_info.h"
#include "test_paths.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

// A 1 x 1 ceiling at y = 1, facing down, and a lamp of radius 0.06 under it at `lampY`.
Scene ceilingScene(float lampY, float radius) {
    Scene s;
    TriangleMesh ceiling = makeQuad({1.0f, 1.0f});
    s.real.push_back(test::placed(ceiling, {0, 1, 0}, test::diffuse(glm::vec3(0.7f)), "ceiling"));
    Light lamp = test::pointLight({0.0f, lampY, 0.0f}, 1.0f);
    lamp.type = Light::Type::Spot;
    lamp.radius = radius;
    s.lights.push_back(lamp);
    return s;
}

TEST(LightPlacementTest, ALampHalfInTheCeilingIsReported) {
    // The examples' old lamp: centre 1 mm below the ceiling, radius 0.06.
    const std::vector<std::string> warnings = lightPlacementWarnings(ceilingScene(0.999f, 0.06f));
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("lights[0]"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("real 'ceiling'"), std::string::npos) << warnings[0];
}

TEST(LightPlacementTest, ALampWhollyBelowTheCeilingIsNotReported) {
    EXPECT_TRUE(lightPlacementWarnings(ceilingScene(0.939f, 0.06f)).empty());
}

TEST(LightPlacementTest, APointLightOnASurfaceIsReportedAndOneOffItIsNot) {
    EXPECT_EQ(lightPlacementWarnings(ceilingScene(1.0f, 0.0f)).size(), 1u);
    EXPECT_TRUE(lightPlacementWarnings(ceilingScene(0.99f, 0.0f)).empty());
}

TEST(LightPlacementTest, BeyondTheEdgeOfASurfaceTheDistanceIsToTheEdge) {
    // Level with the ceiling but 0.05 beyond its edge (x = 0.5): within the radius of the edge.
    Scene s = ceilingScene(1.0f, 0.06f);
    s.lights[0].position = {0.55f, 1.0f, 0.0f};
    EXPECT_EQ(lightPlacementWarnings(s).size(), 1u);
    s.lights[0].position = {0.57f, 1.0f, 0.0f};
    EXPECT_TRUE(lightPlacementWarnings(s).empty());
}

TEST(LightPlacementTest, AVirtualObjectAroundTheLightIsReported) {
    Scene s = ceilingScene(0.5f, 0.06f);
    s.virtuals.push_back(
        test::placed(makeSphere(0.1f, 32), {0.0f, 0.45f, 0.0f}, test::diffuse(glm::vec3(0.5f)), "ball"));
    const std::vector<std::string> warnings = lightPlacementWarnings(s);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("virtual 'ball'"), std::string::npos) << warnings[0];
}

TEST(LightPlacementTest, DirectionalLightsAreNotChecked) {
    Scene s = ceilingScene(1.0f, 0.0f);
    s.lights[0].type = Light::Type::Directional;
    EXPECT_TRUE(lightPlacementWarnings(s).empty());
}

// The loader adds the warnings to the scene's, which `render` and `info` print.
TEST(LightPlacementTest, TheCornellExampleLoadsWithoutWarningAndWarnsWithTheOldLamp) {
    const std::filesystem::path file = std::filesystem::path(test::kSourceDir) / "examples/cornell-box.json";
    EXPECT_TRUE(loadScene(file).warnings.empty());
    const Scene old = loadScene(file, {"lights.0.position=[0.278, 0.5478, 0.2795]"});
    ASSERT_EQ(old.warnings.size(), 1u);
    EXPECT_NE(old.warnings[0].find("real 'ceiling'"), std::string::npos) << old.warnings[0];
}

}  // namespace
}  // namespace deltagi
