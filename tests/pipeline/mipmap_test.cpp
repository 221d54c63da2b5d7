#include "pipeline/mipmap.h"

#include <algorithm>
#include <cmath>
#include <limits>

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
    auto mean = [](const PackedGrid3& grid) {
        glm::dvec4 sum(0.0);
        for (size_t i = 0; i < grid.size(); ++i) sum += glm::dvec4(grid[i]);
        return sum / double(grid.size());
    };
    MipVolume mips = buildMipChain({glm::vec3(0), 1.0f, n}, std::move(g));
    ASSERT_EQ(mips.levelCount(), 4);
    EXPECT_EQ(mips.level(3).resolution(), 1);
    // Each level is rounded to bfloat16 once more: a relative error under 2^-8 of the largest value (21) a
    // level.
    const glm::dvec4 m0 = mean(mips.level(0));
    for (int l = 1; l < 4; ++l) {
        const glm::dvec4 m = mean(mips.level(l));
        for (int c = 0; c < 4; ++c)
            EXPECT_NEAR(m[c], m0[c], l * std::ldexp(21.0, -8)) << "level " << l << " channel " << c;
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
    EXPECT_FLOAT_EQ(v.sample({1.0f, 3.0f, 3.0f}, 0.5f).x,
                    0.5f * (v.sampleLevel({1.0f, 3.0f, 3.0f}, 0).x + 0.25f));
}

// Level 0 rewritten inside a box, and the chain updated above it only: the same bits as a chain built anew.
TEST(Mipmap, UpdatingTheLevelsAboveAChangedBoxEqualsRebuildingTheChain) {
    const int n = 16;
    const VolumeRegion region{glm::vec3(0), 1.0f, n};
    auto value = [](int x, int y, int z, float seed) {
        return glm::vec4(std::sin(seed * float(x + 3 * y)), float(z) * 0.1f + seed, 0.0f,
                         1.0f / float(1 + x));
    };
    Grid3 g(n);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) g.at(x, y, z) = value(x, y, z, 0.3f);
    MipVolume kept = buildMipChain(region, g.clone());
    // Odd corners, so that the box's parents straddle voxels at every level.
    for (const VoxelBox box : {VoxelBox{{3, 5, 1}, {9, 6, 14}}, VoxelBox{{0, 0, 0}, {1, 1, 1}},
                               VoxelBox{{15, 2, 7}, {16, 16, 8}}}) {
        for (int z = box.lo.z; z < box.hi.z; ++z)
            for (int y = box.lo.y; y < box.hi.y; ++y)
                for (int x = box.lo.x; x < box.hi.x; ++x) {
                    g.at(x, y, z) = value(x, y, z, 0.7f + float(box.lo.x));
                    kept.levelForUpdate(0).set(x, y, z, g.at(x, y, z));
                }
        updateMipChain(kept, box, VoxelBox::all(n));
        const MipVolume fresh = buildMipChain(region, g.clone());
        for (int l = 0; l < fresh.levelCount(); ++l)
            for (size_t i = 0; i < fresh.level(l).size(); ++i)
                ASSERT_EQ(kept.level(l).packed(i), fresh.level(l).packed(i))
                    << "level " << l << ", voxel " << i;
    }
}

