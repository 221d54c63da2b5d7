// Multi-bounce light in the volumes (bounceLight) against the closed form of a furnace: inside a closed box
// whose walls all leave radiance L and reflect albedo rho, each wall sees radiance L everywhere, so one more
// bounce adds rho L, two add rho L + rho^2 L.
#include "pipeline/bounce_light.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "core/ray_scene.h"
#include "pipeline/mipmap.h"
#include "scene/shapes.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

const glm::vec3 kCentre(0.5f);  // the viewpoint: inside the box

struct Furnace {
    VolumeRegion region{glm::vec3(0.0f), 1.0f, 32};
    VoxelGeometry geometry;
    Grid3 direct;
    MipVolume visibility;
};

// A closed box of albedo `albedo`, whose every surface voxel leaves radiance 1; its faces point out
// (makeBox), or in (`inward`: each triangle's winding reversed): the viewpoint inside decides the side that
// gathers.
Furnace furnace(float albedo, bool inward = false) {
    Furnace f;
    TriangleMesh box = makeBox(glm::vec3(0.7f));
    transformMesh(box, glm::translate(glm::mat4(1.0f), glm::vec3(0.5f)));
    if (inward)
        for (glm::uvec3& t : box.triangles) std::swap(t.y, t.z);
    box.material = test::diffuse(glm::vec3(albedo));
    const TriangleMesh meshes[] = {box};
    f.geometry = voxelize(meshes, f.region, true, true);
    f.direct = Grid3(f.region.resolution);
    for (size_t i = 0; i < f.direct.size(); ++i) {
        const float occupancy = f.geometry.visibility[i].x;
        f.direct[i] = glm::vec4(glm::vec3(occupancy), occupancy);
    }
    f.visibility = buildMipChain(f.region, f.geometry.visibility.clone());
    return f;
}

// The mean added radiance over the surface voxels.
float meanAdded(const Furnace& f, const SurfaceRadiance& added) {
    EXPECT_EQ(added.size(), f.geometry.surfaceVoxels.size());
    double sum = 0.0;
    for (const glm::vec3& a : added) sum += a.x;
    return added.empty() ? 0.0f : static_cast<float>(sum / static_cast<double>(added.size()));
}

TEST(BounceLight, AFurnaceGainsAlbedoTimesItsRadiancePerBounce) {
    Options options;
    options.render.bounceTail = false;
    // Faces pointing in, as a room's walls do: the cone marcher takes a coherent surface seen from behind as
    // a back face (options.trace.backface_weight), which does not apply to a box wound the other way.
    for (const bool inward : {true}) {
        SCOPED_TRACE(inward ? "faces in" : "faces out");
        const Furnace f = furnace(0.5f, inward);
        EXPECT_NEAR(meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, 1, kCentre)), 0.5f,
                    0.1f);
        EXPECT_NEAR(meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, 2, kCentre)), 0.75f,
                    0.15f);
        EXPECT_EQ(meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, 0, kCentre)), 0.0f);
    }
}

// The gather's cones are options.render.bounce_cones, not the diffuse cones: a furnace gains its albedo with
// few or many of them, and changing the diffuse count leaves the bounce as it was.
TEST(BounceLight, GathersWithTheBounceCones) {
    Options options;
    options.render.bounceTail = false;
    const Furnace f = furnace(0.5f, true);
    std::vector<float> added;
    for (const int cones : {1, 5, 16}) {
        SCOPED_TRACE(cones);
        options.render.bounceCones = cones;
        added.push_back(meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, 1, kCentre)));
        EXPECT_NEAR(added.back(), 0.5f, 0.1f);
    }
    EXPECT_NE(added[0], added[1]);
    EXPECT_NE(added[1], added[2]);
    options.render.bounceCones = 5;
    options.diffuse.count = 3;
    EXPECT_EQ(meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, 1, kCentre)), added[1]);
}

