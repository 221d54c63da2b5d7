// The path tracer's sample values (src/core/sampler.h): each dimension stratified over a pixel's samples,
// pixels and dimensions uncorrelated, copies in step, and integrals converging faster than with independent
// random numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/rng.h"
#include "core/sampler.h"

namespace deltagi {
namespace {

// The first `n` samples of dimension `dimension` (requests before it are 2D ones) of pixel `pixel`.
std::vector<glm::vec2> points2(uint64_t pixel, int dimension, int n, uint64_t seed = 0) {
    std::vector<glm::vec2> out;
    for (int i = 0; i < n; ++i) {
        Sampler s(pixel, static_cast<uint64_t>(i), seed);
        for (int d = 0; d < dimension; ++d) s.uniform2();
        out.push_back(s.uniform2());
    }
    return out;
}

TEST(Sampler, The1DValuesOf2PowerKSamplesFillEachOf2PowerKIntervalsOnce) {
    for (uint64_t pixel : {0ull, 17ull, 123456ull})
        for (int dimension = 0; dimension < 6; ++dimension) {
            std::vector<int> count(256, 0);
            for (int i = 0; i < 256; ++i) {
                Sampler s(pixel, static_cast<uint64_t>(i), 3);
                for (int d = 0; d < dimension; ++d) s.uniform();
                const float u = s.uniform();
                ASSERT_GE(u, 0.0f);
                ASSERT_LT(u, 1.0f);
                ++count[static_cast<int>(u * 256.0f)];
            }
            for (int c : count) ASSERT_EQ(c, 1) << "pixel " << pixel << " dimension " << dimension;
        }
}

// A (0,2)-sequence: 2^k points fill every elementary interval of area 2^-k (2^a x 2^b cells, a + b = k) once.
TEST(Sampler, The2DValuesFillEveryElementaryIntervalOnce) {
    constexpr int k = 8, n = 1 << k;
    for (uint64_t pixel : {0ull, 99ull})
        for (int dimension = 0; dimension < 4; ++dimension) {
            const std::vector<glm::vec2> points = points2(pixel, dimension, n, 5);
            for (int a = 0; a <= k; ++a) {
                const int cellsX = 1 << a, cellsY = 1 << (k - a);
                std::vector<int> count(n, 0);
                for (glm::vec2 p : points)
                    ++count[static_cast<int>(p.y * cellsY) * cellsX + static_cast<int>(p.x * cellsX)];
                for (int c : count) ASSERT_EQ(c, 1) << "cells " << cellsX << " x " << cellsY;
            }
        }
}

// Pixels, seeds and dimensions get different points, without correlation between them.
TEST(Sampler, PixelsSeedsAndDimensionsAreUncorrelated) {
    constexpr int n = 1024;
    const std::vector<glm::vec2> a = points2(5, 0, n), b = points2(6, 0, n), c = points2(5, 0, n, 1),
                                 d = points2(5, 1, n);
    auto correlation = [](const std::vector<glm::vec2>& p, const std::vector<glm::vec2>& q, int ci, int cj) {
        double sum = 0.0, sp = 0.0, sq = 0.0, spp = 0.0, sqq = 0.0;
        for (size_t i = 0; i < p.size(); ++i) {
            const double x = p[i][ci], y = q[i][cj];
            sum += x * y;
            sp += x;
            sq += y;
            spp += x * x;
            sqq += y * y;
        }
        const double m = static_cast<double>(p.size());
        return (sum / m - sp * sq / (m * m)) /
               std::sqrt((spp / m - sp * sp / (m * m)) * (sqq / m - sq * sq / (m * m)));
    };
    EXPECT_NE(a[0], b[0]);
    EXPECT_NE(a[0], c[0]);
    EXPECT_NE(a[0], d[0]);
    // Over 1024 pairs the correlation of independent values is about +-0.03.
    for (const auto* other : {&b, &c, &d})
        for (int ci = 0; ci < 2; ++ci)
            for (int cj = 0; cj < 2; ++cj) EXPECT_LT(std::abs(correlation(a, *other, ci, cj)), 0.12);
    EXPECT_LT(std::abs(correlation(a, a, 0, 1)), 0.12);  // x and y of one dimension
}

// A copy goes on with the same values as the original: the two paths of the differential path tracer.
TEST(Sampler, ACopyGoesOnInStep) {
    Sampler s(3, 7, 11);
    s.uniform();
    s.uniform2();
    Sampler copy = s;
    for (int i = 0; i < 5; ++i) {
        EXPECT_EQ(s.uniform(), copy.uniform());
        EXPECT_EQ(s.uniform2(), copy.uniform2());
    }
}

// Integrating a smooth 4D function (a pixel's position and a light's point) over 256 samples: the error
// averaged over pixels is well below that of independent random numbers (about a quarter: each pair is
// stratified, their product only as well as a Latin hypercube), and the estimate unbiased.
TEST(Sampler, IntegratesWithLessErrorThanIndependentNumbers) {
    // f = (x + y^2) * (1 + cos(2 pi u) * v): its integral over [0,1]^4 is (1/2 + 1/3) * 1.
    auto f = [](glm::vec2 p, glm::vec2 q) {
        return (p.x + p.y * p.y) * (1.0f + std::cos(6.2831853f * q.x) * q.y);
    };
    constexpr double exact = 0.5 + 1.0 / 3.0;
    constexpr int pixels = 200, n = 256;
    double sobolSquared = 0.0, randomSquared = 0.0, sobolMean = 0.0;
    for (int pixel = 0; pixel < pixels; ++pixel) {
        double sobolSum = 0.0, randomSum = 0.0;
        for (int i = 0; i < n; ++i) {
            Sampler s(static_cast<uint64_t>(pixel), static_cast<uint64_t>(i), 0);
            const glm::vec2 p = s.uniform2(), q = s.uniform2();
            sobolSum += f(p, q);
            Rng r(static_cast<uint64_t>(pixel), static_cast<uint64_t>(i), 0);
            const glm::vec2 rp(r.uniform(), r.uniform()), rq(r.uniform(), r.uniform());
            randomSum += f(rp, rq);
        }
        sobolSquared += std::pow(sobolSum / n - exact, 2);
        randomSquared += std::pow(randomSum / n - exact, 2);
        sobolMean += sobolSum / n / pixels;
    }
    const double sobolRmse = std::sqrt(sobolSquared / pixels), randomRmse = std::sqrt(randomSquared / pixels);
    EXPECT_LT(sobolRmse, 0.5 * randomRmse) << sobolRmse << " vs " << randomRmse;
    // Unbiased: the mean over pixels is within a few of its standard errors of the exact value.
    EXPECT_NEAR(sobolMean, exact, 4.0 * sobolRmse / std::sqrt(pixels));
}

}  // namespace
}  // namespace deltagi
