// The direct light of the G-buffer's points: a glossy lobe under a sphere light.
#include "pipeline/shading.h"

#include <gtest/gtest.h>

#include "core/brdf.h"
#include "core/lights.h"
#include "core/sampling.h"
#include "test_disk.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

// The direct light (green) at `p` of a sphere light seen as the disk `s.wi`, `lightAngle` wide: the BRDF
// times the cosine averaged over the disk (uniform over its solid angle, as the path tracer's light samples)
// on a side x side grid, by brute force.
float meanOverDisk(const SurfacePoint& p, const LightSample& s, float lightAngle, int side) {
    return static_cast<float>(test::meanOverCone(s.wi, lightAngle, side,
                                                 [&](glm::vec3 wi) {
                                                     return evalBrdf(p.surface, p.normal, p.toEye, wi).y *
                                                            std::max(glm::dot(wi, p.normal), 0.0f);
                                                 })) *
           s.irradiance.y;
}

// A gilded floor (GGX alpha 0.04) seen 60 degrees off its normal under a sphere light 4 times as wide as the
// lobe: directRadiance against the BRDF averaged over the light's disk (uniform over its solid angle, as the
// path tracer's light samples), with the mirror direction at the disk's centre, halfway out, at its edge and
// beyond. The highlight is flat-topped as wide as the disk; the lobe widened for the light
// (ggxAlphaOverLight) alone, rounded, misses its edge by 15 % of its peak, the 3 x 3 quadrature by 2 %.
TEST(Shading, ANarrowLobeUnderAWideLightIsAveragedOverTheLightsDisk) {
    Material gold;
    gold.model = MaterialModel::MetallicRoughness;
    gold.albedo = glm::vec3(1.0f, 0.71f, 0.29f);
    gold.metallic = 1.0f;
    gold.roughness = 0.2f;
    SurfacePoint p = test::floorPoint(glm::vec3(0.0f), gold);
    const float view = glm::radians(60.0f);
    p.toEye = glm::vec3(std::sin(view), std::cos(view), 0.0f);
    const glm::vec3 mirror = glm::reflect(-p.toEye, p.normal);
    constexpr float kDistance = 2.0f, kRadius = 0.2f;
    const float lightAngle = std::asin(kRadius / kDistance);
    float peak = 0.0f, worstWidened = 0.0f;
    for (const float offset : {0.0f, 0.5f, 1.0f, 1.5f}) {
        // Turned out of the plane of incidence, where the disk's half vectors spread furthest.
        const glm::vec3 centre = frameAround(mirror) * glm::vec3(0.0f, std::sin(offset * lightAngle),
                                                                 std::cos(offset * lightAngle));
        Light light = test::pointLight(kDistance * centre, 1.0f);
        light.radius = kRadius;
        const LightSample s = sampleLight(light, p.position);
        const float truth = meanOverDisk(p, s, lightAngle, 128);
        const float quadrature = directRadiance(p, light).y;
        const float widened = evalBrdf(p.surface, p.normal, p.toEye, s.wi, lightAngle).y * s.irradiance.y *
                              glm::dot(s.wi, p.normal);
        if (offset == 0.0f) peak = truth;
        SCOPED_TRACE(::testing::Message() << offset << " radii off: " << quadrature << " (widened lobe "
                                          << widened << ") vs " << truth);
        EXPECT_NEAR(quadrature, truth, 0.04f * peak);  // 2 % at the disk's edge
        worstWidened = std::max(worstWidened, std::abs(widened - truth));
    }
    EXPECT_GT(worstWidened, 0.1f * peak) << "the widened lobe alone";  // 15 % at the disk's edge
}

