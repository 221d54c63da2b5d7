// A sphere of uniform radiance over a grey floor: the closed form for the tests of what rays bring from a
// light volume (object_bounce_rays_test, diffuse_rays_test). A floor point at distance D from the sphere's
// centre, at angle theta from its normal, receives E / pi = L (r / D)^2 cos theta.
#pragma once

#include "pipeline/mipmap.h"
#include "pipeline/voxelize.h"
#include "scene/shapes.h"
#include "test_scenes.h"

namespace deltagi::test {

struct BrightSphereScene {
    static constexpr float kRadius = 0.2f, kHeight = 0.5f, kRadiance = 2.0f;
    // A floor of `floorSize` at y = 0 around (0.5, 0.5) and the sphere over it, its centre kHeight up.
    static Scene makeScene(float floorSize) {
        Scene s;
        s.real.push_back(
            placed(makeQuad({floorSize, floorSize}), {0.5f, 0.0f, 0.5f}, diffuse(glm::vec3(0.5f))));
        s.virtuals.push_back(
            placed(makeSphere(kRadius, 64), {0.5f, kHeight, 0.5f}, diffuse(glm::vec3(0.5f))));
        return s;
    }
    // The light volume of the sphere's voxels at kRadiance (64^3 over the unit cube, from y = -0.25).
    static MipVolume light(const Scene& s) {
        const VolumeRegion region{glm::vec3(0.0f, -0.25f, 0.0f), 1.0f, 64};
        const VoxelGeometry sphere = voxelize(s.virtuals, region);
        Grid3 grid(region.resolution);
        for (size_t i = 0; i < grid.size(); ++i) {
            const float occupancy = sphere.visibility[i].x;
            grid[i] = glm::vec4(glm::vec3(kRadiance * occupancy), occupancy);
        }
        return buildMipChain(region, std::move(grid));
    }
};

}  // namespace deltagi::test
