// Shadow rays (options.shadow.method "rays") against closed forms: the umbra of a sphere under a point light,
// and the penumbra of a disk light behind a straight edge.
#include "pipeline/shadow_rays.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include <gtest/gtest.h>

#include "core/brdf_sampling.h"
#include "deltagi/renderer.h"
#include "relit_surfaces.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

using test::diffuse;
using test::floorPoint;
using test::placed;

// A sphere of radius 0.2 at height 0.5 under a point light at 1.5 casts a round umbra of radius
// 1.5 tan(asin(0.2 / 1.0)) = 0.306 on the floor, with no penumbra. Rendered end to end with the default
// volume (twice the sphere's box, which does not reach the floor): the floor's change is its whole direct
// light inside the umbra and nothing outside. The paper's shadow cones removed 56-64 % of it and spread it
// wider.
TEST(ShadowRays, SphereUnderAPointLightCastsItsProjectedUmbra) {
    Scene scene = test::floorScene();
    scene.real[0] = placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor");
    // A black sphere: it reflects nothing, so the floor's change is the shadow alone.
    scene.virtuals.push_back(placed(makeSphere(0.2f, 96), {0, 0.5f, 0}, diffuse(glm::vec3(0.0f)), "ball"));
    scene.camera = test::lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, 160, 120, 60.0f);
    const RenderOutput out = render(scene);
    const float umbra = 1.5f * std::tan(std::asin(0.2f));
    const glm::vec3 eye = scene.camera.position();
    int inside = 0, outside = 0;
    for (int y = 0; y < scene.camera.height; ++y)
        for (int x = 0; x < scene.camera.width; ++x) {
            if (out.objectMask.at(x, y, 0) > 0.0f) continue;
            const glm::vec3 dir = scene.camera.rayDirection(x + 0.5f, y + 0.5f);
            if (dir.y >= 0.0f) continue;
            const glm::vec3 p = eye + dir * (-eye.y / dir.y);
            const float r = glm::length(glm::vec2(p.x, p.z));
            const glm::vec3 toLight = glm::vec3(0, 1.5f, 0) - p;
            const float d2 = glm::dot(toLight, toLight);
            const float direct = 0.5f / std::numbers::pi_v<float> * 2.0f * (1.5f / std::sqrt(d2)) / d2;
            const float change = out.delta.at(x, y, 0);
            if (r < umbra - 0.06f) {
                EXPECT_NEAR(change, -direct, 0.05f * direct) << "umbra at r = " << r;
                ++inside;
            } else if (r > umbra + 0.1f && r < 1.0f) {  // beyond the filter's reach (2 pixels)
                EXPECT_NEAR(change, 0.0f, 0.02f * direct) << "lit at r = " << r;
                ++outside;
            }
        }
    EXPECT_GT(inside, 50);
    EXPECT_GT(outside, 500);
}

// A hard light's shadow keeps its edge a pixel wide, however sparse its samples and wide the filter: every
// real pixel whose footprint lies wholly in the umbra, or wholly outside it, has the exact value; only the
// pixels that the edge crosses lie between (issue 36: the filter spread it over 3-4 pixels, the stride's
// more).
TEST(ShadowRays, AHardLightsShadowEdgeStaysAPixelWide) {
    Scene scene = test::floorScene();
    scene.real[0] = placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor");
    scene.virtuals.push_back(placed(makeSphere(0.2f, 96), {0, 0.5f, 0}, diffuse(glm::vec3(0.0f)), "ball"));
    const glm::vec3 light(0.4f, 1.5f, 0.1f), centre(0, 0.5f, 0);
    scene.lights[0].position = light;
    scene.camera = test::lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, 160, 120, 60.0f);
    scene.options.shadow.relightPixelStride = 4;  // sparse, and the filter's radius is the default 2
    const RenderOutput out = render(scene);
    const glm::vec3 eye = scene.camera.position();
    auto floorAt = [&](float px, float py) {
        const glm::vec3 dir = scene.camera.rayDirection(px, py);
        return eye + dir * (-eye.y / dir.y);
    };
    auto shadowed = [&](glm::vec3 p) {  // does the segment to the light pass through the ball?
        const glm::vec3 d = glm::normalize(light - p), m = p - centre;
        const float b = glm::dot(m, d), c = glm::dot(m, m) - 0.04f;
        return b * b - c > 0.0f && -b > 0.0f;
    };
    int umbra = 0, lit = 0, edge = 0;
    for (int y = 1; y < scene.camera.height - 1; ++y)
        for (int x = 1; x < scene.camera.width - 1; ++x) {
            if (out.objectMask.at(x, y, 0) > 0.0f) continue;
            if (scene.camera.rayDirection(x, y).y >= -0.05f) continue;
            int corners = 0;
            for (int c = 0; c < 4; ++c) corners += shadowed(floorAt(x + (c & 1), y + (c >> 1)));
            const glm::vec3 p = floorAt(x + 0.5f, y + 0.5f);
            const glm::vec3 toLight = light - p;
            const float d2 = glm::dot(toLight, toLight);
            const float direct = 0.5f / std::numbers::pi_v<float> * 2.0f * (toLight.y / std::sqrt(d2)) / d2;
            const float change = out.delta.at(x, y, 0);
            if (corners == 4) {
                EXPECT_NEAR(change, -direct, 0.05f * direct) << "umbra at pixel " << x << ", " << y;
                ++umbra;
            } else if (corners == 0 && glm::length(glm::vec2(p.x, p.z)) < 1.5f) {
                EXPECT_NEAR(change, 0.0f, 0.03f * direct) << "lit at pixel " << x << ", " << y;
                ++lit;
            } else if (corners != 0) {
                ++edge;
            }
        }
    EXPECT_GT(umbra, 200);
    EXPECT_GT(lit, 2000);
    EXPECT_GT(edge, 30);
}

