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
                           std::span<const uint8_t> sampled, std::vector<size_t>* holes) {
    std::vector<float> out(values.begin(), values.end());
    if (s.radius <= 0 || channels <= 0) return out;
    std::vector<std::vector<size_t>> rowHoles(holes ? height : 0);
    const int r = s.radius;
    std::vector<float> spatial(2 * r + 1);
    for (int d = -r; d <= r; ++d) spatial[d + r] = std::exp(-0.5f * d * d / (s.spatialSigma * s.spatialSigma));
    parallelFor(0, height, 4, [&](int64_t y64) {
        const int y = static_cast<int>(y64);
        std::vector<float> sum(channels);
        for (int x = 0; x < width; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            const SurfacePoint& p = points[i];
            if (!p.valid()) continue;
            const float pixelSize = pixelAngle * glm::length(p.position - eye);  // world size of a pixel here
            std::fill(sum.begin(), sum.end(), 0.0f);
            float weightSum = 0.0f;
            for (int dy = -r; dy <= r; ++dy) {
                const int yy = y + dy;
                if (yy < 0 || yy >= height) continue;
                for (int dx = -r; dx <= r; ++dx) {
                    const int xx = x + dx;
                    if (xx < 0 || xx >= width) continue;
                    const size_t j = static_cast<size_t>(yy) * width + xx;
                    const SurfacePoint& q = points[j];
                    if (!q.valid() || (!sampled.empty() && !sampled[j])) continue;
                    const float cosN = glm::dot(p.normal, q.normal);
                    if (cosN <= 0.0f) continue;
                    // Off the tangent plane by more than the allowance: another surface (a depth edge).
                    const float offPlane = std::abs(glm::dot(p.normal, q.position - p.position));
                    const float allowance = s.planeDistance * pixelSize * std::sqrt(float(dx * dx + dy * dy) + 1.0f);
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
