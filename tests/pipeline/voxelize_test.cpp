#include "pipeline/voxelize.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <numeric>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "deltagi/shapes.h"
#include "deltagi/transforms.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

// The brute-force reference that voxelize()'s cutting of triangles by the grid planes is checked against:
// for each voxel of a triangle's bounds, an exact overlap test (separating axes, Akenine-Möller 2001) and
// the area of the triangle clipped to the voxel (Sutherland-Hodgman).

// Exact overlap test of a triangle with the axis-aligned box centre +- halfSize (closed box).
bool triangleBoxOverlap(glm::vec3 boxCenter, glm::vec3 h, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const glm::vec3 v[3] = {a - boxCenter, b - boxCenter, c - boxCenter};
    // 1. The box's face normals: the triangle's bounds against the box.
    for (int i = 0; i < 3; ++i) {
        float mn = std::min({v[0][i], v[1][i], v[2][i]}), mx = std::max({v[0][i], v[1][i], v[2][i]});
        if (mn > h[i] || mx < -h[i]) return false;
    }
    // 2. The triangle's plane.
    const glm::vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
    glm::vec3 n = glm::cross(e[0], e[1]);
    float r = glm::dot(h, glm::abs(n));
    if (std::abs(glm::dot(n, v[0])) > r) return false;
    // 3. The nine cross products of box axes and triangle edges.
    for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < 3; ++i) {
            glm::vec3 axis(0.0f);
            axis[i] = 1.0f;
            glm::vec3 l = glm::cross(axis, e[k]);
            float p0 = glm::dot(l, v[0]), p1 = glm::dot(l, v[1]), p2 = glm::dot(l, v[2]);
            float rad = glm::dot(h, glm::abs(l));
            if (std::min({p0, p1, p2}) > rad || std::max({p0, p1, p2}) < -rad) return false;
        }
    }
    return true;
}

// Area of the part of triangle abc inside the box [boxMin, boxMax].
float clippedTriangleArea(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 boxMin, glm::vec3 boxMax) {
    // A triangle clipped by 6 planes has at most 9 vertices.
    std::array<glm::vec3, 12> polyA{a, b, c}, polyB{};
    int count = 3;
    glm::vec3* in = polyA.data();
    glm::vec3* out = polyB.data();
    for (int plane = 0; plane < 6 && count > 0; ++plane) {
        const int axis = plane / 2;
        const bool keepAbove = plane % 2 == 0;  // keep p[axis] >= min, or p[axis] <= max
        const float bound = keepAbove ? boxMin[axis] : boxMax[axis];
        auto inside = [&](const glm::vec3& p) { return keepAbove ? p[axis] >= bound : p[axis] <= bound; };
        if (std::all_of(in, in + count, inside)) continue;  // the plane cuts nothing off (the usual case)
        int outCount = 0;
        for (int i = 0; i < count; ++i) {
            const glm::vec3& p = in[i];
            const glm::vec3& q = in[(i + 1) % count];
            const bool pIn = inside(p), qIn = inside(q);
            if (pIn) out[outCount++] = p;
            if (pIn != qIn) {
                float t = (bound - p[axis]) / (q[axis] - p[axis]);
                out[outCount++] = p + t * (q - p);
            }
        }
        count = outCount;
        std::swap(in, out);
    }
    glm::vec3 sum(0.0f);
    for (int i = 1; i + 1 < count; ++i) sum += glm::cross(in[i] - in[0], in[i + 1] - in[0]);
    return 0.5f * glm::length(sum);
}

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
    // Bounding boxes overlap and the plane crosses the box, but the axis across the edge x + y = 1.1
    // separates (the box corner has x + y = 1); with x + y = 0.9 the corner is inside.
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
    EXPECT_NEAR(
        clippedTriangleArea({-10, -10, 0.5f}, {30, -10, 0.5f}, {-10, 30, 0.5f}, glm::vec3(0), glm::vec3(1)),
        1.0f, 1e-5f);
    // A diagonal plane x = y through the unit cube: the cut is a sqrt(2) x 1 rectangle.
    EXPECT_NEAR(clippedTriangleArea({-5, -5, -5}, {5, 5, -5}, {0, 0, 20}, glm::vec3(0), glm::vec3(1)),
                std::sqrt(2.0f), 1e-5f);
    // Outside.
    EXPECT_EQ(clippedTriangleArea({2, 2, 2}, {3, 2, 2}, {2, 3, 2}, glm::vec3(0), glm::vec3(1)), 0.0f);
}

