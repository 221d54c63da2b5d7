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
    // Only they keep samples: the pixels of the objects' rectangle that show none and lie on no silhouette
    // take no memory.
    size_t kept = 0;
    for (size_t i = 0; i < g.object.size(); ++i) kept += g.objectSamples.of(i, w).size();
    EXPECT_EQ(g.objectSamples.points.size(), kept);
    const PixelRect& r = g.written;
    EXPECT_LT(kept, static_cast<size_t>(r.x1 - r.x0) * (r.y1 - r.y0) * 4);
    // One sample per pixel keeps none.
    renderObjectSurfaces(scene.camera, all, scene.virtuals[0].bounds(), 1, g);
    EXPECT_EQ(g.objectSamples.perPixel, 0);
    EXPECT_TRUE(g.objectSamples.of(static_cast<size_t>(12) * w + 16, w).empty());
}

// A glossy box seen obliquely: the pixels across an edge between two of its faces, whose 2 x 2 samples
// show the normal turn by 90 degrees, take the 8 x 8 grid (a highlight on either face may cover a part of the
// pixel the 2 x 2 samples miss); pixels inside a face keep 2 x 2, and a matte box has no finer grids at all.
TEST(GBuffer, GlossyPixelsWhoseNormalTurnsInsideThemTakeAFinerGrid) {
    Scene scene = test::floorScene();
    scene.camera = test::lookAtCamera({0.5f, 1.2f, 1.5f}, {0, 0.1f, 0}, 64, 48, 50.0f);
    const int w = scene.camera.width;
    Material glossy = diffuse(glm::vec3(0.2f));
    glossy.specular = glm::vec3(0.5f);
    glossy.roughness = 0.1f;  // Phong exponent 198
    auto render = [&](const Material& m, GBuffer& g) {
        scene.virtuals = {placed(makeBox({0.6f, 0.2f, 0.6f}), {0, 0.1f, 0}, m, "box")};
        const RayScene realOnly(scene, SceneContent::RealOnly);
        const RayScene all(scene, SceneContent::VirtualOnly, &realOnly);
        renderObjectSurfaces(scene.camera, all, scene.virtuals[0].bounds(), 4, g);
    };
    GBuffer g;
    render(glossy, g);
    ASSERT_EQ(g.objectSamples.finePerPixel, 64);
    int fine = 0, coarse = 0;
    for (size_t i = 0; i < g.object.size(); ++i) {
        const std::span<const SurfacePoint> samples = g.objectSamples.of(i, w);
        if (samples.empty() || g.coverage[i] < 1.0f) continue;
        float largestTurn = 0.0f;
        for (const SurfacePoint& a : samples)
            for (const SurfacePoint& b : samples)
                if (a.valid() && b.valid())
                    largestTurn = std::max(largestTurn, glm::length(a.normal - b.normal));
        if (samples.size() == 64) {
            ++fine;
            EXPECT_NEAR(largestTurn, std::sqrt(2.0f), 1e-3f) << i;  // two faces at right angles
            for (const SurfacePoint& s : samples)
                if (s.valid())  // seen through the pixel itself
                    EXPECT_EQ(test::project(scene.camera, s.position), glm::ivec2(i % w, i / w));
        } else {
            ASSERT_EQ(samples.size(), 4u);
            EXPECT_LE(largestTurn * largestTurn, 0.03f)
                << i;  // every pixel across an edge has the finer grid
            if (largestTurn == 0.0f) ++coarse;
        }
    }
    EXPECT_GE(fine, 10);
    EXPECT_GE(coarse, 20);
    GBuffer matte;
    render(diffuse(glm::vec3(0.2f)), matte);
    EXPECT_EQ(matte.objectSamples.finePerPixel, 0);
    EXPECT_TRUE(matte.objectSamples.fine.empty());
}

// A glazed ball seen whole in a still: its normal turns by a few degrees across a pixel, far less than across
// an edge, but by more than its narrow lobe is wide (Phong exponent 5,000: 0.017 rad), so that a highlight
// can fall between the 2 x 2 samples or on one of them: its pixels take the finer grid. A rougher ball's
// (exponent 198) keep their 2 x 2 samples away from its silhouette, and so do the glazed ball's in a
// session's frame (only turns of about 10 degrees and more there).
TEST(GBuffer, ANarrowLobesPixelsTakeTheFinerGridWhereTheNormalTurnsByMoreThanItsWidth) {
    Scene scene = test::floorScene();
    scene.camera = test::lookAtCamera({0.0f, 0.3f, 1.2f}, {0, 0.2f, 0}, 64, 48, 50.0f);
    const int w = scene.camera.width;
    auto fineShare = [&](float roughness, bool still = true) {
        Material m = diffuse(glm::vec3(0.1f));
        m.specular = glm::vec3(0.5f);
        m.roughness = roughness;
        scene.virtuals = {placed(makeSphere(0.2f, 256), {0, 0.2f, 0}, m, "ball")};
        const RayScene realOnly(scene, SceneContent::RealOnly);
        const RayScene all(scene, SceneContent::VirtualOnly, &realOnly);
        GBuffer g;
        renderObjectSurfaces(scene.camera, all, scene.virtuals[0].bounds(), 4, g, still);
        int fine = 0, inside = 0;
        for (size_t i = 0; i < g.object.size(); ++i) {
            if (!g.object[i].valid() || g.coverage[i] < 1.0f) continue;
            const std::span<const SurfacePoint> samples = g.objectSamples.of(i, w);
            // Well inside the silhouette: the normal turns by less than 10 degrees across the pixel.
            if (glm::dot(g.object[i].normal, g.object[i].toEye) < 0.5f) continue;
            ++inside;
            fine += samples.size() == 64 ? 1 : 0;
        }
        EXPECT_GT(inside, 150);
        return static_cast<float>(fine) / static_cast<float>(std::max(inside, 1));
    };
    EXPECT_GT(fineShare(0.02f), 0.9f);
    EXPECT_LT(fineShare(0.1f), 0.1f);
    EXPECT_EQ(fineShare(0.02f, false), 0.0f);
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