// A disk light of radius a = 0.1 at height 1 above a straight edge at height 0.5 (an opaque plate over
// x < 0): a floor point at x sees the part of the disk beyond -x, so its visible fraction is the disk's area
// fraction beyond a chord at distance -x: (acos(d) - d sqrt(1 - d^2)) / pi with d = -x / a. The penumbra is
// 2a wide, centred under the edge.
TEST(ShadowRays, DiskLightPenumbraFollowsTheChordAreaBehindAnEdge) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.real.push_back(placed(makeQuad({2.0f, 2.0f}), {-1.0f, 0.5f, 0}, diffuse(glm::vec3(0.5f)), "plate"));
    Light light = test::pointLight({0.0f, 1.0f, 0.0f}, 1.0f);
    light.radius = 0.1f;
    scene.lights.push_back(light);
    const RayScene rays(scene, SceneContent::RealOnly);
    Options options;
    options.shadow.raySamples = 256;
    std::vector<SurfacePoint> points;
    std::vector<float> xs;
    for (float x = -0.14f; x <= 0.1401f; x += 0.02f) {
        points.push_back(floorPoint({x, 0.0f, 0.3f * x}, scene.real[0].material));
        xs.push_back(x);
    }
    const std::vector<ShadowOcclusion> shadows =
        traceShadowRays(points, scene.lights, {&rays, nullptr, {}}, options, ShadowMode::SceneOnly);
    for (size_t i = 0; i < xs.size(); ++i) {
        const float d = glm::clamp(-xs[i] / 0.1f, -1.0f, 1.0f);
        const float visible = (std::acos(d) - d * std::sqrt(1.0f - d * d)) / std::numbers::pi_v<float>;
        EXPECT_NEAR(1.0f - shadows[i].scene, visible, 0.04f) << "x = " << xs[i];
    }
}

