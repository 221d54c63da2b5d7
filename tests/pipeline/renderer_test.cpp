// End-to-end properties of the Delta Global Illumination pipeline on small scenes built in code.
#include "deltagi/renderer.h"

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <map>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "io/atomic_file.h"
#include "io/image_output.h"
#include "scene/shapes.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;

using test::diffuse;
using test::placed;

Image patternImage(int w, int h) {
    Image img(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) img.setRgb(x, y, {0.01f * x, 0.02f * y, 0.3f + 0.001f * (x * y % 7)});
    return img;
}

void expectFinite(const Image& img) {
    for (float v : img.data()) ASSERT_TRUE(std::isfinite(v));
}

TEST(Render, NoVirtualObjectReturnsTheBackgroundExactly) {
    Scene s = test::floorScene();
    s.background = patternImage(s.camera.width, s.camera.height);
    RenderOutput out = render(s);
    ASSERT_EQ(out.composite.data().size(), s.background->data().size());
    for (size_t i = 0; i < out.composite.data().size(); ++i)
        ASSERT_EQ(out.composite.data()[i], s.background->data()[i]);
    for (float v : out.delta.data()) ASSERT_EQ(v, 0.0f);
    for (float v : out.objectMask.data()) ASSERT_EQ(v, 0.0f);
}

TEST(Render, WithoutAPhotoTheRealSceneIsRenderedAsBackground) {
    Scene s = test::floorScene();
    RenderOutput out = render(s);
    // The floor under the light: albedo/pi * I / d^2 = 0.5/pi * 2/2.25, plus a little indirect (none: a
    // plane).
    const glm::ivec2 p = test::project(s.camera, {0, 0, 0});
    const float expected = 0.5f / 3.14159265f * 2.0f / 2.25f;
    EXPECT_NEAR(out.background.rgb(p.x, p.y).x, expected, 0.05f * expected);
    EXPECT_EQ(out.composite.data()[0], out.background.data()[0]);
}

Scene sphereOverFloor() {
    Scene s = test::floorScene();
    s.virtuals.push_back(
        placed(makeSphere(0.2f, 32), {0.0f, 0.35f, 0.0f}, diffuse({0.7f, 0.7f, 0.7f}), "ball"));
    return s;
}

// The largest difference of two images' red channels over the brightest red of `b`.
float largestDifferenceOverBrightest(const Image& a, const Image& b) {
    float brightest = 0.0f, largest = 0.0f;
    for (int y = 0; y < b.height(); ++y)
        for (int x = 0; x < b.width(); ++x) {
            brightest = std::max(brightest, b.rgb(x, y).x);
            largest = std::max(largest, std::abs(a.rgb(x, y).x - b.rgb(x, y).x));
        }
    EXPECT_GT(brightest, 0.0f);
    return brightest > 0.0f ? largest / brightest : 1.0f;
}

// The background without a photo is rendered once per real scene with 16 times the shadow rays: its
// penumbrae are as smooth with the default 4 rays as with 64 (with 4 rays of its own, the soft shadow of a
// ball under a wide lamp came out blotchy: pixels 3.5 % of the lit floor's radiance apart; 0.4 % now).
TEST(Render, TheBackgroundsSoftShadowsDoNotDependOnTheRaysOfTheFrames) {
    Scene s = test::floorScene();
    s.real.push_back(placed(makeSphere(0.25f, 48), {0.0f, 0.5f, 0.0f}, diffuse(glm::vec3(0.5f)), "ball"));
    s.lights[0].radius = 0.4f;
    s.camera = test::lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, 320, 240, 60.0f);
    s.options.shadow.raySamples = 4;
    const Image few = render(s).background;
    s.options.shadow.raySamples = 64;
    const Image many = render(s).background;
    EXPECT_LT(largestDifferenceOverBrightest(few, many), 0.015f);
}

// ... and traces its diffuse cones 4 times as densely as the frames: a wall's bounce on the floor, rendered
// as the background at the frames' stride 8, is within 1.5 % of every pixel traced (1.25 %: the floor's map
// has about 3 texels across a voxel, and the voxels' share of them shows in the bounce; at stride 8 the
// interpolation showed as a grid of blocks, 2.1 % apart).
TEST(Render, TheBackgroundsIndirectLightIsTracedDensely) {
    Scene s = test::floorScene();
    TriangleMesh wall = makeQuad({2.0f, 2.0f});
    transformMesh(wall, glm::translate(glm::mat4(1.0f), glm::vec3(0, 1.0f, -0.5f)) *
                            glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(1, 0, 0)));
    wall.material = diffuse(glm::vec3(0.8f));
    s.real.push_back(wall);
    s.camera = test::lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, 320, 240, 60.0f);
    s.options.diffuse.pixelStride = 8;
    const Image sparse = render(s).background;
    s.options.diffuse.pixelStride = 1;
    const Image dense = render(s).background;
    EXPECT_LT(largestDifferenceOverBrightest(sparse, dense), 0.015f);
}

