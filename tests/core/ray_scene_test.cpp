// RayScene: closest hits over one layer or a layer over a base, and refitting a layer whose meshes moved.
#include <gtest/gtest.h>

#include "core/ray_scene.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

// Hits of a fan of rays from above, for comparing two scenes.
std::vector<RayHit> raysFromAbove(const RayScene& rays) {
    std::vector<RayHit> hits;
    for (int i = -8; i <= 8; ++i)
        for (int j = -8; j <= 8; ++j)
            hits.push_back(rays.intersect({0.05f * i, 2.0f, 0.05f * j}, {0.0f, -1.0f, 0.0f}));
    return hits;
}

TEST(RayScene, RefitLayerAnswersAsAFreshBuild) {
    Scene s = test::floorScene();
    s.virtuals.push_back(
        test::placed(makeSphere(0.3f, 16), {0.0f, 0.5f, 0.0f}, test::diffuse(glm::vec3(0.5f))));
    const RayScene real(s, SceneContent::RealOnly);
    RayScene objects(s, SceneContent::VirtualOnly, &real);
    for (glm::vec3& p : s.virtuals[0].positions) p = glm::vec3(1.3f * p.x + 0.1f, p.y, p.z - 0.05f);
    ASSERT_TRUE(objects.refit(s));
    const RayScene fresh(s, SceneContent::VirtualOnly, &real);
    // The hit attributes are computed from the triangle (the same bits whichever BVH finds it); a refit BVH
    // may find the other of two triangles that a ray meets on their shared edge, at the same point to
    // rounding.
    const std::vector<RayHit> a = raysFromAbove(objects), b = raysFromAbove(fresh);
    size_t onObject = 0, same = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].isVirtual, b[i].isVirtual);
        ASSERT_NEAR(a[i].t, b[i].t, 1e-6f);
        ASSERT_LT(glm::length(a[i].position - b[i].position), 1e-6f);
        ASSERT_LT(glm::length(a[i].normal - b[i].normal), 1e-5f);
        onObject += a[i].isVirtual;
        same += a[i].t == b[i].t && a[i].position == b[i].position && a[i].normal == b[i].normal;
    }
    EXPECT_GT(onObject, 100u);
    EXPECT_GT(same, a.size() * 95 / 100);
    EXPECT_EQ(objects.bounds().max.x, fresh.bounds().max.x);

    // Other triangles (or another count of meshes, vertices or triangles) cannot be refit.
    Scene other = s;
    std::swap(other.virtuals[0].triangles[0], other.virtuals[0].triangles[1]);
    EXPECT_FALSE(objects.refit(other));
    other = s;
    other.virtuals[0].positions.push_back(glm::vec3(0.0f));
    other.virtuals[0].normals.push_back(glm::vec3(0.0f, 1.0f, 0.0f));
    EXPECT_FALSE(objects.refit(other));
    other = s;
    other.virtuals.push_back(other.virtuals[0]);
    EXPECT_FALSE(objects.refit(other));
    EXPECT_TRUE(objects.refit(s));
}

// Camera rays in packets ask the same as one at a time: blocked within their tMax; a ray with tMax <= 0 is
// not traced. The sphere above the floor blocks some of the rays towards the floor, and rays stopped short
// of it are not blocked.
TEST(RayScene, OccludedCoherentAnswersAsOneRayAtATime) {
    Scene s = test::floorScene();
    s.real.push_back(test::placed(makeSphere(0.3f, 16), {0.0f, 0.5f, 0.0f}, test::diffuse(glm::vec3(0.5f))));
    const RayScene rays(s, SceneContent::RealOnly);
    const glm::vec3 eye(0.1f, 2.0f, 0.2f);
    std::vector<glm::vec3> directions;
    std::vector<float> tMax;
    for (int i = -10; i <= 10; ++i)
        for (int j = -10; j <= 10; ++j) {
            directions.push_back(glm::normalize(glm::vec3(0.04f * i, -1.0f, 0.04f * j)));
            const int kind = (i + j + 20) % 3;  // to the floor, short of the sphere's top, or not traced
            tMax.push_back(kind == 0 ? 1.9f : kind == 1 ? 1.1f : 0.0f);
        }
    std::vector<uint8_t> blocked(directions.size(), 7);
    rays.occludedCoherent(eye, directions, tMax, blocked);
    size_t count = 0;
    for (size_t i = 0; i < directions.size(); ++i) {
        const bool expected = tMax[i] > 0.0f && rays.occludedTopLayer(eye, directions[i], 0.0f, tMax[i]);
        ASSERT_EQ(blocked[i], expected ? 1 : 0) << i;
        count += expected;
    }
    EXPECT_GT(count, 20u);
    EXPECT_LT(count, directions.size() / 3);
}

}  // namespace
}  // namespace deltagi
