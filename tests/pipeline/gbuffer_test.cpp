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

}  // namespace
}  // namespace deltagi