TEST(Render, TheObjectsShadowDarkensTheFloorUnderIt) {
    Scene s = sphereOverFloor();
    RenderOutput out = render(s);
    expectFinite(out.composite);
    // The floor point under the sphere, seen past it (the camera looks down at 45 degrees, so it is visible).
    const glm::ivec2 under = test::project(s.camera, {0.0f, 0.0f, 0.25f});
    ASSERT_EQ(out.objectMask.at(under.x, under.y, 0), 0.0f) << "the floor point must be visible";
    const glm::vec3 bg = out.background.rgb(under.x, under.y);
    const glm::vec3 d = out.delta.rgb(under.x, under.y);
    EXPECT_LT(d.x, -0.3f * bg.x);
    EXPECT_LT(d.y, 0.0f);
    EXPECT_LT(d.z, 0.0f);
    // The sphere itself is covered and lit.
    const glm::ivec2 ball = test::project(s.camera, {0.0f, 0.5f, 0.1f});
    EXPECT_EQ(out.objectMask.at(ball.x, ball.y, 0), 1.0f);
    EXPECT_GT(out.composite.rgb(ball.x, ball.y).x, 0.05f);
    // Composite never goes below zero, even on a black photo.
    s.background = Image(s.camera.width, s.camera.height, 3, 0.0f);
    RenderOutput black = render(s);
    for (float v : black.composite.data()) ASSERT_GE(v, 0.0f);
}