// A disk light half hidden behind an edge, seen from a glossy floor point whose lobe is far narrower than the
// disk: where the mirror direction falls on the visible half the point's highlight is unshadowed, where it
// falls on the hidden half the highlight is gone, though half of the disk reaches the point either way (the
// plain fraction, which holds for a matte point and is kept for it).
TEST(ShadowRays, AGlossyPointsShadowIsThatOfThePartOfTheLightItsLobeSees) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.real.push_back(placed(makeQuad({2.0f, 2.0f}), {-1.0f, 0.5f, 0}, diffuse(glm::vec3(0.5f)), "plate"));
    Light light = test::pointLight({0.0f, 1.0f, 0.0f}, 1.0f);
    light.radius = 0.1f;
    const RayScene rays(scene, SceneContent::RealOnly);
    const ShadowRayScenes scenes{&rays, nullptr, {}};
    Options options;
    options.shadow.raySamples = 256;
    Material glaze = diffuse(glm::vec3(0.05f));
    glaze.specular = glm::vec3(0.5f);
    glaze.roughness = 0.02f;  // Phong exponent 5,000: a lobe 0.017 rad wide under a disk 0.1 rad wide
    const Material matte = diffuse(glm::vec3(0.5f));
    SurfacePoint p = floorPoint(glm::vec3(0.0f), glaze);
    const float plain =
        1.0f - traceShadowRays(std::span(&p, 1), std::span(&light, 1), scenes, options, ShadowMode::Shaded)[0]
                   .combined;
    EXPECT_NEAR(plain, 0.5f, 0.03f);
    for (const float side : {1.0f, -1.0f}) {  // the mirror direction on the visible (x > 0), hidden half
        p.toEye = glm::normalize(glm::vec3(-0.05f * side, 1.0f, 0.0f));
        const float occlusion = glossyShadowOcclusion(p, {}, light, scenes, 1.0f - plain, 64);
        EXPECT_NEAR(occlusion, side > 0.0f ? 0.0f : 1.0f, 0.1f) << side;
    }
    SurfacePoint m = floorPoint(glm::vec3(0.0f), matte);
    EXPECT_EQ(glossyShadowOcclusion(m, {}, light, scenes, 1.0f - plain, 64), 1.0f - plain);
    // Its sub-samples as the pixel's area: the same.
    std::vector<SurfacePoint> area(4, p);
    EXPECT_NEAR(glossyShadowOcclusion(p, area, light, scenes, 1.0f - plain, 64), 1.0f, 0.1f);
}

// Relighting reads only the change the objects make: where the scene already blocks a sample, the objects
// blocking it too changes nothing (no double shadow, §3.2), and points whose rays cannot reach the objects
// get no rays.
TEST(ShadowRays, RelightingCountsOnlySamplesTheSceneLeavesOpen) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.real.push_back(placed(makeQuad({2.0f, 2.0f}), {-1.0f, 0.5f, 0}, diffuse(glm::vec3(0.5f)), "plate"));
    // A box over the whole edge between plate and light: it blocks what the plate blocks, and more.
    scene.virtuals.push_back(
        placed(makeBox({0.4f, 0.02f, 0.4f}), {0, 0.75f, 0}, diffuse(glm::vec3(0.5f)), "lid"));
    Light light = test::pointLight({0.0f, 1.0f, 0.0f}, 1.0f);
    light.radius = 0.1f;
    scene.lights.push_back(light);
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene objects(scene, SceneContent::VirtualOnly, &realOnly);
    Options options;
    options.shadow.raySamples = 64;
    const Material& m = scene.real[0].material;
    const std::vector<SurfacePoint> points = {floorPoint({-0.3f, 0, 0}, m), floorPoint({0.3f, 0, 0}, m),
                                              floorPoint({1.8f, 0, 1.8f}, m)};
    const ShadowRayScenes rays{&realOnly, &objects, scene.virtuals[0].bounds()};
    const auto relit = traceShadowRays(points, scene.lights, rays, options, ShadowMode::DeltaShadow);
    const auto shaded = traceShadowRays(points, scene.lights, rays, options, ShadowMode::Shaded);
    // Under the plate: in its shadow already, the lid changes nothing.
    EXPECT_EQ(shadowFactor(relit[0], ShadowMode::DeltaShadow), 0.0f);
    EXPECT_EQ(shaded[0].combined, 1.0f);
    // In the open, under the lid: all of the light is taken away.
    EXPECT_FLOAT_EQ(shadowFactor(relit[1], ShadowMode::DeltaShadow), -1.0f);
    EXPECT_FLOAT_EQ(shaded[1].combined, 1.0f);
    EXPECT_FLOAT_EQ(shaded[1].scene, 0.0f);
    // Far away, out of the lid's shadow: nothing.
    EXPECT_EQ(shadowFactor(relit[2], ShadowMode::DeltaShadow), 0.0f);
    EXPECT_EQ(shaded[2].combined, 0.0f);
}

