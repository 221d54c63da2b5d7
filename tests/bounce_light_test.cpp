// Multi-bounce light in the volumes (bounceLight) against the closed form of a furnace: inside a closed box
// whose walls all leave radiance L and reflect albedo rho, each wall sees radiance L everywhere, so one more
// bounce adds rho L, two add rho L + rho^2 L.
#include "bounce_light.h"

#include <gtest/gtest.h>

#include "mipmap.h"
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
float meanAdded(const Furnace& f, const Grid3& added) {
    double sum = 0.0;
    int count = 0;
    for (size_t i = 0; i < added.size(); ++i)
        if (f.geometry.visibility[i].x > 0.0f) {
            EXPECT_EQ(added[i].w, 0.0f);
            sum += added[i].x;
            ++count;
        }
    return count ? static_cast<float>(sum / count) : 0.0f;
}

TEST(BounceLight, AFurnaceGainsAlbedoTimesItsRadiancePerBounce) {
    Options options;
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

TEST(BounceLight, BlackWallsReflectNothing) {
    const Furnace f = furnace(0.0f);
    Options options;
    EXPECT_EQ(meanAdded(f, bounceLight(f.direct, f.geometry, f.visibility, options, 2, kCentre)), 0.0f);
}

}  // namespace
}  // namespace deltagi