// The mip volumes' voxels are 4 bfloat16: a float's upper half, rounded to nearest even.
TEST(PackedGrid3, KeepsAFloatsRangeAndEightSignificantBits) {
    EXPECT_EQ(fromBfloat16(toBfloat16(0.0f)), 0.0f);
    EXPECT_EQ(fromBfloat16(toBfloat16(1.0f)), 1.0f);
    EXPECT_EQ(fromBfloat16(toBfloat16(-255.0f)), -255.0f);                   // integers to 256 are exact
    EXPECT_EQ(fromBfloat16(toBfloat16(1.0f + std::ldexp(1.0f, -8))), 1.0f);  // a tie: to the even one
    EXPECT_EQ(fromBfloat16(toBfloat16(1.0f + 3.0f * std::ldexp(1.0f, -8))), 1.0f + std::ldexp(1.0f, -6));
    EXPECT_TRUE(std::isnan(fromBfloat16(toBfloat16(std::numeric_limits<float>::quiet_NaN()))));
    EXPECT_NEAR(fromBfloat16(toBfloat16(1e30f)), 1e30f, 1e30f * std::ldexp(1.0f, -8));
    EXPECT_GT(fromBfloat16(toBfloat16(1e-30f)), 0.0f);  // no flush to zero
    float worst = 0.0f;
    for (int k = 0; k < 100000; ++k) {
        const float v = std::ldexp(1.0f + static_cast<float>(k) / 100000.0f, k % 40 - 20);
        worst = std::max(worst, std::abs(fromBfloat16(toBfloat16(v)) - v) / v);
    }
    EXPECT_LE(worst, std::ldexp(1.0f, -8));
    EXPECT_GT(worst, std::ldexp(1.0f, -9));

    // A voxel's four values are packed as toBfloat16 packs each (SSE2 on x86-64).
    Grid3 g(2);
    g[3] = glm::vec4(0.1f, -2.5f, 1000.0f, 1e-3f);
    g[5] = glm::vec4(1.0f + std::ldexp(1.0f, -8), -(1.0f + 3.0f * std::ldexp(1.0f, -8)), -1e30f, 3e38f);
    const PackedGrid3 p(g);
    for (int i : {3, 5})
        for (int c = 0; c < 4; ++c) EXPECT_EQ(p[i][c], fromBfloat16(toBfloat16(g[i][c]))) << i << " " << c;
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(p[3][c], g[3][c], std::abs(g[3][c]) * std::ldexp(1.0f, -8));
    EXPECT_EQ(p[2], glm::vec4(0.0f));
    EXPECT_EQ(p.bytes(), 8u * 8u);
    const PackedGrid3 narrow(4, VoxelBox{{2, 0, 0}, {3, 4, 4}});  // one voxel wide: one zero voxel more
    EXPECT_EQ(narrow.bytes(), 8u * (16u + 1u));
    EXPECT_EQ(narrow.data()[16], PackedVoxel(0));
}

