#include "denoise.h"

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
            const int xCentre = (x + stride / 2) / stride;
            std::fill(sum.begin(), sum.end(), 0.0f);
            float weightSum = 0.0f;
            for (int dy = -r; dy <= r; ++dy) {
                const int yy = (yCentre + dy) * stride;
                if (yy < 0 || yy >= height) continue;
                for (int dx = -r; dx <= r; ++dx) {
                    const int xx = (xCentre + dx) * stride;
                    if (xx < 0 || xx >= width) continue;
                    const size_t j = static_cast<size_t>(yy) * width + xx;
                    const SurfacePoint& q = points[j];
                    if (!q.valid()) continue;
                    const float cosN = glm::dot(p.normal, q.normal);
                    if (cosN <= 0.0f) continue;
                    // Off the tangent plane by more than the allowance: another surface (a depth edge).
                    const float offPlane = std::abs(glm::dot(p.normal, q.position - p.position));
                    const float px = static_cast<float>(xx - x), py = static_cast<float>(yy - y);
                    const float allowance = s.planeDistance * pixelSize * std::sqrt(px * px + py * py + 1.0f);
                    if (offPlane > allowance) continue;
                    const float w = spatial[dx + r] * spatial[dy + r] * powInt(cosN, s.normalPower);
                    const float* v = &values[j * channels];
                    for (int k = 0; k < channels; ++k) sum[k] += v[k] * w;
                    weightSum += w;
                }
            }
            if (weightSum > 0.0f)
                for (int k = 0; k < channels; ++k) out[i * channels + k] = sum[k] / weightSum;
            else if (holes)
                rowHoles[y].push_back(i);
        }
    });
    for (const std::vector<size_t>& row : rowHoles) holes->insert(holes->end(), row.begin(), row.end());
    return out;
}

}  // namespace deltagi