VolumeRegion unitRegion(int n) {
    return {glm::vec3(-1.0f), 2.0f, n};
}

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
                if (g.area[g.visibility.index(x, y, z)] > 0.0f)
                    EXPECT_NEAR(v.z, 1.0f, 1e-5f) << "normal must be +y";
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

// Every voxel's occupancy and area are what testing the triangles against it one by one and clipping them
// to it give: small triangles across voxel planes, large ones across many voxels, some partly outside.
TEST(Voxelize, PiecesAreTheTrianglesClippedToEachVoxel) {
    const int n = 8;
    const VolumeRegion region{glm::vec3(0.0f), 8.0f, n};  // voxels of size 1
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> position(-0.5f, 8.5f), offset(-1.0f, 1.0f);
    TriangleMesh mesh;
    for (int t = 0; t < 300; ++t) {
        const float size = t % 3 == 0 ? 4.0f : t % 3 == 1 ? 1.0f : 0.3f;
        const glm::vec3 a(position(rng), position(rng), position(rng));
        for (int k = 0; k < 3; ++k)
            mesh.positions.push_back(k == 0 ? a
                                            : a + size * glm::vec3(offset(rng), offset(rng), offset(rng)));
        mesh.normals.insert(mesh.normals.end(), 3, glm::vec3(0.0f, 1.0f, 0.0f));
        mesh.triangles.push_back(glm::uvec3(3 * t, 3 * t + 1, 3 * t + 2));
    }
    const VoxelGeometry g = voxelize(std::span(&mesh, 1), region);
    size_t occupied = 0;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const glm::vec3 lo(x, y, z);
                bool touched = false;
                double area = 0.0;
                for (const glm::uvec3& t : mesh.triangles) {
                    const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
                    if (!triangleBoxOverlap(lo + 0.5f, glm::vec3(0.5f), a, b, c)) continue;
                    touched = true;
                    area += clippedTriangleArea(a, b, c, lo, lo + 1.0f);
                }
                const size_t i = g.visibility.index(x, y, z);
                ASSERT_EQ(g.visibility[i].x, touched ? 1.0f : 0.0f) << x << " " << y << " " << z;
                ASSERT_NEAR(g.area[i], area, 1e-4 * (1.0 + area)) << x << " " << y << " " << z;
                occupied += touched;
            }
    EXPECT_GT(occupied, 200u);
}

