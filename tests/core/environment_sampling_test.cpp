// The environment map's importance sampling (src/core/environment_sampling.h): a sample lands in the pixel
// that inverting the map's row and column CDFs gives (the guided search is exact, empty rows and columns
// skipped), its pdf and radiance are the map's there, and the centre of its pixel lies within pixelRadius()
// of it (what the relit shadow rays cull by, src/pipeline/area_light_rays.cpp).
#include <tuple>

#include <glm/gtc/matrix_transform.hpp>

#include "core/environment.h"
#include "core/environment_sampling.h"
#include "core/sampling.h"

namespace deltagi {
namespace {

// Every pixel's red channel names it (1 + its index), green carries the weight; some rows and columns black.
Environment numberedMap(int width, int height) {
    Environment e;
    e.radiance = Image(width, height, 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const bool black = y % 5 == 3 || x % 7 == 2;
            const float weight = black ? 0.0f : 1.0f + static_cast<float>((x * 31 + y * 17) % 13);
            e.radiance.setRgb(x, y, {black ? 0.0f : static_cast<float>(1 + y * width + x), weight, 0.0f});
        }
    e.worldFromEnvironment =
        glm::mat3(glm::rotate(glm::mat4(1.0f), 0.7f, glm::normalize(glm::vec3(1, 2, 3))));
    return e;
}

// The pixel sample(u1, u2) must land in: the last row whose cdf is at most u1, then the last column of that
// row's cdf at most u2 (the CDFs built as the sampler documents them: mean radiance times solid angle).
glm::ivec2 invertedPixel(const Image& map, double u1, double u2) {
    const int w = map.width(), h = map.height();
    auto mean = [&](int x, int y) {
        const glm::vec3 l = map.rgb(x, y);
        return (l.x + l.y + l.z) / 3.0f;
    };
    std::vector<double> rows(h + 1, 0.0);
    for (int y = 0; y < h; ++y) {
        double row = 0.0;
        for (int x = 0; x < w; ++x) row += mean(x, y);
        rows[y + 1] = rows[y] + row * equirectPixelSolidAngle(y, w, h);
    }
    int y = 0;
    for (int k = 0; k < h; ++k)
        if (rows[k] / rows[h] <= u1) y = k;
    std::vector<double> columns(w + 1, 0.0);
    for (int x = 0; x < w; ++x) columns[x + 1] = columns[x] + mean(x, y);
    int x = 0;
    for (int k = 0; k < w; ++k)
        if (columns[k] / columns[w] <= u2) x = k;
    return {x, y};
}

TEST(EnvironmentSamplingTest, LandsWhereTheCdfsSayWithTheMapsPdfAndRadiance) {
    for (const auto [width, height, sun] :
         {std::tuple{16, 8, false}, std::tuple{64, 32, false}, std::tuple{100, 37, false},
          std::tuple{100, 37, true}, std::tuple{256, 128, true}}) {
        Environment map = numberedMap(width, height);
        // A sun: one pixel with most of the light, the others' share a few bins of the CDFs.
        if (sun)
            map.radiance.setRgb(width / 3, height / 4, {1.0f + (height / 4) * width + width / 3, 1e6f, 0.0f});
        const EnvironmentSampler sampler(map);
        constexpr int kSide = 48;
        for (int i = 0; i <= kSide; ++i)
            for (int j = 0; j <= kSide; ++j) {
                // The grid's own points (u * n exactly a bin's edge) and points inside the cells.
                for (const float jitter : {0.0f, 0.37f}) {
                    const float u1 = std::min((static_cast<float>(i) + jitter) / kSide, 0.99999994f);
                    const float u2 = std::min((static_cast<float>(j) + jitter) / kSide, 0.99999994f);
                    const EnvironmentSampler::Sample s = sampler.sample(u1, u2);
                    const glm::ivec2 p = invertedPixel(map.radiance, u1, u2);
                    ASSERT_EQ(s.radiance.x, static_cast<float>(1 + p.y * width + p.x))
                        << width << "x" << height << " u " << u1 << " " << u2;
                    EXPECT_GT(s.pdf, 0.0f);
                    // The map looked up at the centre of the sample's pixel (a direction on a pixel's edge
                    // may round into its neighbour).
                    const glm::vec3 centre = sampler.pixelCentre(sampler.pixelOf(u1, u2));
                    const EnvironmentSampler::Value value = sampler.value(centre);
                    EXPECT_EQ(value.radiance, s.radiance);
                    EXPECT_EQ(value.pdf, s.pdf);
                    EXPECT_EQ(sampler.pdf(centre), s.pdf);
                    EXPECT_EQ(sampler.radiance(centre), s.radiance);
                    const float angle = std::acos(std::clamp(glm::dot(centre, s.wi), -1.0f, 1.0f));
                    EXPECT_LE(angle, sampler.pixelRadius());
                }
            }
    }
}

// The row of a sample bounds its pixel centre's angle to any direction from below by the difference of their
// elevations in the map's frame (what the relit shadow rays cull whole rows by before looking up the column):
// the row's elevation is its pixel centres' own, and no centre is nearer a direction than that difference.
TEST(EnvironmentSamplingTest, ARowsElevationBoundsItsPixelCentresAngleToADirection) {
    const Environment map = numberedMap(64, 32);
    const EnvironmentSampler sampler(map);
    std::vector<glm::vec3> directions;
    for (int k = 0; k < 40; ++k) {
        const float z = 1.0f - 2.0f * (static_cast<float>(k) + 0.5f) / 40.0f, phi = 2.3999632f * k;
        const float r = std::sqrt(1.0f - z * z);
        directions.push_back({r * std::cos(phi), z, r * std::sin(phi)});
    }
    constexpr int kSide = 32;
    for (int i = 0; i < kSide; ++i)
        for (int j = 0; j < kSide; ++j) {
            const float u1 = (static_cast<float>(i) + 0.37f) / kSide,
                        u2 = (static_cast<float>(j) + 0.61f) / kSide;
            const glm::vec3 centre = sampler.pixelCentre(sampler.pixelOf(u1, u2));
            const float row = sampler.rowElevation(sampler.rowOf(u1));
            ASSERT_NEAR(sampler.elevationOf(centre), row, 1e-5f) << u1 << " " << u2;
            for (const glm::vec3& d : directions) {
                const float angle = std::acos(std::clamp(glm::dot(centre, d), -1.0f, 1.0f));
                EXPECT_GE(angle, std::abs(row - sampler.elevationOf(d)) - 1e-4f);
            }
        }
}

// A map lit above its horizon only (a fish-eye light camera's): value() is the map's own pixel for every
// direction, those just above and below the lowest lit row's bottom edge included, which value() passes over
// as dark without finding their pixel.
TEST(EnvironmentSamplingTest, AValueBelowTheLowestLitRowIsThePixelsOwn) {
    for (const int litRows : {1, 9, 16}) {
        Environment map = numberedMap(64, 32);
        for (int y = litRows; y < 32; ++y)
            for (int x = 0; x < 64; ++x) map.radiance.setRgb(x, y, glm::vec3(0.0f));
        const EnvironmentSampler sampler(map);
        // The bottom edge of the lowest lit row, in the map's frame.
        const float edge = static_cast<float>(std::sin(equirectRowElevation(litRows, 32)));
        int checked = 0;
        for (int k = 0; k < 4000; ++k) {
            // Directions spread over the sphere, and many within 1e-3 of the edge in y.
            const float phi = 2.3999632f * static_cast<float>(k);
            const float y = k % 2 == 0 ? 1.0f - 2.0f * (static_cast<float>(k) + 0.5f) / 4000.0f
                                       : edge + 1e-3f * (static_cast<float>(k % 200) / 100.0f - 1.0f);
            const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
            const glm::vec3 local(r * std::cos(phi), y, r * std::sin(phi));
            const glm::vec3 world = map.worldFromEnvironment * local;
            const EnvironmentSampler::Value value = sampler.value(world);
            ASSERT_EQ(value.radiance, sampler.radiance(world)) << litRows << " " << k;
            ASSERT_EQ(value.pdf, sampler.pdf(world)) << litRows << " " << k;
            checked += value.radiance != glm::vec3(0.0f);
        }
        EXPECT_GT(checked, 100);
    }
}

// A cone the sampler calls dark has no light anywhere in it (directions over its whole disk of directions and
// its rim); a cone that reaches a lit row is not dark, one below it by more than the margin is.
TEST(EnvironmentSamplingTest, ADarkConeHoldsNoLight) {
    Environment map = numberedMap(64, 32);
    for (int y = 16; y < 32; ++y)  // lit above the horizon only
        for (int x = 0; x < 64; ++x) map.radiance.setRgb(x, y, glm::vec3(0.0f));
    const EnvironmentSampler sampler(map);
    const glm::mat3 world = map.worldFromEnvironment;
    auto direction = [](float elevation, float azimuth) {
        return glm::vec3(std::cos(elevation) * std::sin(azimuth), std::sin(elevation),
                         -std::cos(elevation) * std::cos(azimuth));
    };
    EXPECT_TRUE(sampler.darkCone(world * direction(-0.8f, 1.0f), 0.3f));
    EXPECT_FALSE(sampler.darkCone(world * direction(-0.2f, 1.0f), 0.3f));  // reaches above the horizon
    EXPECT_FALSE(sampler.darkCone(world * direction(-1.5f, 2.0f), 1.6f));  // over the nadir and beyond
    EXPECT_FALSE(sampler.darkCone(world * direction(0.5f, 0.0f), 0.01f));
    int dark = 0;
    for (int k = 0; k < 400; ++k) {
        const float elevation = -1.5f + 1.6f * static_cast<float>(k % 20) / 20.0f;
        const float halfAngle = 0.02f + 0.05f * static_cast<float>(k / 20);
        const glm::vec3 axis = world * direction(elevation, 0.37f * static_cast<float>(k));
        if (!sampler.darkCone(axis, halfAngle)) continue;
        ++dark;
        const glm::mat3 frame = frameAround(axis);
        for (int j = 0; j < 64; ++j) {
            const float theta = halfAngle * (j < 32 ? static_cast<float>(j % 8) / 7.0f : 1.0f);
            const float phi = 2.0f * 3.14159265f * static_cast<float>(j) / 32.0f;
            const glm::vec3 wi =
                glm::normalize(frame * glm::vec3(std::sin(theta) * std::cos(phi),
                                                 std::sin(theta) * std::sin(phi), std::cos(theta)));
            ASSERT_EQ(sampler.value(wi).radiance, glm::vec3(0.0f)) << k << " " << j;
        }
    }
    EXPECT_GT(dark, 50);
}

// A map too dark to sample gives no sample, and a pdf of 0 everywhere.
TEST(EnvironmentSamplingTest, ABlackMapGivesNoSample) {
    Environment black;
    black.radiance = Image(8, 4, 3);
    const EnvironmentSampler sampler(black);
    EXPECT_EQ(sampler.sample(0.3f, 0.6f).pdf, 0.0f);
    EXPECT_EQ(sampler.value(glm::vec3(0, 1, 0)).pdf, 0.0f);
}

}  // namespace
}  // namespace deltagi
