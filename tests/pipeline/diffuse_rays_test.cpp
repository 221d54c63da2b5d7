// The objects' diffuse light by rays into the light volume (traceDiffuseRays) against closed forms: a floor
// point under a uniformly bright sphere of radius r and radiance L, its centre at distance D and angle theta
// from the normal, receives E / pi = L (r / D)^2 cos theta; a floor point under the centre of a bright w x w
// patch of the ceiling of a closed room, at height h, receives E / pi = L F with F the point-to-rectangle
// form factor.
#include "pipeline/diffuse_rays.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "bright_sphere.h"
#include "pipeline/mipmap.h"
#include "pipeline/voxelize.h"
#include "scene/shapes.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

// Each point kCopies times over: the copies' rays are jittered apart (by the point's index); their mean (red
// channel) is what is checked. A far patch takes a dozen of a point's 256 rays: 256 copies.
constexpr int kCopies = 256;
float meanOfCopies(const std::vector<glm::vec3>& values, size_t point) {
    float sum = 0.0f;
    for (int c = 0; c < kCopies; ++c) sum += values[point * kCopies + static_cast<size_t>(c)].x;
    return sum / static_cast<float>(kCopies);
}

constexpr int kManyRays = 256;

TEST(DiffuseRays, ABrightSphereLightsTheFloorUnderItAsItsSolidAngle) {
    using Bright = test::BrightSphereScene;
    const Scene s = Bright::makeScene(2.0f);
    const MipVolume light = Bright::light(s);
    const RayScene realOnly(s, SceneContent::RealOnly);
    const RayScene all(s, SceneContent::VirtualOnly, &realOnly);
    const Material& floor = s.real[0].material;
    const float offsets[] = {0.0f, 0.3f, 0.45f};
    std::vector<SurfacePoint> points;
    for (const float dx : offsets)
        for (int c = 0; c < kCopies; ++c) points.push_back(test::floorPoint({0.5f + dx, 0.0f, 0.5f}, floor));
    const std::vector<glm::vec3> got = traceDiffuseRays(points, light, all, kManyRays);
    for (size_t k = 0; k < std::size(offsets); ++k) {
        const glm::vec3 toCentre = glm::vec3(0.5f, Bright::kHeight, 0.5f) - points[k * kCopies].position;
        const float d = glm::length(toCentre);
        const float expected =
            Bright::kRadiance * (Bright::kRadius / d) * (Bright::kRadius / d) * (toCentre.y / d);
        EXPECT_NEAR(meanOfCopies(got, k), expected, 0.08f * expected) << offsets[k];
    }
    // A point without a diffuse part gathers nothing.
    const Material black = test::diffuse(glm::vec3(0.0f));
    const SurfacePoint dark[] = {test::floorPoint({0.5f, 0.0f, 0.5f}, black)};
    EXPECT_EQ(traceDiffuseRays(dark, light, all, kManyRays)[0], glm::vec3(0.0f));
}

// The form factor from a point to a w x w square centred above it at height h (the sum of four corner
// rectangles of w/2 x w/2).
float squareFormFactor(float w, float h) {
    const float a = 0.5f * w / h;
    const float s = std::sqrt(1.0f + a * a);
    const float corner = (a / s) * std::atan(a / s);  // (1 / 2 pi) of the two equal terms, times pi
    return 4.0f * corner / std::numbers::pi_v<float>;
}

// A closed room (faces in) whose ceiling has a bright square in its middle and whose other surfaces are dark
// but opaque: the floor's point under it sees the square through empty space. (The diffuse cones read the
// square through voxels as wide as the cone there, which average it with the dark ceiling and walls, and take
// the dark walls' opacity before they reach it: they bring 35 % of this.)
TEST(DiffuseRays, AFloorPointGetsAFarBrightPatchAsItsFormFactor) {
    constexpr float kRoom = 0.8f, kRadiance = 10.0f;
    constexpr float kPatch = 20.0f / 64.0f;  // 20 voxels of the volume below, centred on a voxel edge
    Scene s;
    TriangleMesh room = makeBox(glm::vec3(kRoom));
    for (glm::uvec3& t : room.triangles) std::swap(t.y, t.z);
    s.real.push_back(test::placed(room, glm::vec3(0.5f), test::diffuse(glm::vec3(0.5f))));
    const VolumeRegion region{glm::vec3(0.0f), 1.0f, 64};
    const VoxelGeometry geometry = voxelize(s.real, region);
    const float ceiling = 0.5f + 0.5f * kRoom;
    Grid3 grid(region.resolution);
    for (int z = 0; z < region.resolution; ++z)
        for (int y = 0; y < region.resolution; ++y)
            for (int x = 0; x < region.resolution; ++x) {
                const size_t i = geometry.visibility.index(x, y, z);
                const float occupancy = geometry.visibility[i].x;
                const glm::vec3 centre = region.origin + (glm::vec3(x, y, z) + 0.5f) * region.voxelSize();
                const bool bright = std::abs(centre.y - ceiling) < region.voxelSize() &&
                                    std::abs(centre.x - 0.5f) < 0.5f * kPatch &&
                                    std::abs(centre.z - 0.5f) < 0.5f * kPatch;
                grid[i] = glm::vec4(glm::vec3(bright ? kRadiance * occupancy : 0.0f), occupancy);
            }
    const MipVolume light = buildMipChain(region, std::move(grid));
    const RayScene scene(s, SceneContent::RealOnly);
    const Material& floor = s.real[0].material;
    const float floorY = 0.5f - 0.5f * kRoom;
    std::vector<SurfacePoint> points(kCopies, test::floorPoint({0.5f, floorY, 0.5f}, floor));
    const float expected = kRadiance * squareFormFactor(kPatch, ceiling - floorY);
    EXPECT_NEAR(meanOfCopies(traceDiffuseRays(points, light, scene, kManyRays), 0), expected,
                0.08f * expected);
}

TEST(DiffuseRays, AFootprintIsItsRaysShareOfTheHemisphere) {
    // 16 rays: cones of half-angle acos(15/16), tan 0.3712; 0.1 away in voxels of 0.01 that is 3.712 voxels.
    EXPECT_NEAR(rayFootprintLevel(0.1f, 16, 0.01f, 7.0f), std::log2(3.7123f), 1e-3f);
    EXPECT_EQ(rayFootprintLevel(0.01f, 16, 0.01f, 7.0f), 0.0f);   // under a voxel: level 0
    EXPECT_EQ(rayFootprintLevel(100.0f, 16, 0.01f, 7.0f), 7.0f);  // at most the coarsest
    EXPECT_LT(rayFootprintLevel(0.1f, 256, 0.01f, 7.0f), rayFootprintLevel(0.1f, 16, 0.01f, 7.0f));
}

}  // namespace
}  // namespace deltagi