// A glaze's lobe (GGX alpha 0.0144) under a lamp 15 times as wide, seen 45 degrees off its normal: the
// highlight is flat-topped as wide as the lamp's disk, with a sharp edge, and the quadrature's cells where
// the mirror direction falls on the disk are about as wide as the lobe (diskSide); 3 x 3 cells give 1.22
// times the truth at the centre and 0.69 at 0.9 radii.
TEST(Shading, AGlazesHighlightUnderAWideLampIsFlatTopped) {
    Material glaze;
    glaze.model = MaterialModel::MetallicRoughness;
    glaze.albedo = glm::vec3(0.1f, 0.2f, 0.6f);
    glaze.roughness = 0.12f;
    SurfacePoint p = test::floorPoint(glm::vec3(0.0f), glaze);
    const float view = glm::radians(45.0f);
    p.toEye = glm::vec3(std::sin(view), std::cos(view), 0.0f);
    const glm::vec3 mirror = glm::reflect(-p.toEye, p.normal);
    constexpr float kDistance = 0.28f, kRadius = 0.06f;
    const float lightAngle = std::asin(kRadius / kDistance);
    for (const float offset : {0.0f, 0.5f, 0.9f, 1.1f}) {
        const glm::vec3 centre = frameAround(mirror) * glm::vec3(0.0f, std::sin(offset * lightAngle),
                                                                 std::cos(offset * lightAngle));
        Light light = test::pointLight(kDistance * centre, 1.0f);
        light.radius = kRadius;
        const LightSample s = sampleLight(light, p.position);
        const float truth = meanOverDisk(p, s, lightAngle, 400);
        const float got = directRadiance(p, light).y;
        SCOPED_TRACE(::testing::Message() << offset << " radii off: " << got << " vs " << truth);
        EXPECT_NEAR(got, truth, 0.15f * truth);
    }
}

// A matte and a glossy floor, seen 60 degrees off their normal, under a sphere light low over their horizon:
// the part of its disk above the horizon lights them (as the path tracer's samples of the disk do), with its
// centre above the horizon, on it and below it; once the whole disk is below, nothing (the light at the
// centre's cosine alone is 0 with the centre below). The matte floor's clipped cosine is exact (to the
// disk's solid angle against its projection, 1 - cos(sigma) against sin^2(sigma) / 2: 0.6 % here); the
// glossy one's quadrature within a quarter. (Seen at grazing angles, where the mirror direction meets the
// disk, the lobe widened over each quadrature cell spreads too far: 0.4 times a glaze's truth at 85
// degrees.)
TEST(Shading, ASphereLightAcrossTheHorizonLightsWithItsPartAboveIt) {
    Material glaze;
    glaze.model = MaterialModel::MetallicRoughness;
    glaze.albedo = glm::vec3(0.1f, 0.2f, 0.6f);
    glaze.roughness = 0.12f;
    for (const Material& material : {test::diffuse(glm::vec3(0.7f)), glaze}) {
        const bool glossy = material.model == MaterialModel::MetallicRoughness;
        const float tolerance = glossy ? 0.25f : 0.01f;
        SurfacePoint p = test::floorPoint(glm::vec3(0.0f), material);
        const float view = glm::radians(60.0f);
        p.toEye = glm::vec3(-std::sin(view), std::cos(view), 0.0f);  // on the light's side
        constexpr float kDistance = 2.0f, kRadius = 0.3f;
        const float lightAngle = std::asin(kRadius / kDistance);
        float scale = 0.0f;
        for (const float elevation : {0.5f, 0.25f, 0.0f, -0.5f, -1.2f}) {
            const float a = elevation * lightAngle;
            Light light = test::pointLight(kDistance * glm::vec3(std::cos(a), std::sin(a), 0.0f), 1.0f);
            light.radius = kRadius;
            const LightSample s = sampleLight(light, p.position);
            const float truth = meanOverDisk(p, s, lightAngle, 128);
            const float got = directRadiance(p, light).y;
            if (elevation == 0.5f) scale = truth;
            SCOPED_TRACE(::testing::Message()
                         << "centre " << elevation << " radii above the horizon: " << got << " vs " << truth);
            if (elevation < -1.0f) {
                EXPECT_EQ(got, 0.0f);
                continue;
            }
            EXPECT_GT(truth, 0.05f * scale);
            // The tolerance, or for the glaze's thinnest cap (a few of the quadrature's points) 3 % of the
            // light with the centre half a radius above.
            EXPECT_NEAR(got, truth, std::max(tolerance * truth, glossy ? 0.03f * scale : 0.0f));
        }
    }
}

}  // namespace
}  // namespace deltagi
