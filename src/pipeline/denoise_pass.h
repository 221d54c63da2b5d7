// One pass of the edge-aware filter (denoise.cpp): what it reads, the neighbours' weights and the filter of
// one pixel over its window, shared by the one-pixel code (denoise.cpp) and the filter in lanes
// (denoise_lanes.h). Internal to denoise.cpp.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "pipeline/denoise.h"

namespace deltagi::denoise_pass {

// x^n for a float or, lane by lane, a vector of them (interpolationWeights, the filter in lanes: always
// inlined, so that it is compiled for their instruction set).
template <typename T>
[[gnu::always_inline]] inline T powInt(T x, int n) {
    if (n == 16) {  // the filter's normal power: the loop's own squarings, unrolled (the same bits)
        x *= x;
        x *= x;
        x *= x;
        return x * x;
    }
    T r = T{} + 1.0f;
    for (; n > 0; n >>= 1, x *= x)
        if (n & 1) r *= x;
    return r;
}

// The filter's sample at a point (invalid where the pass holds no value there: `traced` false).
inline FilterSample filterSampleOf(const SurfacePoint& q, bool traced = true) {
    return {q.position, q.normal, q.valid() && traced};
}

// Everything one filter pass reads, shared by its rows.
struct FilterPass {
    std::span<float> values;
    int channels;
    std::span<const SurfacePoint> points;
    int width, height;
    glm::vec3 eye;
    float pixelAngle;
    const DenoiseSettings& s;
    int r, stride, reach, side;
    // The grid of samples the pass keeps: (ox, oy) its first, sw x sh of them. The whole image's without a
    // rectangle or with a plan (built over the whole image); else the rectangle's samples and one more on
    // each side, which hold every window centre of its pixels (the samples outside the rectangle are never
    // valid, so that leaving them out changes no weight).
    int ox, oy, sw, sh;
    std::vector<float> spatial{};       // (2r+1)^2 window weights
    std::vector<float> offsetLength{};  // sqrt(px^2 + py^2 + 1) for every pixel offset a window can have
    std::vector<float> fraction{};      // d / stride for d in [0, stride): a pixel's place between samples
    std::vector<FilterSample> samples{};
    std::vector<float> sampleValues{};
    // Per window centre ((sw + 1) x (sh + 1): a centre may lie one past the last sample): whether any sample
    // of its window holds a non-zero value. A window of zeros filters to zero, whatever its weights.
    std::vector<uint8_t> windowHasValue{};

    // Sample (sx, sy) of the image's stride grid in the kept grid, and window centre (cx, cy).
    size_t sampleIndex(int sx, int sy) const { return static_cast<size_t>(sy - oy) * sw + (sx - ox); }
    size_t centreIndex(int cx, int cy) const { return static_cast<size_t>(cy - oy) * (sw + 1) + (cx - ox); }
    // How far a neighbour may lie off the tangent plane of the surface at `position`, per unit of
    // offsetLength: settings.planeDistance pixel sizes there.
    float planeAllowance(glm::vec3 position) const {
        return s.planeDistance * pixelAngle * glm::length(position - eye);
    }
    // Whether the pixels between the samples are interpolated from them (settings.interpolate at a stride).
    bool interpolates() const { return stride > 1 && s.interpolate; }
    // offsetLength's entry for sample (sx, sy) seen from pixel (x, y).
    size_t offsetIndex(int sx, int sy, int x, int y) const {
        return static_cast<size_t>(sy * stride - y + reach) * side + sx * stride - x + reach;
    }
};

// Whether sample k is a usable neighbour of pixel p: on the same side, near p's tangent plane. Returns its
// weight (0: not usable) without the spatial factor.
// The test of both (surfaceWeight too): a point at `position` with `normal` against p.
inline float sameSurfaceWeight(const SurfacePoint& p, glm::vec3 position, glm::vec3 normal, float allowance,
                               int normalPower) {
    const float cosN = glm::dot(p.normal, normal);
    if (cosN <= 0.0f) return 0.0f;
    // Off the tangent plane by more than the allowance: another surface (a depth edge).
    if (std::abs(glm::dot(p.normal, position - p.position)) > allowance) return 0.0f;
    return powInt(cosN, normalPower);
}
inline float neighbourWeight(const FilterPass& f, const SurfacePoint& p, const FilterSample& q,
                             float allowance) {
    return q.valid ? sameSurfaceWeight(p, q.position, q.normal, allowance, f.s.normalPower) : 0.0f;
}

// The edge-aware filter at pixel (x, y), whose surface is p, from the samples of its window, into `dst`.
// Returns false, leaving `dst` alone, when no sample is usable (a hole). C is the channel count when known at
// compile time (0: f.channels).
template <int C>
bool filterPixel(const FilterPass& f, int x, int y, const SurfacePoint& p, float* dst) {
    const int channels = C > 0 ? C : f.channels;
    std::array<float, (C > 0 ? C : 1)> fixedSum{};
    std::vector<float> dynamicSum(C > 0 ? 0 : channels);
    float* sum = C > 0 ? fixedSum.data() : dynamicSum.data();
    const int r = f.r, stride = f.stride;
    // The samples nearest to the pixel (below and right of it when between two): the window's centre.
    const int xCentre = (x + stride / 2) / stride, yCentre = (y + stride / 2) / stride;
    const int sxBegin = std::max(xCentre - r, f.ox), sxEnd = std::min(xCentre + r, f.ox + f.sw - 1);
    const int syBegin = std::max(yCentre - r, f.oy), syEnd = std::min(yCentre + r, f.oy + f.sh - 1);
    const float planeAllowance = f.planeAllowance(p.position);
    auto allowance = [&](int sx, int sy) {
        return planeAllowance * f.offsetLength[f.offsetIndex(sx, sy, x, y)];
    };
    if (!f.windowHasValue[f.centreIndex(xCentre, yCentre)]) {
        // All zeros: the result is zero if any sample is usable, else the pixel is a hole.
        for (int sy = syBegin; sy <= syEnd; ++sy)
            for (int sx = sxBegin; sx <= sxEnd; ++sx)
                if (neighbourWeight(f, p, f.samples[f.sampleIndex(sx, sy)], allowance(sx, sy)) > 0.0f) {
                    std::fill_n(dst, channels, 0.0f);
                    return true;
                }
        return false;
    }
    std::fill_n(sum, channels, 0.0f);
    float weightSum = 0.0f;
    for (int sy = syBegin; sy <= syEnd; ++sy) {
        const float* spatialRow = &f.spatial[static_cast<size_t>(sy - yCentre + r) * (2 * r + 1)];
        for (int sx = sxBegin; sx <= sxEnd; ++sx) {
            const size_t k = f.sampleIndex(sx, sy);
            float w = neighbourWeight(f, p, f.samples[k], allowance(sx, sy));
            if (w == 0.0f) continue;
            w *= spatialRow[sx - xCentre + r];
            const float* v = &f.sampleValues[k * channels];
            for (int c = 0; c < channels; ++c) sum[c] += v[c] * w;
            weightSum += w;
        }
    }
    if (!(weightSum > 0.0f)) return false;
    for (int c = 0; c < channels; ++c) dst[c] = sum[c] / weightSum;
    return true;
}

}  // namespace deltagi::denoise_pass