// With the bounces beyond the last estimated (options.render.bounce_tail), a furnace's walls gain the whole
// series rho L + rho^2 L + ... = rho L / (1 - rho), however many bounces are gathered.
TEST(BounceLight, AFurnaceWithTheTailGainsTheWholeSeries) {
    Options options;
    ASSERT_TRUE(options.render.bounceTail);
    for (const float albedo : {0.3f, 0.5f}) {
        SCOPED_TRACE(albedo);
        const Furnace f = furnace(albedo, true);
        const float series = albedo / (1.0f - albedo);
        for (const int bounces : {1, 2})
            EXPECT_NEAR(
                meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, bounces, kCentre)),
                series, 0.15f * series)
                << bounces;
    }
}

// The bounced light is one radiance per surface voxel; addBounce adds each to its voxel, occupancy unchanged,
// and nothing elsewhere.
TEST(BounceLight, AddsItsRadianceAtEachSurfaceVoxel) {
    const Furnace f = furnace(0.5f, true);
    const SurfaceRadiance bounced = bounceLight(f.direct, f.geometry, f.visibility, Options{}, 2, kCentre);
    ASSERT_EQ(bounced.size(), f.geometry.surfaceVoxels.size());
    Grid3 light = f.direct.clone();
    addBounce(light, bounced, f.geometry);
    std::vector<glm::vec4> expected(light.size());
    for (size_t i = 0; i < light.size(); ++i) expected[i] = f.direct[i];
    size_t nonZero = 0;
    for (size_t k = 0; k < bounced.size(); ++k) {
        expected[f.geometry.surfaceVoxels[k]] += glm::vec4(bounced[k], 0.0f);
        nonZero += bounced[k] != glm::vec3(0.0f);
    }
    for (size_t i = 0; i < light.size(); ++i) ASSERT_EQ(light[i], expected[i]) << i;
    EXPECT_GT(nonZero, 1000u);
    // Each row's surface voxels from a column on (reinjectLight walks them along a row).
    const VoxelBox& b = f.geometry.bounds;
    const int n = f.region.resolution;
    for (int z = b.lo.z; z < b.hi.z; ++z)
        for (int y = b.lo.y; y < b.hi.y; ++y) {
            const int x0 = (y + z) % n;
            const auto [first, last] = surfaceVoxelsInRow(f.geometry, y, z, x0);
            size_t expectedCount = 0;
            for (int x = x0; x < n; ++x) expectedCount += f.geometry.visibility.at(x, y, z).x > 0.0f;
            ASSERT_EQ(last - first, expectedCount) << y << ", " << z;
            for (uint32_t k = first; k < last; ++k)
                ASSERT_GE(f.geometry.surfaceVoxels[k], (static_cast<uint32_t>(z) * n + y) * n + x0);
        }
    EXPECT_EQ(surfaceVoxelsInRow(f.geometry, b.hi.y, b.lo.z, 0).first,
              surfaceVoxelsInRow(f.geometry, b.hi.y, b.lo.z, 0).second);  // outside the bounds: none
}

