// Emitting surfaces as area lights of the DGI pipeline (options.shadow.method "rays"): their direct light
// against the closed form of a rectangle's irradiance, and the shadow a virtual object casts from one.
#include "pipeline/area_light_rays.h"

#include <cmath>
#include <cstring>
#include <numbers>

#include <gtest/gtest.h>

#include "deltagi/renderer.h"
#include "relit_surfaces.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

using test::diffuse;
using test::floorPoint;
using test::placed;

constexpr float kPi = std::numbers::pi_v<float>;

// The form factor from a point to a parallel a x b rectangle at height h whose corner lies straight above
// it (Siegel & Howell): the irradiance is pi L F for a rectangle of radiance L.
float cornerFormFactor(float a, float b, float h) {
    const float x = a / h, y = b / h;
    const float sx = std::sqrt(1.0f + x * x), sy = std::sqrt(1.0f + y * y);
    return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2.0f * kPi);
}

// A 0.4 x 0.4 panel of radiance 5 at height 1 over a white-ish floor, facing down, and a floor point under
// its centre.
Scene panelScene() {
    Scene s;
    s.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    TriangleMesh panel = makeQuad({0.4f, 0.4f});
    transformMesh(panel, glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.0f, 0.0f)) *
                             glm::rotate(glm::mat4(1.0f), kPi, glm::vec3(1, 0, 0)));
    panel.material = diffuse(glm::vec3(0.5f));
    panel.material.emission = glm::vec3(5.0f);
    panel.name = "panel";
    s.real.push_back(panel);
    s.camera = test::lookAtCamera({0.0f, 1.4f, 1.6f}, {0, 0, 0}, 96, 72, 60.0f);
    s.options.volume.resolution = 32;
    s.options.rsm.resolution = 128;
    s.options.diffuse.count = 6;
    return s;
}

TEST(AreaLightRays, APanelLightsAPointWithTheRectanglesClosedFormIrradiance) {
    const Scene scene = panelScene();
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const AreaLights emitters(scene, SceneContent::RealOnly);
    Options options;
    options.shadow.areaRaySamples = 256;
    const std::vector<SurfacePoint> points = {floorPoint({0, 0, 0}, scene.real[0].material),
                                              floorPoint({0.2f, 0, 0.2f}, scene.real[0].material)};
    const auto light =
        traceAreaLightRays(points, emitters, {&realOnly, nullptr, {}}, options, ShadowMode::SceneOnly);
    // Under the centre: four 0.2 x 0.2 corner rectangles; under a corner: one 0.4 x 0.4.
    const float centre = 0.5f / kPi * kPi * 5.0f * 4.0f * cornerFormFactor(0.2f, 0.2f, 1.0f);
    const float corner = 0.5f / kPi * kPi * 5.0f * cornerFormFactor(0.4f, 0.4f, 1.0f);
    EXPECT_NEAR(light[0].x, centre, 0.02f * centre);
    EXPECT_NEAR(light[1].x, corner, 0.03f * corner);
}

// A virtual box hanging under the panel: the floor under it loses all of the panel's light (the change is
// minus the light), a point far to the side keeps it (no change), and a shaded point on the box's top gets
// the panel's light.
TEST(AreaLightRays, AnObjectUnderThePanelShadowsTheFloor) {
    Scene scene = panelScene();
    scene.virtuals.push_back(
        placed(makeBox({0.6f, 0.02f, 0.6f}), {0, 0.5f, 0}, diffuse(glm::vec3(0.5f)), "lid"));
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene objects(scene, SceneContent::VirtualOnly, &realOnly);
    const AreaLights emitters(scene, SceneContent::RealAndVirtual);
    const ShadowRayScenes rays{&realOnly, &objects, scene.virtuals[0].bounds()};
    Options options;
    const Material& m = scene.real[0].material;
    const std::vector<SurfacePoint> points = {floorPoint({0, 0, 0}, m), floorPoint({1.8f, 0, 1.8f}, m)};
    const auto unshadowed =
        traceAreaLightRays(points, emitters, {&realOnly, nullptr, {}}, options, ShadowMode::SceneOnly);
    const auto change = traceAreaLightRays(points, emitters, rays, options, ShadowMode::DeltaShadow);
    EXPECT_GT(unshadowed[0].x, 0.1f);
    EXPECT_NEAR(change[0].x, -unshadowed[0].x, 1e-6f);
    EXPECT_EQ(change[1].x, 0.0f);
    const std::vector<SurfacePoint> top = {floorPoint({0, 0.511f, 0}, scene.virtuals[0].material)};
    const auto shaded = traceAreaLightRays(top, emitters, rays, options, ShadowMode::Shaded);
    EXPECT_GT(shaded[0].x, 0.5f * 0.5f / kPi * kPi * 5.0f * 4.0f * cornerFormFactor(0.2f, 0.2f, 0.49f));
}

