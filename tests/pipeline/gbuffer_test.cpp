// The G-buffer's virtual half: coverage of the objects over each pixel's sub-samples, and the sub-samples'
// surfaces that the objects' direct light is shaded over.
#include "pipeline/gbuffer.h"

#include <gtest/gtest.h>

#include "test_scenes.h"

namespace deltagi {
namespace {

using test::diffuse;
using test::placed;

// A box in front of a floor, seen from above at 32 x 24: every pixel that shows it keeps its 2 x 2
// sub-samples' surfaces, as many valid ones as its coverage says, each the surface its own ray meets.
TEST(GBuffer, PixelsThatShowAnObjectKeepTheirSubSamplesSurfaces) {
    Scene scene = test::floorScene();
    scene.virtuals.push_back(
        placed(makeBox({0.6f, 0.2f, 0.6f}), {0, 0.1f, 0}, diffuse(glm::vec3(0.5f)), "box"));
    scene.camera = test::lookAtCamera({0.0f, 2.0f, 0.5f}, {0, 0, 0}, 32, 24, 60.0f);
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene all(scene, SceneContent::VirtualOnly, &realOnly);
    GBuffer g;
    renderObjectSurfaces(scene.camera, all, scene.virtuals[0].bounds(), 4, g);
    ASSERT_EQ(g.objectSamples.perPixel, 4);
    const int w = scene.camera.width;
    int inside = 0, edges = 0;
    for (int y = 0; y < scene.camera.height; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const std::span<const SurfacePoint> samples = g.objectSamples.of(i, w);
            int valid = 0;
            for (const SurfacePoint& s : samples) {
                if (!s.valid()) continue;
                ++valid;
                // On the box, and a sub-pixel away from the pixel's point.
                EXPECT_LE(glm::length(s.position - g.object[i].position), 0.2f);
                EXPECT_EQ(s.material, &scene.virtuals[0].material);
            }
            EXPECT_FLOAT_EQ(g.coverage[i], static_cast<float>(valid) / 4.0f) << x << ", " << y;
            if (valid == 4) {
                ++inside;
                // Four different points.
                EXPECT_NE(samples[0].position, samples[3].position);
            } else if (valid > 0) {
                ++edges;
            }
        }
    EXPECT_GT(inside, 20);
    EXPECT_GT(edges, 8);
    // One sample per pixel keeps none.
    renderObjectSurfaces(scene.camera, all, scene.virtuals[0].bounds(), 1, g);
    EXPECT_EQ(g.objectSamples.perPixel, 0);
    EXPECT_TRUE(g.objectSamples.of(static_cast<size_t>(12) * w + 16, w).empty());
}

// A red and white checker far finer than a pixel, on a box seen from above: every pixel inside the box shows
// the checker's mean, pink (1, 0.5, 0.5), at its centre (the mean of its sub-samples, each filtered over its
// quarter of the pixel) and at each sub-sample; a coarse checker keeps its squares apart.
TEST(GBuffer, TexturedPixelsShowTheTexturesMeanOverThePixel) {
    auto checkerBox = [](int squares, int texelsPerSquare) {
        const int size = squares * texelsPerSquare;
        std::vector<uint8_t> bytes;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const bool white = (x / texelsPerSquare + y / texelsPerSquare) % 2 == 0;
                bytes.insert(bytes.end(), {255, uint8_t(white ? 255 : 0), uint8_t(white ? 255 : 0), 255});
            }
        Material m = diffuse(glm::vec3(1.0f));
        m.baseColorTexture.texture =
            std::make_shared<const Texture>(size, size, std::move(bytes), TextureEncoding::Linear, "checker");
        return placed(makeBox({0.6f, 0.2f, 0.6f}), {0, 0.1f, 0}, m, "box");
    };
    Scene scene = test::floorScene();
    scene.camera = test::lookAtCamera({0.0f, 2.0f, 0.01f}, {0, 0, 0}, 32, 24, 60.0f);
    const int w = scene.camera.width;
    auto render = [&](const TriangleMesh& box, GBuffer& g) {
        scene.virtuals = {box};
        const RayScene realOnly(scene, SceneContent::RealOnly);
        const RayScene all(scene, SceneContent::VirtualOnly, &realOnly);
        renderObjectSurfaces(scene.camera, all, scene.virtuals[0].bounds(), 4, g);
        ASSERT_EQ(g.objectSamples.perPixel, 4);
    };
    // 256 squares across the box's top: about 30 to a pixel.
    GBuffer fine;
    render(checkerBox(256, 2), fine);
    int inside = 0;
    for (size_t i = 0; i < fine.object.size(); ++i) {
        if (fine.coverage[i] < 1.0f) continue;
        ++inside;
        const glm::vec3 centre = fine.object[i].surface.diffuse;
        EXPECT_NEAR(centre.x, 1.0f, 1e-4f) << i;
        EXPECT_NEAR(centre.y, 0.5f, 0.06f) << i;
        EXPECT_NEAR(centre.z, 0.5f, 0.06f) << i;
        for (const SurfacePoint& s : fine.objectSamples.of(i, w))
            EXPECT_NEAR(s.surface.diffuse.y, 0.5f, 0.1f);
    }
    EXPECT_GT(inside, 20);
    // 2 squares across: the pixels inside show red or white, not their mean.
    GBuffer coarse;
    render(checkerBox(2, 16), coarse);
    int red = 0, white = 0;
    for (size_t i = 0; i < coarse.object.size(); ++i) {
        if (coarse.coverage[i] < 1.0f) continue;
        const float g = coarse.object[i].surface.diffuse.y;
        red += g < 0.05f;
        white += g > 0.95f;
    }
    EXPECT_GT(red, 5);
    EXPECT_GT(white, 5);
}

}  // namespace
}  // namespace deltagi