// A floor under a ceiling whose voxels leave radiance 1 within a disk of radius a over the floor's centre
// (the spot a bare bulb near the ceiling makes), height h above it: the floor under the disk's centre
// receives E / pi = a^2 / (a^2 + h^2) of it, and reflects albedo times that. The rays of
// options.render.bounce_rays find it; the bounce cones read the disk through coarse voxels that average it
// with the dark ceiling around it and with the empty room, and bring a fraction.
TEST(BounceLight, AFloorGetsABrightCeilingSpotsLightByRays) {
    const float floorY = 0.1f, ceilingY = 0.9f, a = 0.25f, albedo = 0.5f;
    Scene s;
    s.real.push_back(
        test::placed(makeQuad({0.98f, 0.98f}), {0.5f, floorY, 0.5f}, test::diffuse(glm::vec3(albedo))));
    TriangleMesh ceiling = makeQuad({0.98f, 0.98f});
    for (glm::uvec3& t : ceiling.triangles) std::swap(t.y, t.z);  // facing down, into the room
    s.real.push_back(
        test::placed(std::move(ceiling), {0.5f, ceilingY, 0.5f}, test::diffuse(glm::vec3(albedo))));
    const VolumeRegion region{glm::vec3(0.0f), 1.0f, 32};
    const VoxelGeometry geometry = voxelize(s.real, region, true, true);
    Grid3 direct(region.resolution);
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                const size_t i = direct.index(x, y, z);
                const float occupancy = geometry.visibility[i].x;
                const glm::vec3 centre = (glm::vec3(x, y, z) + 0.5f) * region.voxelSize();
                const bool spot =
                    centre.y > 0.5f && glm::length(glm::vec2(centre.x, centre.z) - glm::vec2(0.5f)) < a;
                direct[i] = glm::vec4(glm::vec3(spot ? occupancy : 0.0f), occupancy);
            }
    const MipVolume visibility = buildMipChain(region, geometry.visibility.clone());
    const RayScene rays(s, SceneContent::RealOnly);
    Options options;
    options.render.bounceTail = false;
    options.render.bounceRays = 256;
    const glm::vec3 viewpoint(0.5f);
    const SurfaceRadiance byRays = bounceLight(direct, geometry, visibility, options, 1, viewpoint, &rays);
    const SurfaceRadiance byCones = bounceLight(direct, geometry, visibility, options, 1, viewpoint);
    // The floor's surface voxels within 0.1 of the centre (two by two gathering voxels).
    const float h = ceilingY - floorY, expected = albedo * a * a / (a * a + h * h);
    double sumRays = 0.0, sumCones = 0.0;
    int count = 0;
    for (size_t k = 0; k < geometry.surfaceVoxels.size(); ++k) {
        const uint32_t i = geometry.surfaceVoxels[k];
        const glm::vec3 centre = (glm::vec3(i % 32, i / 32 % 32, i / 1024) + 0.5f) * region.voxelSize();
        if (centre.y > 0.5f || glm::length(glm::vec2(centre.x, centre.z) - glm::vec2(0.5f)) > 0.1f) continue;
        sumRays += byRays[k].x;
        sumCones += byCones[k].x;
        ++count;
    }
    ASSERT_GT(count, 20);
    EXPECT_NEAR(sumRays / count, expected, 0.15f * expected);
    EXPECT_LT(sumCones / count, 0.6f * expected);
}

// With the injection's voxels listed (its direct light is non-zero at the surface voxels alone), the light
// it gathers from is packed from those voxels into a zeroed grid: the same bounces bit for bit, by rays over
// two passes and by cones.
TEST(BounceLight, TheInjectionsListedVoxelsGiveTheSameBounces) {
    Scene s;
    s.real.push_back(
        test::placed(makeQuad({0.98f, 0.98f}), {0.5f, 0.1f, 0.5f}, test::diffuse(glm::vec3(0.5f))));
    TriangleMesh ceiling = makeQuad({0.98f, 0.98f});
    for (glm::uvec3& t : ceiling.triangles) std::swap(t.y, t.z);
    s.real.push_back(test::placed(std::move(ceiling), {0.5f, 0.9f, 0.5f}, test::diffuse(glm::vec3(0.7f))));
    const VolumeRegion region{glm::vec3(0.0f), 1.0f, 32};
    const VoxelGeometry geometry = voxelize(s.real, region, true, true);
    Grid3 direct(region.resolution);
    forEachSurfaceVoxel(geometry, [&](size_t, size_t k, size_t i) {
        const float occupancy = geometry.visibility[i].x;
        direct[i] = glm::vec4(glm::vec3(0.3f + 0.1f * static_cast<float>(k % 7)) * occupancy, occupancy);
    });
    InjectedVoxels written;
    written.listed = true;
    const MipVolume visibility = buildMipChain(region, geometry.visibility.clone());
    const RayScene rays(s, SceneContent::RealOnly);
    Options options;
    options.render.bounceRays = 64;
    const glm::vec3 viewpoint(0.5f);
    for (const RayScene* byRays : {&rays, static_cast<const RayScene*>(nullptr)}) {
        SCOPED_TRACE(byRays ? "rays" : "cones");
        const SurfaceRadiance whole =
            bounceLight(direct, geometry, visibility, options, 2, viewpoint, byRays);
        const SurfaceRadiance listed =
            bounceLight(direct, geometry, visibility, options, 2, viewpoint, byRays, &written);
        ASSERT_EQ(whole.size(), listed.size());
        size_t differing = 0, lit = 0;
        for (size_t k = 0; k < whole.size(); ++k) {
            differing += std::memcmp(&whole[k], &listed[k], sizeof(glm::vec3)) != 0;
            lit += whole[k].x > 0.0f;
        }
        EXPECT_EQ(differing, 0u);
        EXPECT_GT(lit, whole.size() / 2);
    }
}