// Voxelizing again in place (as frames do) gives voxelize()'s bits, whatever the meshes did: moved, partly
// and wholly out of the region, emissive and not, more and fewer.
// With albedo, the voxels that any triangle touches are listed by row of the bounds, in index order: every
// occupied voxel, nothing else.
TEST(Voxelize, ListsTheSurfaceVoxelsRowByRow) {
    const VolumeRegion region = unitRegion(32);
    const std::vector<TriangleMesh> meshes = {
        test::placed(makeSphere(0.3f, 24), {0.1f, 0.0f, -0.2f}, test::diffuse(glm::vec3(0.5f))),
        test::placed(makeBox(glm::vec3(0.2f)), {-0.5f, 0.5f, 0.5f}, test::diffuse(glm::vec3(1)))};
    EXPECT_TRUE(voxelize(meshes, region).surfaceVoxels.empty());  // without albedo: not asked for
    const VoxelGeometry g = voxelize(meshes, region, true, true);
    const VoxelBox& b = g.bounds;
    const glm::ivec3 extent = b.hi - b.lo;
    ASSERT_EQ(g.surfaceRowStart.size(), static_cast<size_t>(extent.y) * extent.z + 1);
    std::vector<uint32_t> occupied;
    for (size_t i = 0; i < g.area.size(); ++i)
        if (g.visibility[i].x > 0.0f) occupied.push_back(static_cast<uint32_t>(i));
    EXPECT_GT(occupied.size(), 300u);
    EXPECT_EQ(g.surfaceVoxels, occupied);
    for (int z = b.lo.z; z < b.hi.z; ++z)
        for (int y = b.lo.y; y < b.hi.y; ++y) {
            const size_t row = static_cast<size_t>(z - b.lo.z) * extent.y + (y - b.lo.y);
            for (uint32_t k = g.surfaceRowStart[row]; k < g.surfaceRowStart[row + 1]; ++k) {
                const uint32_t i = g.surfaceVoxels[k];
                ASSERT_EQ(i / (32 * 32), static_cast<uint32_t>(z));
                ASSERT_EQ(i / 32 % 32, static_cast<uint32_t>(y));
            }
        }
    // And each one's albedo: the sphere's 0.5, the box's 1 (they share no voxel; the box lies at x < -0.3).
    ASSERT_EQ(g.albedo.size(), g.surfaceVoxels.size());
    for (size_t k = 0; k < g.albedo.size(); ++k) {
        const float x = -1.0f + (static_cast<float>(g.surfaceVoxels[k] % 32) + 0.5f) * (2.0f / 32.0f);
        ASSERT_NEAR(g.albedo[k].x, x < -0.3f ? 1.0f : 0.5f, 1e-5f) << k;
    }
}