TEST(Render, AnObjectOutOfTheLightsReachChangesOnlyItsOwnPixels) {
    Scene s;
    s.real.push_back(placed(makeQuad({6.0f, 2.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    Light spot;
    spot.type = Light::Type::Spot;
    spot.position = {-2.0f, 1.5f, 0.0f};
    spot.direction = {0, -1, 0};
    spot.innerAngleDeg = 15.0f;
    spot.outerAngleDeg = 20.0f;
    spot.intensity = 3.0f;
    s.lights.push_back(spot);
    s.virtuals.push_back(
        placed(makeBox(glm::vec3(0.3f)), {2.0f, 0.15f, 0.0f}, diffuse({0.9f, 0.2f, 0.2f}), "box"));
    s.camera = test::lookAtCamera({0.0f, 2.5f, 3.0f}, {0, 0, 0}, 64, 48, 70.0f);
    s.options.volume.resolution = 32;
    s.options.rsm.resolution = 128;
    s.background = patternImage(64, 48);
    RenderOutput out = render(s);
    int objectPixels = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
            if (out.objectMask.at(x, y, 0) > 0.0f) {
                ++objectPixels;
                continue;
            }
            ASSERT_EQ(out.delta.rgb(x, y), glm::vec3(0.0f)) << x << "," << y;
        }
    EXPECT_GT(objectPixels, 0);
}

// A real table shadows the floor; a virtual ball under it must not darken that shadow again (§3.2).
Scene ballUnderTable() {
    Scene s = test::floorScene();
    s.real.push_back(
        placed(makeBox({1.0f, 0.05f, 1.0f}), {0.0f, 0.8f, 0.0f}, diffuse(glm::vec3(0.5f)), "table"));
    s.virtuals.push_back(
        placed(makeSphere(0.15f, 32), {0.0f, 0.15f, 0.0f}, diffuse(glm::vec3(0.7f)), "ball"));
    s.camera = test::lookAtCamera({0.0f, 0.5f, 1.8f}, {0, 0.1f, 0}, 64, 48, 60.0f);
    s.options.volume.center = glm::vec3(0.0f, 0.4f, 0.0f);
    s.options.volume.size = 1.2f;
    s.background = Image(64, 48, 3, 0.2f);
    return s;
}

TEST(Render, ARealSurfaceInARealShadowIsNotDarkenedAgain) {
    Scene s = ballUnderTable();
    const float unshadowed = 0.5f / 3.14159265f * 2.0f / 2.25f;  // direct light on the floor, were it lit
    auto meanDeltaNextToBall = [&](const RenderOutput& out) {
        double sum = 0.0;
        int count = 0;
        for (float x : {-0.3f, -0.25f, 0.25f, 0.3f}) {
            glm::ivec2 p = test::project(s.camera, {x, 0.0f, 0.1f});
            if (out.objectMask.at(p.x, p.y, 0) > 0.0f) continue;
            sum += out.delta.rgb(p.x, p.y).x;
            ++count;
        }
        EXPECT_GT(count, 0);
        return sum / count;
    };
    const double fixed = meanDeltaNextToBall(render(s));
    EXPECT_LT(std::abs(fixed), 0.1 * unshadowed);
    s.options.render.doubleShadowFix = false;  // one shared visibility: the double shadow of §3.2
    const double doubled = meanDeltaNextToBall(render(s));
    EXPECT_LT(doubled, -0.5 * unshadowed);
}

TEST(Render, ABrightObjectNextToAWhiteWallBleedsItsColourOntoIt) {
    Scene s;
    s.real.push_back(placed(makeQuad({2.0f, 2.0f}), {0, 0, 0}, diffuse(glm::vec3(0.8f)), "floor"));
    TriangleMesh wall = makeQuad({2.0f, 2.0f});
    transformMesh(wall, glm::translate(glm::mat4(1.0f), glm::vec3(0, 1.0f, -0.5f)) *
                            glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(1, 0, 0)));
    wall.material = diffuse(glm::vec3(0.8f));
    s.real.push_back(wall);
    s.virtuals.push_back(
        placed(makeBox(glm::vec3(0.4f)), {0.0f, 0.2f, -0.25f}, diffuse({0.9f, 0.1f, 0.05f}), "box"));
    s.lights.push_back(test::pointLight({1.0f, 1.0f, 0.5f}, 3.0f));
    s.camera = test::lookAtCamera({0.3f, 0.6f, 1.5f}, {0.0f, 0.2f, -0.5f}, 64, 48, 60.0f);
    s.options.volume.resolution = 32;
    s.options.rsm.resolution = 128;
    s.background = Image(64, 48, 3, 0.3f);
    RenderOutput out = render(s);
    const glm::ivec2 p = test::project(s.camera, {0.3f, 0.2f, -0.5f});
    ASSERT_EQ(out.objectMask.at(p.x, p.y, 0), 0.0f);
    const glm::vec3 d = out.delta.rgb(p.x, p.y);
    EXPECT_GT(d.x, 0.0f);
    EXPECT_GT(d.x, d.y + 0.002f);
    EXPECT_GT(d.x, d.z + 0.002f);
}

// The virtual objects' diffuse cones have an aperture of their own (options.diffuse.object_aperture_deg):
// it changes the objects' light and nothing of the real surfaces' change, which options.diffuse.aperture_deg
// does.
TEST(Render, TheObjectsConesHaveTheirOwnAperture) {
    Scene s = test::floorScene();
    s.virtuals.push_back(
        placed(makeBox(glm::vec3(0.4f)), {0.0f, 0.2f, 0.0f}, diffuse(glm::vec3(0.8f)), "box"));
    s.background = Image(64, 48, 3, 0.3f);
    auto differs = [](const Image& a, const Image& b) {
        const auto x = a.data(), y = b.data();
        return !std::equal(x.begin(), x.end(), y.begin(), y.end());
    };
    // The real surfaces' change: the delta where no object covers the pixel.
    auto realChange = [](const RenderOutput& out) {
        Image change = out.delta;
        for (int y = 0; y < change.height(); ++y)
            for (int x = 0; x < change.width(); ++x)
                if (out.objectMask.at(x, y, 0) > 0.0f) change.setRgb(x, y, glm::vec3(0.0f));
        return change;
    };
    // The relit cones carry the box's light on the floor (with "rays" only the floor's own change, which a
    // plane does not see).
    s.options.render.relightObjectLight = RelightObjectLight::Cones;
    s.options.diffuse.objectGatherRays = 0;  // the objects' cones, not rays
    s.options.diffuse.objectApertureDeg = 20.0f;
    const RenderOutput narrow = render(s);
    s.options.diffuse.objectApertureDeg = 70.0f;
    const RenderOutput wide = render(s);
    EXPECT_TRUE(differs(narrow.composite, wide.composite));
    EXPECT_FALSE(differs(realChange(narrow), realChange(wide)));
    s.options.diffuse.apertureDeg = 20.0f;
    EXPECT_TRUE(differs(realChange(render(s)), realChange(wide)));
}

// The compositing layers rebuild the composite, composite = object + (1 - alpha) max(background + shadow +
// indirect, 0), through a multi-layer EXR and back; the shadow layer is negative under the ball and zero
// where the ball covers the pixel; the depth is the floor's distance along the camera's axis.
TEST(Render, TheLayersRebuildTheComposite) {
    Scene s = test::floorScene();
    s.virtuals.push_back(
        placed(makeSphere(0.2f, 48), {0.0f, 0.3f, 0.0f}, diffuse({0.8f, 0.2f, 0.1f}), "ball"));
    s.background = Image(64, 48, 3, 0.3f);
    s.options.render.layers = true;
    const RenderOutput out = render(s);
    // Without the option, the same composite and no layers.
    Scene without = s;
    without.options.render.layers = false;
    const RenderOutput plain = render(without);
    EXPECT_TRUE(plain.object.empty() && plain.shadow.empty() && plain.depth.empty());
    for (size_t k = 0; k < out.composite.data().size(); ++k)
        ASSERT_NEAR(plain.composite.data()[k], out.composite.data()[k], 1e-6f);
    const fs::path file = fs::temp_directory_path() / ("deltagi_layers_" + std::to_string(getpid()) + ".exr");
    {
        AtomicFile atomic(file);
        writeLayers(compositingLayers(out), atomic);
        atomic.commit();
    }
    std::map<std::string, Image> layers;
    for (NamedImage& layer : readLayers(file)) layers[layer.name] = std::move(layer.image);
    fs::remove(file);
    ASSERT_EQ(layers.size(), 7u);
    const glm::vec3 eye = s.camera.position();
    const glm::vec3 axis = glm::normalize(s.camera.rayDirection(s.camera.cx, s.camera.cy));
    int shadowed = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
            const float alpha = layers["object"].at(x, y, 3);
            for (int k = 0; k < 3; ++k) {
                const float real = std::max(layers["background"].at(x, y, k) + layers["shadow"].at(x, y, k) +
                                                layers["indirect"].at(x, y, k),
                                            0.0f);
                EXPECT_NEAR(layers["object"].at(x, y, k) + (1.0f - alpha) * real, out.composite.at(x, y, k),
                            1e-5f)
                    << x << ", " << y;
            }
            EXPECT_EQ(alpha, out.objectMask.at(x, y, 0));
            if (alpha == 1.0f) EXPECT_EQ(layers["shadow"].rgb(x, y), glm::vec3(0.0f));
            if (alpha == 0.0f && layers["shadow"].at(x, y, 0) < -0.01f) ++shadowed;
            if (alpha == 0.0f) {  // the floor at y = 0
                const glm::vec3 dir = glm::normalize(s.camera.rayDirection(x + 0.5f, y + 0.5f));
                if (dir.y < 0.0f) {
                    const glm::vec3 p = eye + dir * (-eye.y / dir.y);
                    if (std::abs(p.x) < 0.99f && std::abs(p.z) < 0.99f)
                        EXPECT_NEAR(layers["depth"].at(x, y, 0), glm::dot(p - eye, axis), 1e-4f);
                }
            }
        }
    EXPECT_GT(shadowed, 20);
}

// The light an object blocks between two real surfaces: a red wall lights the floor in front of it; a
// black board stands between them, out of the lamp's way (it shadows neither the wall nor the floor point).
// The floor point loses the wall's red light. The paper's delta volume holds no change here (nothing the lamp
// lights is shadowed), so its cones see none; the differential cones (full light through both visibility
// volumes minus the scene's light through its own) do.
TEST(Render, AnObjectBlocksTheLightBouncingBetweenTwoRealSurfaces) {
    Scene s;
    s.real.push_back(placed(makeQuad({2.0f, 2.0f}), {0, 0, 0}, diffuse(glm::vec3(0.8f)), "floor"));
    TriangleMesh wall = makeQuad({1.0f, 2.0f});
    transformMesh(wall, glm::translate(glm::mat4(1.0f), glm::vec3(-0.5f, 0.5f, 0.0f)) *
                            glm::rotate(glm::mat4(1.0f), glm::radians(-90.0f), glm::vec3(0, 0, 1)));
    wall.material = diffuse({0.9f, 0.05f, 0.05f});
    s.real.push_back(wall);
    s.virtuals.push_back(
        placed(makeBox({0.05f, 0.6f, 0.8f}), {-0.2f, 0.35f, 0.0f}, diffuse(glm::vec3(0.0f)), "board"));
    s.lights.push_back(test::pointLight({0.6f, 1.5f, 0.0f}, 3.0f));
    s.camera = test::lookAtCamera({0.8f, 0.8f, 0.8f}, {0.1f, 0.0f, 0.0f}, 64, 48, 60.0f);
    s.options.volume.resolution = 32;
    s.options.volume.center = glm::vec3(0.0f, 0.5f, 0.0f);
    s.options.volume.size = 1.2f;
    s.options.rsm.resolution = 128;
    s.background = Image(64, 48, 3, 0.3f);
    const glm::ivec2 p = test::project(s.camera, {0.15f, 0.0f, 0.0f});
    s.options.render.relightCones = RelightCones::Differential;
    const RenderOutput differential = render(s);
    s.options.render.relightCones = RelightCones::DeltaVolume;
    const RenderOutput deltaVolume = render(s);
    ASSERT_EQ(differential.objectMask.at(p.x, p.y, 0), 0.0f);
    const glm::vec3 a = differential.delta.rgb(p.x, p.y), b = deltaVolume.delta.rgb(p.x, p.y);
    EXPECT_LT(a.x, -0.01f) << "the wall's red light is blocked";
    EXPECT_LT(a.x, a.y - 0.005f);
    EXPECT_GT(b.x, 0.3f * a.x) << "the delta volume holds (almost) none of it";
}

// The default region reaches the real surfaces that light the object: a ball hanging over a lit floor gets
// the floor's light on its lower half, which no direct light reaches. The paper's region (twice the ball's
// box, reach_scale 0) stops short of the floor, and the lower half went black.
TEST(Render, TheDefaultVolumeReachesTheFloorUnderAHangingBall) {
    Scene s = test::floorScene();
    s.real[0] = placed(makeQuad({4.0f, 4.0f}), {0, 0, 0}, diffuse(glm::vec3(0.8f)), "floor");
    s.virtuals.push_back(placed(makeSphere(0.2f, 48), {0, 0.5f, 0}, diffuse(glm::vec3(0.8f)), "ball"));
    s.camera = test::lookAtCamera({0.0f, 0.25f, 1.6f}, {0.0f, 0.45f, 0.0f}, 64, 48, 40.0f);
    s.background = Image(64, 48, 3, 0.3f);
    // A point on the ball's lower front, facing down and towards the camera.
    const glm::vec3 lower = glm::vec3(0, 0.5f, 0) + 0.2f * glm::normalize(glm::vec3(0, -0.6f, 1.0f));
    const glm::ivec2 p = test::project(s.camera, lower);
    const RenderOutput reaching = render(s);
    ASSERT_GT(reaching.objectMask.at(p.x, p.y, 0), 0.99f);
    const VolumeRegion region = volumeRegion(s);
    EXPECT_LE(region.origin.y, 0.0f) << "the region holds the floor";
    s.options.volume.reachScale = 0.0f;
    EXPECT_GT(volumeRegion(s).origin.y, 0.0f) << "twice the ball's box does not";
    const RenderOutput paper = render(s);
    const float bounced = reaching.composite.at(p.x, p.y, 0), cut = paper.composite.at(p.x, p.y, 0);
    EXPECT_GT(bounced, 0.02f);
    EXPECT_GT(bounced, 2.0f * cut);
}

TEST(Render, ResultDoesNotDependOnTheThreadCount) {
    auto run = [](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        Scene s = sphereOverFloor();
        s.options.specular.minApertureDeg = 10.0f;
        s.real[0].material.specular = glm::vec3(0.3f);
        s.real[0].material.albedo = glm::vec3(0.5f);
        s.real[0].material.roughness = 0.3f;
        // A glazed ball in the big one's penumbra under a sphere light: its finer grids and its glossy
        // pixels' shadows (glossyShadowOcclusion) too.
        s.lights[0].radius = 0.2f;
        Material glaze = diffuse(glm::vec3(0.1f));
        glaze.specular = glm::vec3(0.5f);
        glaze.roughness = 0.05f;
        s.virtuals.push_back(placed(makeSphere(0.08f, 64), {0.27f, 0.08f, 0.0f}, glaze, "glaze"));
        return render(s);
    };
    RenderOutput a = run(1), b = run(2);
    for (size_t i = 0; i < a.composite.data().size(); ++i)
        ASSERT_EQ(a.composite.data()[i], b.composite.data()[i]);
    for (size_t i = 0; i < a.background.data().size(); ++i)
        ASSERT_EQ(a.background.data()[i], b.background.data()[i]);
}

}  // namespace
}  // namespace deltagi
