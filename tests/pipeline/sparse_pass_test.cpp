// Sparse passes (src/pipeline/sparse_pass.h): the refinement of the cells where the samples change sharply.
#include "pipeline/sparse_pass.h"

#include <cmath>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

namespace deltagi {
namespace {

constexpr int kW = 128, kH = 64;

// A floor seen from above, one point per pixel 1 cm apart, and on it a narrow dip of the traced value (a
// contact shadow's core, 8 pixels wide) at `centre`, a sample of the stride, and a shallower one at (24, 32),
// on a slow ramp.
struct Floor {
    Material material;
    std::vector<SurfacePoint> points;
    Camera camera;
    glm::vec2 centre{64.0f, 32.0f};

    Floor() {
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) {
                SurfacePoint p;
                p.material = &material;
                p.surface = constantSurfaceMaterial(material);
                p.position = {0.01f * x, 0.0f, 0.01f * y};
                p.normal = {0, 1, 0};
                p.toEye = {0, 1, 0};
                points.push_back(p);
            }
        camera.width = kW, camera.height = kH;
        camera.fx = camera.fy = 100.0f;
        camera.worldFromCamera = glm::translate(glm::mat4(1.0f), glm::vec3(0.64f, 1.0f, 0.32f));
    }
    float truth(size_t i) const {
        const glm::vec2 d = glm::vec2(static_cast<float>(i % kW), static_cast<float>(i / kW)) - centre;
        const glm::vec2 e = d + centre - glm::vec2(24.0f, 32.0f);  // a shallower dip
        return 0.2f + 0.001f * static_cast<float>(i % kW) - 0.8f * std::exp(-glm::dot(d, d) / 32.0f) -
               0.3f * std::exp(-glm::dot(e, e) / 32.0f);
    }
    // The pass at stride 8, with `refine`; `traced` counts the pixels traced.
    std::vector<float> pass(const SparseRefinement& refine, size_t& traced) const {
        DenoiseSettings filter;
        filter.radius = 1;
        filter.interpolate = true;
        traced = 0;
        return traceSparse<float>(
            points, PixelRect{0, 0, kW, kH}, camera, 8, 1, filter,
            [&](std::span<const uint32_t> pixels) {
                std::vector<float> out(points.size(), 0.0f);
                for (uint32_t i : pixels) out[i] = truth(i);
                traced += pixels.size();
                return out;
            },
            refine);
    }
};

TEST(SparsePass, SharpCellsAreTracedAgainAtAQuarterOfTheStride) {
    const Floor floor;
    const size_t dip = static_cast<size_t>(32) * kW + 64;
    size_t coarseTraced = 0, refinedTraced = 0;
    const std::vector<float> coarse = floor.pass({}, coarseTraced);
    const std::vector<float> refined = floor.pass({0.05f}, refinedTraced);
    // Between the samples 8 pixels apart the dip is all but lost; refined, its core is there.
    EXPECT_GT(coarse[dip] - floor.truth(dip), 0.4f);
    EXPECT_NEAR(refined[dip], floor.truth(dip), 0.25f);
    float worstNear = 0.0f;
    for (int y = 27; y < 38; ++y)
        for (int x = 59; x < 70; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            worstNear = std::max(worstNear, std::abs(refined[i] - floor.truth(i)));
        }
    EXPECT_LT(worstNear, 0.3f);
    // Away from the dips (the ramp: no cell is sharp) nothing changes, bit for bit.
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            if ((std::abs(x - 64) > 24 || std::abs(y - 32) > 24) &&
                (std::abs(x - 24) > 24 || std::abs(y - 32) > 24)) {
                const size_t i = static_cast<size_t>(y) * kW + x;
                ASSERT_EQ(refined[i], coarse[i]) << x << "," << y;
            }
    // The fine samples (every 2nd pixel of every 2nd row) in the budget's cells, and in the margin of 4
    // pixels around them that the fine filter reads (at most 3 times as many again, for a lone cell).
    EXPECT_GT(refinedTraced, coarseTraced);
    EXPECT_LE(refinedTraced - coarseTraced, static_cast<size_t>(4 * 0.05f * kW * kH));
}

// The budget takes the sharpest cells first: with room for four cells, those next to the deep dip, among the
// cells a budget for all of them refines (the shallow dip's too).
TEST(SparsePass, TheBudgetTakesTheSharpestCellsFirst) {
    const Floor floor;
    size_t coarseTraced = 0, fewTraced = 0, allTraced = 0;
    const std::vector<float> coarse = floor.pass({}, coarseTraced);
    const std::vector<float> few = floor.pass({64.0f / (kW * kH)}, fewTraced);
    const std::vector<float> all = floor.pass({1.0f}, allTraced);
    EXPECT_LT(fewTraced, allTraced);
    int changed = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const size_t i = static_cast<size_t>(y) * kW + x;
            if (few[i] == coarse[i]) continue;
            ++changed;
            EXPECT_LE(std::abs(x - 64), 16) << x << "," << y;
            EXPECT_LE(std::abs(y - 32), 16) << x << "," << y;
            EXPECT_NE(all[i], coarse[i]) << x << "," << y;
        }
    EXPECT_GE(changed, 4 * 8 * 8 * 3 / 4);  // four cells' pixels, but where the fine result matches
    const size_t shallow = static_cast<size_t>(32) * kW + 24;
    EXPECT_EQ(few[shallow], coarse[shallow]);
    EXPECT_NE(all[shallow], coarse[shallow]);
}

}  // namespace
}  // namespace deltagi