// End to end: an object under an emitting panel darkens the floor below it. DGI used to leave the real scene
// exactly unchanged under area light (emitters cast no shadows).
TEST(AreaLightRays, AnObjectCastsAShadowFromAnEmittingPanelEndToEnd) {
    Scene scene = panelScene();
    scene.virtuals.push_back(placed(makeSphere(0.12f, 48), {0, 0.3f, 0}, diffuse(glm::vec3(0.5f)), "ball"));
    scene.background = Image(scene.camera.width, scene.camera.height, 3, 0.3f);
    const RenderOutput out = render(scene);
    const glm::ivec2 under = test::project(scene.camera, {0.0f, 0.0f, 0.12f});
    ASSERT_EQ(out.objectMask.at(under.x, under.y, 0), 0.0f);
    EXPECT_LT(out.delta.at(under.x, under.y, 0), -0.02f);
    scene.options.shadow.method = ShadowMethod::Cones;
    const RenderOutput cones = render(scene);
    EXPECT_GT(cones.delta.at(under.x, under.y, 0), out.delta.at(under.x, under.y, 0));
}

// The emitters' relit pass runs over the image rectangle of the objects' shadow volume from the panel
// (relitEmitterRect): every floor pixel whose light from the panel the ball changes lies in it, it is smaller
// than the image, and the sparse pass over it with its margin gives the bits of the pass over the whole
// image. An emitting object lights the room wherever it shines: the whole image.
TEST(AreaLightRays, TheRelitEmittersRectangleHoldsEveryPixelTheObjectsChange) {
    Scene scene = panelScene();
    scene.real[0] = placed(makeQuad({6.0f, 6.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor");
    // A wider panel, higher up: a wide penumbra.
    TriangleMesh& panel = scene.real[1];
    transformMesh(panel, glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.5f, 0.0f)) *
                             glm::scale(glm::mat4(1.0f), glm::vec3(2.5f, 1.0f, 2.5f)) *
                             glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, -1.0f, 0.0f)));
    scene.virtuals.push_back(
        placed(makeSphere(0.05f, 48), {0.2f, 0.6f, 0.1f}, diffuse(glm::vec3(0.5f)), "ball"));
    scene.camera = test::lookAtCamera({0.0f, 1.4f, 2.2f}, {0, 0, 0}, 160, 120, 70.0f);
    const test::RelitSurfaces relit(scene);
    const AreaLights emitters(scene, SceneContent::RealAndVirtual);
    Options options;
    options.shadow.areaRaySamples = 16;
    auto trace = [&](std::span<const uint32_t> pixels) {
        return traceAreaLightRays(relit.points, emitters, relit.rays, options, ShadowMode::DeltaShadow,
                                  pixels);
    };
    const PixelRect rect = relitEmitterRect(scene.camera, emitters, relit.rays, relit.image, 0);
    EXPECT_GT(relit.changedPixels(trace({}), 1, rect, "panel"), 100);
    EXPECT_TRUE(relit.smallerThan(rect, 0.5f));
    DenoiseSettings filter;
    filter.interpolate = true;
    const int stride = 2;
    const PixelRect bounds =
        relitEmitterRect(scene.camera, emitters, relit.rays, relit.image, sparsePassMargin(stride, filter));
    EXPECT_TRUE(relit.sameAsWholeImage<glm::vec3>(bounds, stride, 1, filter, trace));

    scene.virtuals[0].material.emission = glm::vec3(1.0f);
    const AreaLights glowing(scene, SceneContent::RealAndVirtual);
    const PixelRect lit = relitEmitterRect(scene.camera, glowing, relit.rays, relit.image, 0);
    EXPECT_TRUE(lit.x0 == 0 && lit.y0 == 0 && lit.x1 == scene.camera.width && lit.y1 == scene.camera.height);
}