// Every lookup, near the borders and beyond them too, at every level and between levels, is the plain
// quadrilinear interpolation of the stored voxels with zero outside the grid (a reference read voxel by
// voxel): the lookup's branch-free corners and its two-voxel reads change nothing.
TEST(MipVolume, ALookupIsTheQuadrilinearInterpolationWithZeroOutside) {
    const int n = 8;
    auto filled = [&](const VoxelBox& box) {
        Grid3 g(n);
        for (int z = box.lo.z; z < box.hi.z; ++z)
            for (int y = box.lo.y; y < box.hi.y; ++y)
                for (int x = box.lo.x; x < box.hi.x; ++x) {
                    const float i = float(g.index(x, y, z));
                    g.at(x, y, z) =
                        glm::vec4(std::sin(0.7f * i), std::cos(1.3f * i), std::fmod(i, 5.0f), 1.0f);
                }
        return g;
    };
    const VolumeRegion region{glm::vec3(0), 1.0f, n};
    // Stored whole; over a window one voxel wide; over one two voxels wide at the grid's far side.
    const VoxelBox narrow{{3, 1, 2}, {4, 7, 8}}, edge{{6, 0, 1}, {8, 8, 5}};
    std::vector<MipVolume> volumes;
    volumes.push_back(buildMipChain(region, filled(VoxelBox::all(n))));
    volumes.push_back(buildMipChain(region, PackedGrid3(filled(narrow), narrow)));
    volumes.push_back(buildMipChain(region, PackedGrid3(filled(edge), edge)));
    for (const MipVolume& v : volumes) {
        auto trilinear = [&](glm::vec3 p, int l) {
            const PackedGrid3& level = v.level(l);
            const glm::vec3 q = p / float(1 << l) - 0.5f, base = glm::floor(q), f = q - base;
            glm::vec4 sum(0.0f);
            for (int k = 0; k < 8; ++k) {
                const glm::ivec3 c = glm::ivec3(base) + glm::ivec3(k & 1, (k >> 1) & 1, k >> 2);
                const bool inside = glm::all(glm::greaterThanEqual(c, glm::ivec3(0))) &&
                                    glm::all(glm::lessThan(c, glm::ivec3(level.resolution())));
                const float w =
                    (k & 1 ? f.x : 1 - f.x) * ((k >> 1) & 1 ? f.y : 1 - f.y) * (k >> 2 ? f.z : 1 - f.z);
                if (inside) sum += w * level.at(c.x, c.y, c.z);  // zero outside a window
            }
            return sum;
        };
        for (int k = 0; k < 4000; ++k) {
            const glm::vec3 p(std::fmod(k * 0.737f, 14.0f) - 3.0f, std::fmod(k * 0.291f, 14.0f) - 3.0f,
                              std::fmod(k * 0.533f, 14.0f) - 3.0f);
            const float level = std::fmod(k * 0.173f, 3.999f);
            const int l0 = static_cast<int>(level);
            const float blend = l0 < 3 ? level - float(l0) : 0.0f;  // none above the coarsest level
            const glm::vec4 expected =
                (1 - blend) * trilinear(p, l0) + (blend > 0 ? blend * trilinear(p, l0 + 1) : glm::vec4(0.0f));
            const glm::vec4 got = v.sample(p, level), one = v.sampleLevel(p, l0);
            const glm::vec4 expectedOne = trilinear(p, l0);
            for (int c = 0; c < 4; ++c) {
                ASSERT_NEAR(got[c], expected[c], 1e-5f) << k << " " << c;
                ASSERT_NEAR(one[c], expectedOne[c], 1e-5f) << k << " " << c;
            }
        }
    }
}

// A volume stored over a window around its non-zero voxels reads as the one stored whole: at every level,
// through its own lookups and through another volume's, and after an update in place.
TEST(MipVolume, AWindowedVolumeReadsAsTheWholeOne) {
    const int n = 16;
    const VolumeRegion region{glm::vec3(0), 1.0f, n};
    const VoxelBox filled{{5, 3, 7}, {9, 12, 10}}, window{{3, 2, 6}, {12, 14, 13}};
    Grid3 g(n);
    for (int z = filled.lo.z; z < filled.hi.z; ++z)
        for (int y = filled.lo.y; y < filled.hi.y; ++y)
            for (int x = filled.lo.x; x < filled.hi.x; ++x)
                g.at(x, y, z) = glm::vec4(float(x) * 0.1f, float(y) - 3.0f, std::sin(float(z)), 1.0f);
    MipVolume whole = buildMipChain(region, g);
    MipVolume windowed = buildMipChain(region, PackedGrid3(g, window));
    EXPECT_LT(windowed.bytes(), whole.bytes() / 4);
    auto expectSame = [&](const MipVolume& a, const MipVolume& b) {
        for (int k = 0; k < 2000; ++k) {
            const glm::vec3 p(std::fmod(k * 0.737f, 18.0f) - 1.0f, std::fmod(k * 0.291f, 18.0f) - 1.0f,
                              std::fmod(k * 0.533f, 18.0f) - 1.0f);
            const float level = std::fmod(k * 0.173f, 4.5f);
            const glm::vec4 u = a.sample(p, level), v = b.sample(p, level);
            const glm::vec4 w = b.gather(a.lookup(p, level));  // another volume's lookup
            for (int c = 0; c < 4; ++c) {
                ASSERT_NEAR(u[c], v[c], 1e-5f) << k;
                ASSERT_NEAR(u[c], w[c], 1e-5f) << k;
            }
        }
    };
    expectSame(whole, windowed);
    // Level 0 rewritten inside a box that reaches beyond the window, the chain updated above it.
    const VoxelBox changed{{6, 0, 8}, {16, 5, 9}};
    for (int z = changed.lo.z; z < changed.hi.z; ++z)
        for (int y = changed.lo.y; y < changed.hi.y; ++y)
            for (int x = changed.lo.x; x < changed.hi.x; ++x)
                if (window.contains(x, y, z)) g.at(x, y, z) = glm::vec4(2.0f);
    for (MipVolume* v : {&whole, &windowed}) {
        const VoxelBox box = changed.intersection(v->level(0).window());
        for (int z = box.lo.z; z < box.hi.z; ++z)
            for (int y = box.lo.y; y < box.hi.y; ++y)
                for (int x = box.lo.x; x < box.hi.x; ++x) v->levelForUpdate(0).set(x, y, z, g.at(x, y, z));
        updateMipChain(*v, box, nonZeroBounds(g, VoxelBox::all(n)));
    }
    expectSame(whole, windowed);
    EXPECT_EQ(windowed.level(0).at(0, 0, 0), glm::vec4(0.0f));  // outside the window
}