// A pixel's shadow is the light's over the pixel's area: with the pixel's sub-samples (PixelSamples), two of
// them under the plate's edge and two in the open give half the light blocked, whichever the centre is
// (the centre alone gave 0 or 1). A sub-sample facing away from the light takes no part.
TEST(ShadowRays, APixelsSubSamplesShareItsShadow) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.real.push_back(placed(makeQuad({2.0f, 2.0f}), {-1.0f, 0.5f, 0}, diffuse(glm::vec3(0.5f)), "plate"));
    scene.lights.push_back(test::pointLight({0.0f, 1.0f, 0.0f}, 1.0f));  // no size: one ray per sample
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const Material& m = scene.real[0].material;
    Options options;
    PixelSamples samples;
    samples.perPixel = 4;
    samples.rect = {0, 0, 1, 1};
    samples.points = {floorPoint({-0.01f, 0, 0}, m), floorPoint({0.01f, 0, 0}, m),
                      floorPoint({-0.01f, 0, 0.01f}, m), floorPoint({0.01f, 0, 0.01f}, m)};
    for (const glm::vec3 centre : {glm::vec3(-0.005f, 0, 0.005f), glm::vec3(0.005f, 0, 0.005f)}) {
        const std::vector<SurfacePoint> points = {floorPoint(centre, m)};
        const auto alone =
            traceShadowRays(points, scene.lights, {&realOnly, nullptr, {}}, options, ShadowMode::Shaded);
        EXPECT_EQ(alone[0].combined, centre.x < 0.0f ? 1.0f : 0.0f);
        const auto area = traceShadowRays(points, scene.lights, {&realOnly, nullptr, {}}, options,
                                          ShadowMode::Shaded, {}, &samples, 1);
        EXPECT_FLOAT_EQ(area[0].combined, 0.5f) << "centre x = " << centre.x;
        EXPECT_FLOAT_EQ(area[0].scene, 0.5f);
    }
    // The two open sub-samples turned away from the light: only the shadowed ones count.
    samples.points[1].normal = samples.points[3].normal = glm::vec3(0, -1, 0);
    const std::vector<SurfacePoint> points = {floorPoint({0.005f, 0, 0.005f}, m)};
    const auto area = traceShadowRays(points, scene.lights, {&realOnly, nullptr, {}}, options,
                                      ShadowMode::Shaded, {}, &samples, 1);
    EXPECT_FLOAT_EQ(area[0].combined, 1.0f);
    // And the light before the shadow is their mean: half of the facing points' (combineLighting).
    const std::vector<ShadowOcclusion> open(1);
    const auto shadedAlone = combineLighting(points, scene.lights, open, ShadowMode::Shaded, {}, {});
    const auto shadedArea =
        combineLighting(points, scene.lights, open, ShadowMode::Shaded, {}, {}, nullptr, 1, &samples);
    EXPECT_NEAR(shadedArea[0].x, 0.5f * shadedAlone[0].x, 1e-3f * shadedAlone[0].x);
}

// A pixel that faces away from the light is in its own attached shadow: occluded, like a ray below a
// sample's horizon, not open. (Open, the edge-aware filter spread that visibility into the facing pixels next
// to it: a bright speck in a torus' shadowed inner rim, which the path tracer does not show.) Relit points
// carry only the change the objects make, none there.
TEST(ShadowRays, APixelFacingAwayFromTheLightIsInItsAttachedShadow) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.lights.push_back(test::pointLight({0.0f, 1.0f, 0.0f}, 1.0f));
    const RayScene realOnly(scene, SceneContent::RealOnly);
    SurfacePoint away = floorPoint({0.1f, 0, 0}, scene.real[0].material);
    away.normal = glm::vec3(0, -1, 0);
    const std::vector<SurfacePoint> points = {away};
    Options options;
    PixelSamples samples;
    samples.perPixel = 4;
    samples.rect = {0, 0, 1, 1};
    samples.points.assign(4, away);
    const std::array<const PixelSamples*, 2> areas = {nullptr, &samples};
    for (const PixelSamples* area : areas) {
        const auto shaded = traceShadowRays(points, scene.lights, {&realOnly, nullptr, {}}, options,
                                            ShadowMode::Shaded, {}, area, 1);
        EXPECT_EQ(shaded[0].combined, 1.0f);
        EXPECT_EQ(shaded[0].scene, 1.0f);
    }
    const auto relit =
        traceShadowRays(points, scene.lights, {&realOnly, nullptr, {}}, options, ShadowMode::DeltaShadow);
    EXPECT_EQ(relit[0].combined, 0.0f);
    EXPECT_EQ(relit[0].object, 0.0f);
    // Facing the light and open: not occluded.
    const auto open = traceShadowRays({{floorPoint({0.1f, 0, 0}, scene.real[0].material)}}, scene.lights,
                                      {&realOnly, nullptr, {}}, options, ShadowMode::Shaded);
    EXPECT_EQ(open[0].combined, 0.0f);
}