TEST(Voxelize, RevoxelizingChangedMeshesEqualsVoxelizingThemAfresh) {
    const VolumeRegion region = unitRegion(32);
    std::vector<TriangleMesh> meshes = {
        test::placed(makeSphere(0.3f, 24), {0.1f, 0.0f, -0.2f}, test::diffuse(glm::vec3(0.5f)))};
    VoxelGeometry kept = voxelize(meshes, region, true, true);
    auto expectSame = [&](const char* step) {
        const VoxelBox old = kept.bounds;
        const VoxelBox returned = revoxelize(kept, meshes, region);
        EXPECT_EQ(returned.lo, old.lo) << step;
        EXPECT_EQ(returned.hi, old.hi) << step;
        const VoxelGeometry fresh = voxelize(meshes, region, true, true);
        EXPECT_EQ(kept.bounds.lo, fresh.bounds.lo) << step;
        EXPECT_EQ(kept.bounds.hi, fresh.bounds.hi) << step;
        ASSERT_EQ(kept.emission.size(), fresh.emission.size()) << step;
        EXPECT_EQ(kept.surfaceVoxels, fresh.surfaceVoxels) << step;
        EXPECT_EQ(kept.surfaceRowStart, fresh.surfaceRowStart) << step;
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

// Packed, the visibility's level 0 is the floats' rounded to bfloat16 voxel for voxel, the occupancy the
// floats' occupancy, and everything else the same bits; a packed voxelization is not redone in place.
TEST(Voxelize, APackedVoxelizationEqualsTheFloatOne) {
    const int n = 32;
    const VolumeRegion region = unitRegion(n);
    Material glowing = test::diffuse(glm::vec3(0.5f));
    glowing.emission = glm::vec3(1.0f, 2.0f, 3.0f);
    const std::vector<TriangleMesh> meshes = {
        test::placed(makeSphere(0.3f, 24), {0.1f, 0.0f, -0.2f}, test::diffuse(glm::vec3(0.5f))),
        test::placed(makeBox(glm::vec3(0.2f)), {-0.5f, 0.5f, 0.5f}, glowing)};
    const VoxelGeometry floats = voxelize(meshes, region, true, true);
    VoxelGeometry packed = voxelizePacked(meshes, region, true, true);
    ASSERT_TRUE(packed.packed);
    EXPECT_EQ(packed.visibility.size(), 0u);
    EXPECT_TRUE(packed.whole());
    EXPECT_EQ(packed.bounds, floats.bounds);
    EXPECT_EQ(packed.surfaceVoxels, floats.surfaceVoxels);
    EXPECT_EQ(packed.surfaceRowStart, floats.surfaceRowStart);
    EXPECT_EQ(packed.albedo, floats.albedo);
    const PackedGrid3 rounded(floats.visibility);
    ASSERT_EQ(packed.packedVisibility.size(), rounded.size());
    size_t occupied = 0;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t i = floats.visibility.index(x, y, z);
                ASSERT_EQ(packed.indexOf(x, y, z), i);
                ASSERT_EQ(packed.indexOf(i), i);
                ASSERT_EQ(packed.packedVisibility.packed(i), rounded.packed(i)) << x << "," << y << "," << z;
                ASSERT_EQ(packed.occupancy(i), floats.occupancy(i));
                ASSERT_EQ(packed.area[i], floats.area[i]);
                ASSERT_EQ(packed.emission[i], floats.emission[i]);
                occupied += packed.occupancy(i) > 0.0f;
            }
    EXPECT_EQ(occupied, packed.surfaceVoxels.size());
    EXPECT_THROW(revoxelize(packed, meshes, region), std::logic_error);
}

// With a window margin the arrays cover the meshes' voxels and the margin only; voxel for voxel the geometry
// is the whole grid's, and so it stays as the meshes move within the window, out of it (a new window) and
// out of the grid.
TEST(Voxelize, AWindowedVoxelizationEqualsTheWholeGridsInsideAndIsEmptyOutside) {
    const int n = 32;
    const VolumeRegion region = unitRegion(n);
    std::vector<TriangleMesh> meshes = {
        test::placed(makeSphere(0.2f, 24), {0.1f, 0.0f, -0.2f}, test::diffuse(glm::vec3(0.5f)))};
    constexpr int kMargin = 2;
    VoxelGeometry kept = voxelize(meshes, region, true, true, kMargin);
    auto expectSame = [&](const char* step) {
        revoxelize(kept, meshes, region);
        const VoxelGeometry whole = voxelize(meshes, region, true, true);
        EXPECT_EQ(kept.bounds, whole.bounds) << step;
        EXPECT_TRUE(kept.visibility.window().contains(whole.bounds)) << step;
        EXPECT_EQ(kept.surfaceVoxels, whole.surfaceVoxels) << step;  // indices of the whole grid
        EXPECT_EQ(kept.surfaceRowStart, whole.surfaceRowStart) << step;
        EXPECT_EQ(kept.area.size(), kept.visibility.size()) << step;
        EXPECT_EQ(kept.albedo.size(), kept.surfaceVoxels.size()) << step;  // per surface voxel
        EXPECT_EQ(kept.albedo, whole.albedo) << step;
        ASSERT_EQ(kept.emission.empty(), whole.emission.empty()) << step;
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const size_t w = whole.visibility.index(x, y, z), k = kept.indexOf(x, y, z);
                    ASSERT_EQ(k, kept.indexOf(w)) << step;
                    if (k == VoxelGeometry::kOutside) {
                        ASSERT_EQ(whole.area[w], 0.0f) << step << " " << x << "," << y << "," << z;
                        continue;
                    }
                    ASSERT_EQ(std::memcmp(&kept.visibility[k], &whole.visibility[w], sizeof(glm::vec4)), 0)
                        << step;
                    ASSERT_EQ(kept.area[k], whole.area[w]) << step;
                    if (!whole.emission.empty()) ASSERT_EQ(kept.emission[k], whole.emission[w]) << step;
                }
    };
    expectSame("first");
    // The sphere's voxels and the margin around them.
    EXPECT_EQ(kept.visibility.window(),
              VoxelBox({kept.bounds.lo - kMargin, kept.bounds.hi + kMargin}).intersection(VoxelBox::all(n)));
    EXPECT_LT(kept.visibility.size() * 4, static_cast<size_t>(n) * n * n);
    auto move = [&](glm::vec3 offset) {
        for (TriangleMesh& m : meshes)
            for (glm::vec3& p : m.positions) p += offset;
    };
    const VoxelBox first = kept.visibility.window();
    move({0.03f, 0.0f, 0.0f});  // one voxel: within the margin
    expectSame("moved a little");
    EXPECT_EQ(kept.visibility.window(), first);
    move({0.3f, 0.1f, 0.0f});
    expectSame("out of the window");
    EXPECT_NE(kept.visibility.window(), first);
    meshes[0].material.emission = glm::vec3(1.0f, 2.0f, 3.0f);
    move({-0.02f, 0.0f, 0.0f});
    expectSame("emissive");
    move({2.0f, 0.0f, 0.0f});
    expectSame("out of the grid");
    EXPECT_TRUE(kept.bounds.empty());
    move({-2.2f, 0.0f, 0.1f});
    expectSame("back");
}

}  // namespace