// The occupied bounds found by a scan, and a box's non-zero bounds.
TEST(MipVolume, OccupiedBoundsAreTheBoxOfTheNonZeroVoxels) {
    Grid3 g(8);
    g.at(2, 3, 4) = glm::vec4(0.0f, 0.0f, 0.0f, -1.0f);
    g.at(5, 1, 6) = glm::vec4(1.0f);
    const VoxelBox inner = nonZeroBounds(g, {{3, 0, 0}, {8, 8, 8}});
    EXPECT_EQ(inner.lo, glm::ivec3(5, 1, 6));
    EXPECT_EQ(inner.hi, glm::ivec3(6, 2, 7));
    EXPECT_TRUE(nonZeroBounds(g, {{0, 0, 0}, {2, 8, 8}}).empty());
    const MipVolume v = buildMipChain({glm::vec3(0), 1.0f, 8}, std::move(g));
    EXPECT_EQ(v.occupiedBounds().lo, glm::ivec3(2, 1, 4));
    EXPECT_EQ(v.occupiedBounds().hi, glm::ivec3(6, 4, 7));
    EXPECT_FALSE(v.mayReadNonZero({20.0f, 2.0f, 5.0f}, 0));
    EXPECT_TRUE(v.mayReadNonZero({3.0f, 2.0f, 5.0f}, 0));
}

// A packed grid's non-zero bounds read its bits: -0 counts as zero, the smallest value that survives the
// rounding does not; voxels outside its window are zero.
TEST(MipVolume, PackedNonZeroBoundsReadTheBits) {
    PackedGrid3 g(16, {{2, 2, 2}, {14, 12, 10}});
    g.set(3, 3, 3, glm::vec4(-0.0f, 0.0f, -0.0f, 0.0f));
    g.set(4, 5, 6, glm::vec4(0.0f, 0.0f, 1e-38f, 0.0f));
    g.set(12, 4, 8, glm::vec4(-2.0f, 0.0f, 0.0f, 0.0f));
    ASSERT_NE(g.at(4, 5, 6), glm::vec4(0.0f));
    const VoxelBox all = nonZeroBounds(g, VoxelBox::all(16));
    EXPECT_EQ(all.lo, glm::ivec3(4, 4, 6));
    EXPECT_EQ(all.hi, glm::ivec3(13, 6, 9));
    const VoxelBox part = nonZeroBounds(g, {{0, 0, 7}, {16, 16, 16}});
    EXPECT_EQ(part.lo, glm::ivec3(12, 4, 8));
    EXPECT_EQ(part.hi, glm::ivec3(13, 5, 9));
    EXPECT_TRUE(nonZeroBounds(g, {{0, 0, 0}, {4, 16, 16}}).empty());
    EXPECT_TRUE(nonZeroBounds(g, {{5, 5, 5}, {5, 9, 9}}).empty());
}

}  // namespace
}  // namespace deltagi
