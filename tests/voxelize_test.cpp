#include "voxelize.h"

#include <cstring>
#include <numeric>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "test_scenes.h"

namespace deltagi {
namespace {

TEST(TriangleBoxOverlap, ClosedFormCases) {
    const glm::vec3 c(0.0f), h(0.5f);
    // Inside.
    EXPECT_TRUE(triangleBoxOverlap(c, h, {-0.1f, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}));
    // Far away along x.
    EXPECT_FALSE(triangleBoxOverlap(c, h, {2, 0, 0}, {3, 0, 0}, {2, 1, 0}));
    // A large triangle through the centre covers the box although no vertex is inside.
    EXPECT_TRUE(triangleBoxOverlap(c, h, {-10, -10, 0}, {10, -10, 0}, {0, 10, 0}));
    // Its plane misses the box.
    EXPECT_FALSE(triangleBoxOverlap(c, h, {-10, -10, 0.6f}, {10, -10, 0.6f}, {0, 10, 0.6f}));
    // Bounding boxes overlap and the plane crosses the box, but the axis across the edge x + y = 1.1 separates
    // (the box corner has x + y = 1); with x + y = 0.9 the corner is inside.
    EXPECT_FALSE(triangleBoxOverlap(c, h, {1.1f, 0, 0}, {0, 1.1f, 0}, {1.1f, 1.1f, 0}));
    EXPECT_TRUE(triangleBoxOverlap(c, h, {0.9f, 0, 0}, {0, 0.9f, 0}, {0.9f, 0.9f, 0}));
    // Touching a face counts as overlap (closed box).
    EXPECT_TRUE(triangleBoxOverlap(c, h, {0.5f, -1, -1}, {0.5f, 1, -1}, {0.5f, 0, 1}));
}

TEST(ClippedTriangleArea, InsideAndCovering) {
    // Fully inside: the triangle's own area.
    EXPECT_NEAR(clippedTriangleArea({0.1f, 0.1f, 0.5f}, {0.9f, 0.1f, 0.5f}, {0.1f, 0.9f, 0.5f}, glm::vec3(0),
                                    glm::vec3(1)),
                0.5f * 0.8f * 0.8f, 1e-6f);
    // A huge triangle in the plane z = 0.5 covers the unit square cross-section exactly.
    EXPECT_NEAR(clippedTriangleArea({-10, -10, 0.5f}, {30, -10, 0.5f}, {-10, 30, 0.5f}, glm::vec3(0), glm::vec3(1)),
                1.0f, 1e-5f);
    // A diagonal plane x = y through the unit cube: the cut is a sqrt(2) x 1 rectangle.
    EXPECT_NEAR(clippedTriangleArea({-5, -5, -5}, {5, 5, -5}, {0, 0, 20}, glm::vec3(0), glm::vec3(1)),
                std::sqrt(2.0f), 1e-5f);
    // Outside.
    EXPECT_EQ(clippedTriangleArea({2, 2, 2}, {3, 2, 2}, {2, 3, 2}, glm::vec3(0), glm::vec3(1)), 0.0f);
}

VolumeRegion unitRegion(int n) { return {glm::vec3(-1.0f), 2.0f, n}; }

TEST(Voxelize, HorizontalQuadFillsOneLayerWithItsNormalAndArea) {
    const int n = 16;
    std::vector<TriangleMesh> meshes = {
        test::placed(makeQuad({1.0f, 1.0f}), {0.0f, 0.0625f, 0.0f}, test::diffuse(glm::vec3(1)))};
    // Voxels are 0.125 wide; y = 0.0625 is the middle of layer 8.
    VoxelGeometry g = voxelize(meshes, unitRegion(n));
    float totalArea = 0.0f;
    int filled = 0;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const glm::vec4 v = g.visibility.at(x, y, z);
                totalArea += g.area[g.visibility.index(x, y, z)];
                if (v.x == 0.0f) continue;
                ++filled;
                EXPECT_EQ(y, 8);
                // Voxels the quad's border only touches hold no area and so no normal.
                if (g.area[g.visibility.index(x, y, z)] > 0.0f) EXPECT_NEAR(v.z, 1.0f, 1e-5f) << "normal must be +y";
            }
    // The quad spans [-0.5, 0.5]: 8 x 8 voxels, plus the touched neighbours on its border lines.
    EXPECT_GE(filled, 64);
    EXPECT_LE(filled, 100);
    EXPECT_NEAR(totalArea, 1.0f, 1e-4f);
}

TEST(Voxelize, SphereKeepsItsSurfaceAreaAndNormalsPointOut) {
    std::vector<TriangleMesh> meshes = {
        test::placed(makeSphere(0.6f, 48), glm::vec3(0.0f), test::diffuse(glm::vec3(1)))};
    double meshArea = 0.0;
    for (const glm::uvec3& t : meshes[0].triangles) {
        const auto& p = meshes[0].positions;
        meshArea += 0.5 * glm::length(glm::cross(p[t.y] - p[t.x], p[t.z] - p[t.x]));
    }
    VoxelGeometry g = voxelize(meshes, unitRegion(32));
    double voxelArea = std::accumulate(g.area.begin(), g.area.end(), 0.0);
    EXPECT_NEAR(voxelArea, meshArea, 1e-3 * meshArea);
    // Mean normals point away from the centre.
    const glm::vec4 right = g.visibility.at(31 - 6, 16, 16);  // x ~ +0.6
    ASSERT_EQ(right.x, 1.0f);
    EXPECT_GT(right.y, 0.7f);
}

TEST(Voxelize, SameResultForAnyThreadCount) {
    std::vector<TriangleMesh> meshes = {
        test::placed(makeTorus(0.5f, 0.2f, 64), glm::vec3(0.05f), test::diffuse(glm::vec3(1)))};
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        return voxelize(meshes, unitRegion(32));
    };
    VoxelGeometry a = run(1), b = run(2);
    for (size_t i = 0; i < a.area.size(); ++i) {
        ASSERT_EQ(a.area[i], b.area[i]);
        ASSERT_EQ(a.visibility[i], b.visibility[i]);
    }
}

