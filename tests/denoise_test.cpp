#include "denoise.h"

#include <cmath>

#include <gtest/gtest.h>

#include "cone_trace.h"

namespace deltagi {
namespace {

// A 32 x 16 view of two surfaces: the left half a floor (normal +y), the right half a wall (normal +x).
struct Fixture {
    static constexpr int kW = 32, kH = 16;
    Material material;
    std::vector<SurfacePoint> points;
    Fixture() {
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) {
                SurfacePoint p;
                p.material = &material;
                p.toEye = {0, 0, 1};
                if (x < kW / 2) {
                    p.position = {0.01f * x, 0.0f, 0.01f * y};
                    p.normal = {0, 1, 0};
                } else {
                    p.position = {0.16f, 0.01f * (x - kW / 2), 0.01f * y};
                    p.normal = {1, 0, 0};
                }
                points.push_back(p);
            }
    }
};

TEST(Denoise, KeepsConstantsReducesNoiseAndDoesNotMixSurfaces) {
    Fixture f;
    std::vector<float> values(f.points.size());
    for (size_t i = 0; i < values.size(); ++i) {
        const bool wall = (i % Fixture::kW) >= Fixture::kW / 2;
        values[i] = (wall ? 1.0f : 0.0f) + 0.2f * (hashToUnit(i, 0) - 0.5f);  // two levels plus noise
    }
    const glm::vec3 eye(0.1f, 1.0f, 0.1f);
    const std::vector<float> out =
        denoise(values, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, DenoiseSettings{});
    double noiseIn = 0.0, noiseOut = 0.0;
    for (size_t i = 0; i < values.size(); ++i) {
        const bool wall = (i % Fixture::kW) >= Fixture::kW / 2;
        const float level = wall ? 1.0f : 0.0f;
        noiseIn += std::pow(values[i] - level, 2.0);
        noiseOut += std::pow(out[i] - level, 2.0);
        // The pixels next to the crease keep their own surface's level: nothing leaks across.
        EXPECT_NEAR(out[i], level, 0.1f) << i;
    }
    EXPECT_LT(noiseOut, 0.25 * noiseIn);
    // A constant stays exactly constant (up to rounding).
    std::vector<float> constant(f.points.size(), 0.7f);
    for (float v : denoise(constant, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, DenoiseSettings{}))
        EXPECT_NEAR(v, 0.7f, 1e-6f);
    // Radius 0 is the identity.
    EXPECT_EQ(denoise(values, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, DenoiseSettings{0}), values);
}

}  // namespace
}  // namespace deltagi