TEST(BounceLight, BlackWallsReflectNothing) {
    const Furnace f = furnace(0.0f);
    Options options;
    EXPECT_EQ(meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, 2, kCentre)), 0.0f);
}

// A box standing on a floor whose voxels leave radiance 1: the box's bottom voxels see only the floor, so
// their bounce is albedo * 1. The rays start on the box's surface and find it; the cones start half a coarse
// voxel and more below it, under the floor, and find almost nothing.
TEST(BounceLight, ObjectsOnAFloorGetItsLightUnderneathByRays) {
    Scene s;
    s.real.push_back(
        test::placed(makeQuad({2.0f, 2.0f}), {0.5f, 0.2f, 0.5f}, test::diffuse(glm::vec3(0.5f))));
    s.virtuals.push_back(test::placed(makeBox(glm::vec3(0.3f)), {0.5f, 0.2f + 0.15f + 0.002f, 0.5f},
                                      test::diffuse(glm::vec3(0.5f))));
    const VolumeRegion region{glm::vec3(0.0f), 1.0f, 32};
    const VoxelGeometry floor = voxelize(s.real, region, true, true);
    const VoxelGeometry box = voxelize(s.virtuals, region, true, true);
    Grid3 light(region.resolution);
    for (size_t i = 0; i < light.size(); ++i) {
        const float occupancy = floor.visibility[i].x;
        light[i] = glm::vec4(glm::vec3(occupancy), occupancy);
    }
    const MipVolume lightMips = buildMipChain(region, std::move(light));
    const MipVolume sceneVisibility = buildMipChain(region, floor.visibility.clone());
    const MipVolume objectVisibility = buildMipChain(region, box.visibility.clone());
    const RayScene realOnly(s, SceneContent::RealOnly);
    const RayScene all(s, SceneContent::VirtualOnly, &realOnly);
    Options options;
    const VoxelBox& bounds = box.bounds;
    const std::vector<glm::vec3> byRays =
        gatherObjectBounceByRays(lightMips, box, objectVisibility, sceneVisibility, all, options, bounds, 2);
    const std::vector<glm::vec3> byCones =
        gatherObjectBounce(lightMips, box, objectVisibility, sceneVisibility, options, bounds, 2);
    // The mean over the box's lowest layer of voxels (its bottom face), and its top layer.
    auto layerMean = [&](const std::vector<glm::vec3>& added, int y) {
        double sum = 0.0;
        int count = 0;
        const glm::ivec3 extent = bounds.hi - bounds.lo;
        for (int z = bounds.lo.z; z < bounds.hi.z; ++z)
            for (int x = bounds.lo.x; x < bounds.hi.x; ++x) {
                if (box.visibility.at(x, y, z).x <= 0.0f) continue;
                sum +=
                    added[(static_cast<size_t>(z - bounds.lo.z) * extent.y + (y - bounds.lo.y)) * extent.x +
                          (x - bounds.lo.x)]
                        .x;
                ++count;
            }
        return count ? sum / count : 0.0;
    };
    EXPECT_NEAR(layerMean(byRays, bounds.lo.y), 0.5, 0.1);
    EXPECT_LT(layerMean(byCones, bounds.lo.y), 0.25);
    // Its top sees no floor: nothing.
    EXPECT_LT(layerMean(byRays, bounds.hi.y - 1), 0.02);
}

}  // namespace
}  // namespace deltagi