TEST(Voxelize, GeometryOutsideTheRegionIsIgnored) {
    std::vector<TriangleMesh> meshes = {
        test::placed(makeBox(glm::vec3(0.5f)), {5.0f, 0.0f, 0.0f}, test::diffuse(glm::vec3(1)))};
    VoxelGeometry g = voxelize(meshes, unitRegion(8));
    EXPECT_EQ(std::accumulate(g.area.begin(), g.area.end(), 0.0f), 0.0f);
}

// Voxelizing again in place (as frames do) gives voxelize()'s bits, whatever the meshes did: moved, partly
// and wholly out of the region, emissive and not, more and fewer.
TEST(Voxelize, RevoxelizingChangedMeshesEqualsVoxelizingThemAfresh) {
    const VolumeRegion region = unitRegion(32);
    std::vector<TriangleMesh> meshes = {
        test::placed(makeSphere(0.3f, 24), {0.1f, 0.0f, -0.2f}, test::diffuse(glm::vec3(0.5f)))};
    VoxelGeometry kept = voxelize(meshes, region);
    auto expectSame = [&](const char* step) {
        const VoxelBox old = kept.bounds;
        const VoxelBox returned = revoxelize(kept, meshes, region);
        EXPECT_EQ(returned.lo, old.lo) << step;
        EXPECT_EQ(returned.hi, old.hi) << step;
        const VoxelGeometry fresh = voxelize(meshes, region);
        EXPECT_EQ(kept.bounds.lo, fresh.bounds.lo) << step;
        EXPECT_EQ(kept.bounds.hi, fresh.bounds.hi) << step;
        ASSERT_EQ(kept.emission.size(), fresh.emission.size()) << step;
        for (size_t i = 0; i < fresh.area.size(); ++i) {
            ASSERT_EQ(std::memcmp(&kept.visibility[i], &fresh.visibility[i], sizeof(glm::vec4)), 0) << step;
            ASSERT_EQ(kept.area[i], fresh.area[i]) << step;
            if (!fresh.emission.empty()) ASSERT_EQ(kept.emission[i], fresh.emission[i]) << step;
        }
        // Nothing outside the bounds.
        for (int z = 0; z < 32; ++z)
            for (int y = 0; y < 32; ++y)
                for (int x = 0; x < 32; ++x) {
                    const glm::ivec3 v(x, y, z);
                    if (glm::all(glm::greaterThanEqual(v, fresh.bounds.lo)) &&
                        glm::all(glm::lessThan(v, fresh.bounds.hi)))
                        continue;
                    ASSERT_EQ(fresh.area[fresh.visibility.index(x, y, z)], 0.0f) << step;
                }
    };
    auto move = [&](glm::vec3 offset) {
        for (TriangleMesh& m : meshes)
            for (glm::vec3& p : m.positions) p += offset;
    };
    move({0.05f, 0.02f, 0.0f});
    expectSame("moved a little");
    move({0.6f, 0.0f, 0.0f});
    expectSame("partly out");
    move({2.0f, 0.0f, 0.0f});
    expectSame("all out");
    EXPECT_TRUE(kept.bounds.empty());
    move({-2.9f, 0.1f, 0.3f});
    meshes[0].material.emission = glm::vec3(1.0f, 2.0f, 3.0f);
    expectSame("back and emissive");
    meshes.push_back(
        test::placed(makeBox(glm::vec3(0.2f)), {-0.5f, 0.5f, 0.5f}, test::diffuse(glm::vec3(1))));
    expectSame("one more");
    meshes.erase(meshes.begin());
    expectSame("one fewer, not emissive");
}

}  // namespace
}  // namespace deltagi