// Sample points on a sphere light lie on its disk facing the point; a light without a size is one ray.
TEST(ShadowRays, SamplesLieOnTheLightsDiskFacingThePoint) {
    Light light = test::pointLight({0.0f, 2.0f, 0.0f}, 1.0f);
    EXPECT_EQ(shadowRayCount(light, 16), 1);
    light.radius = 0.25f;
    EXPECT_EQ(shadowRayCount(light, 16), 16);
    EXPECT_EQ(shadowRayCount(light, 20), 16);
    const glm::vec3 p(1.0f, 0.0f, 0.5f);
    const glm::vec3 axis = glm::normalize(light.position - p);
    for (float u : {0.05f, 0.5f, 0.95f})
        for (float v : {0.1f, 0.6f}) {
            const ShadowRaySample s = sampleShadowRay(light, p, u, v);
            const glm::vec3 target = p + s.wi * s.distance;
            EXPECT_NEAR(glm::dot(target - light.position, axis), 0.0f, 1e-5f);
            EXPECT_LE(glm::length(target - light.position), 0.25f + 1e-5f);
        }
}

// The relit rays' cull: a ray that meets the sphere (or ends inside it) passes; one that passes it by, or
// ends short of it, does not.
TEST(ShadowRays, ARayPassesTheSphereCullWhereItCanMeetTheSphere) {
    const glm::vec3 centre(0.0f, 1.0f, 0.0f), x(1.0f, 0.0f, 0.0f), up(0.0f, 1.0f, 0.0f);
    EXPECT_TRUE(rayMayMeetSphere({0, 0, 0}, up, 5.0f, centre, 0.3f));       // through it
    EXPECT_TRUE(rayMayMeetSphere({0, 0, 0}, up, 0.8f, centre, 0.3f));       // ends inside it
    EXPECT_FALSE(rayMayMeetSphere({0, 0, 0}, up, 0.6f, centre, 0.3f));      // ends short of it
    EXPECT_TRUE(rayMayMeetSphere({0.29f, 0, 0}, up, 5.0f, centre, 0.3f));   // grazes it
    EXPECT_FALSE(rayMayMeetSphere({0.31f, 0, 0}, up, 5.0f, centre, 0.3f));  // passes it by
    EXPECT_FALSE(rayMayMeetSphere({0, 1.0f, 2.0f}, glm::vec3(0, 0, 1), 5.0f, centre, 0.3f));  // away
    EXPECT_TRUE(rayMayMeetSphere({-2.0f, 1.1f, 0}, x, INFINITY, centre, 0.3f));  // a directional light's
}

// The relit shadow pass runs over the image rectangle of the objects' shadow volumes (relitShadowRect): every
// real pixel whose relit shadow rays meet the objects lies inside it, for each kind of light (a disk, a hard
// point, a spot, a directional light with a width, two at once), and the sparse pass over it with its margin
// (sparsePassMargin) gives the bits of the pass over the whole image.
TEST(ShadowRays, TheRelitShadowRectangleHoldsEveryPixelTheObjectsChange) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.real.push_back(placed(makeBox({0.3f, 0.6f, 0.3f}), {-0.6f, 0.3f, -0.3f}, diffuse(glm::vec3(0.5f)),
                                "block"));  // a second surface, partly in the shadows
    scene.virtuals.push_back(
        placed(makeSphere(0.15f, 48), {0.1f, 0.35f, 0.1f}, diffuse(glm::vec3(0.5f)), "ball"));
    scene.camera = test::lookAtCamera({0.0f, 1.6f, 1.9f}, {0, 0.2f, 0}, 160, 120, 60.0f);
    const test::RelitSurfaces relit(scene);
    Options options;
    options.shadow.raySamples = 16;

    Light disk = test::pointLight({0.4f, 1.4f, 0.3f}, 1.0f);
    disk.radius = 0.3f;
    const Light hard = test::pointLight({-0.3f, 1.1f, 0.5f}, 1.0f);
    Light spot = test::pointLight({0.2f, 1.0f, 0.0f}, 1.0f);
    spot.type = Light::Type::Spot;
    spot.radius = 0.05f;
    spot.direction = {0, -1, 0};
    spot.innerAngleDeg = 40.0f;
    spot.outerAngleDeg = 60.0f;
    Light sun = test::directionalLight({0.5f, -1.0f, -0.3f}, 1.0f);
    sun.angularRadius = 0.15f;
    const std::vector<std::vector<Light>> cases = {{disk}, {hard}, {spot}, {sun}, {disk, sun}};
    for (size_t c = 0; c < cases.size(); ++c) {
        const std::vector<Light>& lights = cases[c];
        auto trace = [&](std::span<const uint32_t> pixels) {
            return traceShadowRays(relit.points, lights, relit.rays, options, ShadowMode::DeltaShadow,
                                   pixels);
        };
        const PixelRect rect = relitShadowRect(scene.camera, lights, relit.rays, relit.image, 0);
        const std::string what = "case " + std::to_string(c);
        EXPECT_GT(relit.changedPixels(trace({}), lights.size(), rect, what), 100) << what;
        EXPECT_TRUE(relit.smallerThan(rect, 0.6f)) << what;  // tight enough to matter
        // The sparse pass at a stride of 2 and 4 with the filter, holes traced.
        for (int stride : {2, 4}) {
            DenoiseSettings filter;
            filter.interpolate = true;
            const PixelRect bounds = relitShadowRect(scene.camera, lights, relit.rays, relit.image,
                                                     sparsePassMargin(stride, filter));
            EXPECT_TRUE(relit.sameAsWholeImage<ShadowOcclusion>(
                bounds, stride, static_cast<int>(lights.size()), filter, trace))
                << what << ", stride " << stride;
        }
    }
}

