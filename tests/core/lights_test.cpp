// Lights: the spot cone's quick test (SpotCone::mayReach), which the shadow maps use to pass over the texels
// outside a cone, never turns away a direction the falloff lights.
#include "core/lights.h"

#include <gtest/gtest.h>

#include "core/rng.h"

namespace deltagi {
namespace {

TEST(SpotCone, MayReachWhereverTheFalloffIsNotZero) {
    std::vector<Light> lights;
    for (const float outer : {10.0f, 45.0f, 85.0f, 89.9f, 120.0f}) {
        Light spot;
        spot.type = Light::Type::Spot;
        spot.direction = glm::normalize(glm::vec3(0.2f, -1.0f, 0.1f));
        spot.outerAngleDeg = outer;
        spot.innerAngleDeg = 0.7f * outer;
        lights.push_back(spot);
    }
    Light hard = lights[1];
    hard.innerAngleDeg = hard.outerAngleDeg;  // no smooth edge
    lights.push_back(hard);
    Light lambertian = lights[0];
    lambertian.lambertian = true;
    lights.push_back(lambertian);
    Light point;
    point.type = Light::Type::Point;
    lights.push_back(point);
    Rng rng(1, 2, 3);
    for (size_t l = 0; l < lights.size(); ++l) {
        const SpotCone cone(lights[l]);
        int lit = 0, passedOver = 0;
        for (int k = 0; k < 20000; ++k) {
            // Any length, any direction; near the cone's edge as often as not.
            glm::vec3 d(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
            if (k % 2) d = glm::mix(lights[l].direction, d, 0.05f * rng.uniform()) + 0.3f * d;
            d *= 0.01f + 10.0f * rng.uniform();
            if (!(glm::length(d) > 0.0f)) continue;
            const float falloff = cone.falloff(glm::normalize(d));
            if (falloff > 0.0f) {
                ++lit;
                ASSERT_TRUE(cone.mayReach(d)) << "light " << l << ": falloff " << falloff;
            }
            passedOver += !cone.mayReach(d);
        }
        EXPECT_GT(lit, 0) << l;
        // The test does turn directions away, but for the lights without a cone.
        if (lights[l].type == Light::Type::Spot && lights[l].outerAngleDeg < 90.0f)
            EXPECT_GT(passedOver, 1000) << l;
    }
}

}  // namespace
}  // namespace deltagi
