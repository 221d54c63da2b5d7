// FrameCache keeps each part of a frame's work while what it is made from is unchanged: a change of one input
// empties exactly the parts that depend on it.
#include "pipeline/frame_cache.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "deltagi/shapes.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

using test::diffuse;
using test::placed;

// Each part's version: a new one each time the part is emptied.
std::vector<std::pair<std::string, uint64_t>> versions(const FrameCache& c) {
    return {{"world", c.world.version},
            {"voxels", c.voxels.version},
            {"light", c.light.version},
            {"view", c.view.version},
            {"litView", c.litView.version},
            {"relitShadows", c.relitShadows.version},
            {"objectRays", c.objectRays.version},
            {"objectVolumes", c.objectVolumes.version},
            {"environment", c.environment.version}};
}

// The parts that update(scene) empties, after a first update with the scene as it was.
class FrameCacheTest : public testing::Test {
  protected:
    FrameCacheTest() {
        scene_ = test::floorScene();
        scene_.virtuals.push_back(
            placed(makeSphere(0.2f, 12), {0.1f, 0.3f, 0.0f}, diffuse(glm::vec3(0.6f)), "ball"));
        cache_.update(scene_);
    }
    std::set<std::string> emptied() {
        const auto before = versions(cache_);
        cache_.update(scene_);
        const auto after = versions(cache_);
        std::set<std::string> names;
        for (size_t i = 0; i < before.size(); ++i)
            if (before[i].second != after[i].second) names.insert(before[i].first);
        return names;
    }
    Scene scene_;
    FrameCache cache_;
};

using Parts = std::set<std::string>;

TEST_F(FrameCacheTest, TheSameSceneKeepsEverything) {
    EXPECT_EQ(emptied(), Parts{});
    EXPECT_TRUE(cache_.kept().world);
    EXPECT_TRUE(cache_.kept().camera);
    EXPECT_FALSE(cache_.newRealScene());
}

TEST_F(FrameCacheTest, AMovedObjectInAFixedRegionKeepsEverything) {
    scene_.options.volume.center = glm::vec3(0.0f, 0.5f, 0.0f);
    scene_.options.volume.size = 2.2f;
    cache_.update(scene_);
    for (glm::vec3& p : scene_.virtuals[0].positions) p.x += 0.05f;
    // The objects' own parts are brought up to date where they changed by their own code.
    EXPECT_EQ(emptied(), Parts{});
}

// The objects' volumes are kept: they start from the new light themselves (RealSceneVolumes::lightVersion).
TEST_F(FrameCacheTest, AnotherLightEmptiesTheLightAndWhatIsLitByIt) {
    scene_.lights[0].position.x += 0.1f;
    EXPECT_EQ(emptied(), (Parts{"light", "litView", "relitShadows"}));
    EXPECT_TRUE(cache_.kept().world);
    EXPECT_TRUE(cache_.kept().camera);
    EXPECT_TRUE(cache_.newRealScene());
    scene_.lights.push_back(test::pointLight({0.5f, 1.0f, 0.0f}, 1.0f));
    EXPECT_EQ(emptied(), (Parts{"light", "litView", "relitShadows"}));
}

TEST_F(FrameCacheTest, AnotherEnvironmentEmptiesTheLightAndTheSampler) {
    Environment environment;
    environment.radiance = Image(8, 4, 3, 1.0f);
    scene_.environment = environment;
    EXPECT_EQ(emptied(), (Parts{"light", "litView", "relitShadows", "environment"}));
    // Rotated.
    scene_.environment->worldFromEnvironment = glm::mat3(0, 0, 1, 0, 1, 0, -1, 0, 0);
    EXPECT_EQ(emptied(), (Parts{"light", "litView", "relitShadows", "environment"}));
}

TEST_F(FrameCacheTest, AnotherCameraEmptiesTheView) {
    scene_.camera = test::lookAtCamera({0.3f, 1.6f, 1.6f}, {0, 0, 0}, 64, 48, 60.0f);
    EXPECT_EQ(emptied(), (Parts{"view", "litView", "relitShadows"}));
    EXPECT_TRUE(cache_.kept().world);
    EXPECT_FALSE(cache_.kept().camera);
    EXPECT_FALSE(cache_.newRealScene());
}

TEST_F(FrameCacheTest, ARegionThatFollowsTheObjectsEmptiesTheVoxelsAndWhatIsMadeOverThem) {
    for (glm::vec3& p : scene_.virtuals[0].positions) p.x += 0.05f;  // the region follows the ball
    EXPECT_EQ(emptied(), (Parts{"voxels", "light", "relitShadows", "objectVolumes"}));
    EXPECT_FALSE(cache_.kept().world);
    EXPECT_TRUE(cache_.kept().camera);
    EXPECT_FALSE(cache_.newRealScene());
}

TEST_F(FrameCacheTest, TheRealScenesGeometryMaterialsOrOptionsEmptyAllButTheEnvironment) {
    const Parts all{"world",   "voxels",       "light",      "view",
                    "litView", "relitShadows", "objectRays", "objectVolumes"};
    scene_.real[0].material.albedo = glm::vec3(0.2f);
    EXPECT_EQ(emptied(), all);
    EXPECT_TRUE(cache_.newRealScene());
    scene_.real[0].positions[0].y += 0.01f;
    EXPECT_EQ(emptied(), all);
    scene_.options.trace.stepScale = 0.4f;
    EXPECT_EQ(emptied(), all);
    scene_.options.trace.stepScale = 0.4f;  // the same again
    EXPECT_EQ(emptied(), Parts{});
    scene_.background = Image(64, 48, 3, 0.5f);  // a photo instead of the rendered real scene
    EXPECT_EQ(emptied(), all);
}

TEST_F(FrameCacheTest, AnotherSceneObjectIsNotMistakenForTheOldOne) {
    // The kept BVH and surfaces point into the scene's meshes: a copy of the scene elsewhere is another one.
    const Scene copy = scene_;
    const auto before = versions(cache_);
    cache_.update(copy);
    EXPECT_NE(versions(cache_)[0].second, before[0].second);
}

TEST_F(FrameCacheTest, ClearEmptiesEverything) {
    cache_.clear();
    cache_.update(scene_);
    EXPECT_FALSE(cache_.kept().world);
    EXPECT_FALSE(cache_.kept().camera);
    EXPECT_TRUE(cache_.newRealScene());
}

}  // namespace
}  // namespace deltagi