// The stand-in light of a panel set under a ceiling faces down only, carries the panel's power (L A per
// steradian) and sits just off the panel.
TEST(AreaLightRays, APanelUnderACeilingGetsOneStandInFacingDown) {
    Scene scene = panelScene();
    TriangleMesh ceiling = makeQuad({4.0f, 4.0f});
    transformMesh(ceiling, glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.0005f, 0.0f)));
    ceiling.material = diffuse(glm::vec3(0.5f));
    scene.real.push_back(ceiling);
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const std::vector<Light> lights = emitterStandInLights(scene, realOnly);
    ASSERT_EQ(lights.size(), 1u);
    EXPECT_TRUE(lights[0].lambertian);
    EXPECT_NEAR(lights[0].direction.y, -1.0f, 1e-5f);
    EXPECT_NEAR(lights[0].power().x, 5.0f * 0.16f, 1e-4f);
    EXPECT_NEAR(lights[0].position.y, 1.0f, 0.01f);
}

// Under a uniform environment of radiance L, an open floor point reflects albedo L (its irradiance is pi L);
// under a lid that hides the whole sky, a relit point loses all of it, and a shaded point gets none.
TEST(EnvironmentRays, AUniformSkyGivesAlbedoTimesItsRadianceAndALidTakesItAway) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.virtuals.push_back(
        placed(makeBox({4.0f, 0.02f, 4.0f}), {0, 0.1f, 0}, diffuse(glm::vec3(0.5f)), "lid"));
    Environment environment;
    environment.radiance = Image(64, 32, 3, 0.7f);
    const EnvironmentSampler sampler(environment);
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene objects(scene, SceneContent::VirtualOnly, &realOnly);
    const ShadowRayScenes rays{&realOnly, &objects, scene.virtuals[0].bounds()};
    Options options;
    options.shadow.areaRaySamples = 256;
    const std::vector<SurfacePoint> points = {floorPoint({0, 0, 0}, scene.real[0].material)};
    const auto open =
        traceEnvironmentRays(points, sampler, {&realOnly, nullptr, {}}, options, ShadowMode::SceneOnly);
    EXPECT_NEAR(open[0].x, 0.5f * 0.7f, 0.02f * 0.35f);
    const auto change = traceEnvironmentRays(points, sampler, rays, options, ShadowMode::DeltaShadow);
    EXPECT_NEAR(change[0].x, -0.35f, 0.02f * 0.35f);
    const auto shaded = traceEnvironmentRays(points, sampler, rays, options, ShadowMode::Shaded);
    EXPECT_NEAR(shaded[0].x, 0.0f, 0.02f * 0.35f);
}