// The boxes of relitShadowVolume hold every point of the scene from which a ray towards a light meets the
// objects: random points of the scene's box with random points of a light's disk (or directions of a
// directional light's cone) whose segment meets the objects' box (or whose ray meets their sphere).
TEST(ShadowRays, TheRelitShadowVolumeHoldsEveryPointWhoseRaysMeetTheObjects) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.real.push_back(
        placed(makeBox({0.3f, 1.6f, 0.3f}), {-0.6f, 0.8f, -0.3f}, diffuse(glm::vec3(0.5f)), "pillar"));
    scene.virtuals.push_back(
        placed(makeBox({0.2f, 0.3f, 0.25f}), {0.1f, 0.35f, 0.1f}, diffuse(glm::vec3(0.5f)), "crate"));
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene objects(scene, SceneContent::VirtualOnly, &realOnly);
    const ShadowRayScenes rays{&realOnly, &objects, scene.virtuals[0].bounds(),
                               objectSphereRadius(scene.virtuals)};
    Light disk = test::pointLight({0.4f, 1.4f, 0.3f}, 1.0f);
    disk.radius = 0.3f;
    const Light hard = test::pointLight({-0.3f, 0.9f, 0.5f}, 1.0f);
    // Level with the crate: its shadow crosses the whole room.
    Light side = test::pointLight({1.2f, 0.4f, 0.1f}, 1.0f);
    side.radius = 0.05f;
    Light sun = test::directionalLight({0.5f, -1.0f, -0.3f}, 1.0f);
    sun.angularRadius = 0.3f;
    const Bounds3f room = realOnly.bounds();
    const glm::vec3 centre = rays.objectBounds.center();
    const float sphere = rays.boundingRadius();
    std::mt19937 random(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (const Light& light : {disk, hard, side, sun}) {
        const std::optional<std::vector<Bounds3f>> boxes = relitShadowVolume(std::span(&light, 1), rays);
        ASSERT_TRUE(boxes.has_value());
        int meeting = 0;
        for (int k = 0; k < 400000; ++k) {
            const glm::vec3 p =
                room.min + glm::vec3(unit(random), unit(random), unit(random)) * room.diagonal();
            bool meets;
            if (light.type == Light::Type::Directional) {
                // A direction within the cone: uniform over its solid angle.
                const float cosTheta = 1.0f - unit(random) * (1.0f - std::cos(light.angularRadius));
                const float phi = 2.0f * std::numbers::pi_v<float> * unit(random);
                const float sinTheta = std::sqrt(1.0f - cosTheta * cosTheta);
                const glm::vec3 w = frameAround(-light.direction) *
                                    glm::vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
                meets = rayMayMeetSphere(p, w, 100.0f, centre, sphere);
            } else {
                glm::vec3 offset;
                do offset = 2.0f * glm::vec3(unit(random), unit(random), unit(random)) - 1.0f;
                while (glm::dot(offset, offset) > 1.0f);
                meets = segmentMayMeetBox(p, light.position + light.radius * offset, 0.0f, rays.objectBounds);
            }
            if (!meets) continue;
            ++meeting;
            const bool inside =
                std::any_of(boxes->begin(), boxes->end(), [&](const Bounds3f& b) { return b.contains(p); });
            ASSERT_TRUE(inside) << "point " << p.x << ", " << p.y << ", " << p.z;
        }
        EXPECT_GT(meeting, 500);
    }
}
}  // namespace
}  // namespace deltagi
