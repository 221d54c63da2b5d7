#include "mipmap.h"

#include <gtest/gtest.h>

namespace deltagi {
namespace {

TEST(Mipmap, EachLevelKeepsTheMeanAndOcclusionBecomesTheFilledFraction) {
    const int n = 8;
    Grid3 g(n);
    // One filled voxel in the first 2x2x2 block, and a gradient elsewhere.
    g.at(0, 0, 0) = glm::vec4(1.0f, 0.0f, 1.0f, 0.0f);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 4; x < n; ++x) g.at(x, y, z) = glm::vec4(0.0f, float(x + y + z), 0.0f, 1.0f);
    auto mean = [](const Grid3& grid) {
        glm::dvec4 sum(0.0);
        for (size_t i = 0; i < grid.size(); ++i) sum += glm::dvec4(grid[i]);
        return sum / double(grid.size());
    };
    const glm::dvec4 m0 = mean(g);
    MipVolume mips = buildMipChain({glm::vec3(0), 1.0f, n}, std::move(g));
    ASSERT_EQ(mips.levelCount(), 4);
    EXPECT_EQ(mips.level(3).resolution(), 1);
    for (int l = 1; l < 4; ++l) {
        const glm::dvec4 m = mean(mips.level(l));
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(m[c], m0[c], 1e-5) << "level " << l << " channel " << c;
    }
    EXPECT_FLOAT_EQ(mips.level(1).at(0, 0, 0).x, 0.125f);  // 1 of 8 sub-voxels filled
}

TEST(MipVolume, TrilinearSampleIsExactAtVoxelCentresAndZeroOutside) {
    Grid3 g(4);
    g.at(1, 2, 3) = glm::vec4(2.0f);
    MipVolume v = buildMipChain({glm::vec3(0), 1.0f, 4}, std::move(g));
    EXPECT_EQ(v.sampleLevel({1.5f, 2.5f, 3.5f}, 0), glm::vec4(2.0f));
    EXPECT_EQ(v.sampleLevel({2.0f, 2.5f, 3.5f}, 0), glm::vec4(1.0f));  // half way to an empty neighbour
    EXPECT_EQ(v.sampleLevel({-3.0f, 0.5f, 0.5f}, 0), glm::vec4(0.0f));
    // Level 1 voxel (0,1,1) holds the mean of its 8 children: 2/8.
    EXPECT_FLOAT_EQ(v.sampleLevel({1.0f, 3.0f, 3.0f}, 1).x, 0.25f);
    // Between levels, quadrilinear blending.
    EXPECT_FLOAT_EQ(v.sample({1.0f, 3.0f, 3.0f}, 0.5f).x, 0.5f * (v.sampleLevel({1.0f, 3.0f, 3.0f}, 0).x + 0.25f));
}

}  // namespace
}  // namespace deltagi