// A point's environment rays are tested against the scene first while the scene blocks them (walls), against
// the objects first once it does not (open ground), and each answer is that of both tests, in either order:
// a wall at x = 1 hides the sky towards +x, a ball sits straight above the point.
TEST(EnvironmentRays, TheOcclusionTestsOrderFollowsTheSceneAndAnswersAsBothTests) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.real.push_back(
        placed(makeBox({0.1f, 4.0f, 4.0f}), {1.0f, 2.0f, 0}, diffuse(glm::vec3(0.5f)), "wall"));
    scene.virtuals.push_back(placed(makeSphere(0.3f, 32), {0, 1.0f, 0}, diffuse(glm::vec3(0.5f)), "ball"));
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene objects(scene, SceneContent::VirtualOnly, &realOnly);
    const glm::vec3 origin(0.0f, 1e-3f, 0.0f);
    const glm::vec3 up(0, 1, 0), wallward = glm::normalize(glm::vec3(1, 0.5f, 0)),
                                 open = glm::normalize(glm::vec3(-1, 0.5f, 0.3f));
    auto check = [&](EnvironmentOcclusion& occlusion, glm::vec3 wi) {
        const bool byObjects = objects.occludedTopLayer(origin, wi), byScene = realOnly.occluded(origin, wi);
        EXPECT_EQ(occlusion.objectsOnly(wi), byObjects && !byScene);
        EXPECT_EQ(occlusion.either(wi, true), byObjects || byScene);
        EXPECT_EQ(occlusion.either(wi, false), byScene);
    };
    ASSERT_TRUE(objects.occludedTopLayer(origin, up) && !realOnly.occluded(origin, up));
    ASSERT_TRUE(realOnly.occluded(origin, wallward) && !objects.occludedTopLayer(origin, wallward));
    ASSERT_TRUE(!realOnly.occluded(origin, open) && !objects.occludedTopLayer(origin, open));

    // Open sky: the scene first for the first rays, then the objects first.
    EnvironmentOcclusion ground(&objects, realOnly, origin);
    EXPECT_TRUE(ground.sceneFirst());
    for (int k = 0; k < 4; ++k) check(ground, k % 2 ? up : open);
    EXPECT_FALSE(ground.sceneFirst());
    for (int k = 0; k < 8; ++k) check(ground, k % 2 ? up : open);
    // Rays the wall blocks: the scene first again.
    for (int k = 0; k < 8; ++k) check(ground, wallward);
    EXPECT_TRUE(ground.sceneFirst());
    for (const glm::vec3 wi : {up, open, wallward, up}) check(ground, wi);
}

// A ball of radius r at height d over a floor point under a uniform sky L takes away the sky of its cap:
// albedo L sin^2(a) cos(t) with sin(a) = r / d and t the cap's tilt from the normal. Relit points sample the
// cap's cone besides the map (multiple importance sampling): each point within 30 % with the default 16 rays.
// By the map's samples alone, about one point in six had a ray that met the ball: a speckled shadow.
TEST(EnvironmentRays, ARelitPointSamplesTheObjectsConeOfDirections) {
    Scene scene;
    scene.real.push_back(placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    scene.virtuals.push_back(placed(makeSphere(0.1f, 96), {0, 0.5f, 0}, diffuse(glm::vec3(0.5f)), "ball"));
    Environment environment;
    environment.radiance = Image(64, 32, 3, 0.7f);
    const EnvironmentSampler sampler(environment);
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene objects(scene, SceneContent::VirtualOnly, &realOnly);
    const ShadowRayScenes rays{&realOnly, &objects, scene.virtuals[0].bounds(),
                               objectSphereRadius(scene.virtuals)};
    const Options options;  // 16 rays
    std::vector<SurfacePoint> points;
    for (int i = 0; i < 256; ++i)
        points.push_back(
            floorPoint({0.001f * static_cast<float>(i % 16), 0, 0.001f * static_cast<float>(i / 16)},
                       scene.real[0].material));
    const auto change = traceEnvironmentRays(points, sampler, rays, options, ShadowMode::DeltaShadow);
    double sum = 0.0, expectedSum = 0.0;
    for (size_t i = 0; i < points.size(); ++i) {
        const glm::vec3 toBall = glm::vec3(0, 0.5f, 0) - points[i].position;
        const float distance = glm::length(toBall);
        const float sin2 = 0.01f / (distance * distance);
        const float expected = -0.5f * 0.7f * sin2 * (toBall.y / distance);
        EXPECT_NEAR(change[i].x, expected, 0.3f * std::abs(expected)) << "point " << i;
        sum += change[i].x;
        expectedSum += expected;
    }
    EXPECT_NEAR(sum, expectedSum, 0.02 * std::abs(expectedSum));
}

}  // namespace
}  // namespace deltagi
