#include "denoise.h"

#include <algorithm>
#include <cmath>

#include "parallel.h"

namespace deltagi {

namespace {

float powInt(float x, int n) {
    float r = 1.0f;
    for (; n > 0; n >>= 1, x *= x)
        if (n & 1) r *= x;
    return r;
}

}  // namespace

std::vector<float> denoise(std::span<const float> values, int channels, std::span<const SurfacePoint> points,
                           int width, int height, glm::vec3 eye, float pixelAngle, const DenoiseSettings& s,
                           std::vector<size_t>* holes) {
    std::vector<float> out(values.begin(), values.end());
    if (s.radius <= 0 || channels <= 0) return out;
    const int r = s.radius, stride = std::max(s.stride, 1);
    std::vector<float> spatial(2 * r + 1);
    for (int d = -r; d <= r; ++d)
        spatial[d + r] = std::exp(-0.5f * d * d / (s.spatialSigma * s.spatialSigma));
    // sqrt(px^2 + py^2 + 1) for every pixel offset a window can have.
    const int reach = (r + 1) * stride, side = 2 * reach + 1;
    std::vector<float> offsetLength(static_cast<size_t>(side) * side);
    for (int py = -reach; py <= reach; ++py)
        for (int px = -reach; px <= reach; ++px)
            offsetLength[static_cast<size_t>(py + reach) * side + px + reach] =
                std::sqrt(static_cast<float>(px * px + py * py + 1));

    // The samples (every stride-th pixel of every stride-th row) packed together, for the cache.
    struct Sample {
        glm::vec3 position, normal;
        bool valid;
    };
    const int sw = (width + stride - 1) / stride, sh = (height + stride - 1) / stride;
    std::vector<Sample> samples(static_cast<size_t>(sw) * sh);
    std::vector<float> sampleValues(samples.size() * channels);
    parallelFor(0, sh, 16, [&](int64_t sy) {
        for (int sx = 0; sx < sw; ++sx) {
            const size_t j = static_cast<size_t>(sy) * stride * width + static_cast<size_t>(sx) * stride;
            const size_t k = static_cast<size_t>(sy) * sw + sx;
            samples[k] = {points[j].position, points[j].normal, points[j].valid()};
            std::copy_n(&values[j * channels], channels, &sampleValues[k * channels]);
        }
    });

    std::vector<std::vector<size_t>> rowHoles(holes ? height : 0);
    parallelFor(0, height, 4, [&](int64_t y64) {
        const int y = static_cast<int>(y64);
        std::vector<float> sum(channels);
        // The samples nearest to row y (and below, column x): the window is centred on them.
        const int yCentre = (y + stride / 2) / stride;
        for (int x = 0; x < width; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            const SurfacePoint& p = points[i];
            if (!p.valid()) continue;
            const float pixelSize = pixelAngle * glm::length(p.position - eye);  // world size of a pixel here
            const float planeAllowance = s.planeDistance * pixelSize;
            const int xCentre = (x + stride / 2) / stride;
            std::fill(sum.begin(), sum.end(), 0.0f);
            float weightSum = 0.0f;
            for (int dy = -r; dy <= r; ++dy) {
                const int sy = yCentre + dy;
                if (sy < 0 || sy >= sh) continue;
                const size_t lengthRow = static_cast<size_t>(sy * stride - y + reach) * side;
                for (int dx = -r; dx <= r; ++dx) {
                    const int sx = xCentre + dx;
                    if (sx < 0 || sx >= sw) continue;
                    const size_t k = static_cast<size_t>(sy) * sw + sx;
                    const Sample& q = samples[k];
                    if (!q.valid) continue;
                    const float cosN = glm::dot(p.normal, q.normal);
                    if (cosN <= 0.0f) continue;
                    // Off the tangent plane by more than the allowance: another surface (a depth edge).
                    const float offPlane = std::abs(glm::dot(p.normal, q.position - p.position));
                    if (offPlane > planeAllowance * offsetLength[lengthRow + sx * stride - x + reach])
                        continue;
                    const float w = spatial[dx + r] * spatial[dy + r] * powInt(cosN, s.normalPower);
                    const float* v = &sampleValues[k * channels];
                    for (int c = 0; c < channels; ++c) sum[c] += v[c] * w;
                    weightSum += w;
                }
            }
            if (weightSum > 0.0f)
                for (int c = 0; c < channels; ++c) out[i * channels + c] = sum[c] / weightSum;
            else if (holes)
                rowHoles[y].push_back(i);
        }
    });
    for (const std::vector<size_t>& row : rowHoles) holes->insert(holes->end(), row.begin(), row.end());
    return out;
}

}  // namespace deltagi