// A textured object keeps its triangles' voxel materials while it moves and turns: revoxelizing it equals
// voxelizing it afresh, bit for bit; the kept materials' key stays while only its place changes and changes
// with its scale.
TEST(Voxelize, AMovingTexturedObjectKeepsItsTriangleMaterials) {
    std::vector<glm::vec4> texels;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            texels.push_back((x + y) % 2 ? glm::vec4(1, 1, 1, 1) : glm::vec4(1, 0, 0, 1));
    Material m;
    m.albedo = glm::vec3(1.0f);
    m.baseColorTexture.texture = std::make_shared<Texture>(16, 16, std::move(texels), "checker");
    std::vector<TriangleMesh> meshes{makeSphere(0.3f, 48)};
    meshes[0].material = m;
    const VolumeRegion region{glm::vec3(-1.0f), 2.0f, 32};
    auto place = [&](glm::vec3 at, float turnDeg, float scale) {
        setTransform(meshes[0], glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), at),
                                                       glm::radians(turnDeg), glm::vec3(0, 1, 0)),
                                           glm::vec3(scale)));
    };
    place({0, 0, 0}, 0.0f, 1.0f);
    VoxelGeometry kept = voxelize(meshes, region, false, true);
    ASSERT_EQ(kept.triangleMaterials.size(), 1u);
    ASSERT_EQ(kept.triangleMaterials[0].values.size(), meshes[0].triangles.size());
    const uint64_t signature = kept.triangleMaterials[0].signature;
    for (int frame = 1; frame <= 3; ++frame) {
        place({0.07f * frame, 0.03f * frame, 0}, 25.0f * frame, 1.0f);
        revoxelize(kept, meshes, region, false);
        EXPECT_EQ(kept.triangleMaterials[0].signature, signature) << "frame " << frame;
        const VoxelGeometry fresh = voxelize(meshes, region, false, true);
        ASSERT_EQ(fresh.albedo.size(), kept.albedo.size());
        EXPECT_EQ(
            std::memcmp(fresh.albedo.data(), kept.albedo.data(), fresh.albedo.size() * sizeof(glm::vec3)), 0)
            << "frame " << frame;
    }
    place({0, 0, 0}, 0.0f, 1.5f);
    revoxelize(kept, meshes, region, false);
    EXPECT_NE(kept.triangleMaterials[0].signature, signature);
    // The checker is fine against a voxel: the voxels the sphere passes through reflect pink.
    glm::dvec3 sum(0.0);
    double area = 0.0;
    ASSERT_EQ(kept.albedo.size(), kept.surfaceVoxels.size());
    for (size_t k = 0; k < kept.albedo.size(); ++k) {  // per surface voxel
        const float a = kept.area[kept.surfaceVoxels[k]];
        sum += glm::dvec3(kept.albedo[k]) * static_cast<double>(a);
        area += a;
    }
    const glm::dvec3 mean = sum / area;
    EXPECT_NEAR(mean.x, 1.0, 1e-3);
    EXPECT_NEAR(mean.y, 0.5, 0.05);
    EXPECT_NEAR(mean.z, 0.5, 0.05);
}

}  // namespace deltagi
