#include "core/environment_sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/environment.h"

namespace deltagi {

namespace {

// Index k with cdf[k] <= u < cdf[k + 1] among the n intervals of a cdf of n + 1 entries, skipping empty ones.
int findInterval(const double* cdf, int n, double u) {
    const int k = static_cast<int>(std::upper_bound(cdf, cdf + n + 1, u) - cdf) - 1;
    return std::clamp(k, 0, n - 1);
}

}  // namespace

EnvironmentSampler::EnvironmentSampler(const Environment& environment)
    : environment_(environment),
      width_(environment.radiance.width()),
      height_(environment.radiance.height()) {
    rowCdf_.assign(height_ + 1, 0.0);
    columnCdfs_.assign(static_cast<size_t>(height_) * (width_ + 1), 0.0);
    for (int y = 0; y < height_; ++y) {
        double* cdf = &columnCdfs_[static_cast<size_t>(y) * (width_ + 1)];
        for (int x = 0; x < width_; ++x) cdf[x + 1] = cdf[x] + meanRadiance({x, y});
        const double row = cdf[width_];
        for (int x = 1; x <= width_; ++x) cdf[x] = row > 0.0 ? cdf[x] / row : static_cast<double>(x) / width_;
        rowCdf_[y + 1] = rowCdf_[y] + row * equirectPixelSolidAngle(y, width_, height_);
    }
    total_ = rowCdf_[height_];
    for (double& c : rowCdf_) c = total_ > 0.0 ? c / total_ : 0.0;
}

float EnvironmentSampler::meanRadiance(glm::ivec2 p) const {
    const glm::vec3 l = environment_.radiance.rgb(p.x, p.y);
    return (l.x + l.y + l.z) / 3.0f;
}

glm::ivec2 EnvironmentSampler::pixelOf(glm::vec3 worldDirection) const {
    const glm::vec2 uv = equirectUv(environment_.environmentFromWorld() * worldDirection);
    return {std::clamp(static_cast<int>(uv.x * static_cast<float>(width_)), 0, width_ - 1),
            std::clamp(static_cast<int>(uv.y * static_cast<float>(height_)), 0, height_ - 1)};
}

EnvironmentSampler::Sample EnvironmentSampler::sample(float u1, float u2) const {
    Sample s;
    if (!(total_ > 0.0)) return s;
    const int y = findInterval(rowCdf_.data(), height_, u1);
    const double* cdf = &columnCdfs_[static_cast<size_t>(y) * (width_ + 1)];
    const int x = findInterval(cdf, width_, u2);
    // The numbers' positions inside the chosen intervals are uniform: reuse them within the pixel.
    const double fy = std::clamp((u1 - rowCdf_[y]) / std::max(rowCdf_[y + 1] - rowCdf_[y], 1e-300), 0.0, 1.0);
    const double fx = std::clamp((u2 - cdf[x]) / std::max(cdf[x + 1] - cdf[x], 1e-300), 0.0, 1.0);
    const double sinTop = std::sin(equirectRowElevation(y, height_));
    const double sinBottom = std::sin(equirectRowElevation(y + 1, height_));
    const double sinTheta = sinTop + fy * (sinBottom - sinTop);
    const double cosTheta = std::sqrt(std::max(0.0, 1.0 - sinTheta * sinTheta));
    const double phi = 2.0 * std::numbers::pi * ((x + fx) / width_ - 0.5);
    const glm::vec3 d(static_cast<float>(std::sin(phi) * cosTheta), static_cast<float>(sinTheta),
                      static_cast<float>(-std::cos(phi) * cosTheta));
    s.wi = glm::normalize(environment_.worldFromEnvironment * d);
    s.radiance = environment_.radiance.rgb(x, y);
    s.pdf = static_cast<float>(meanRadiance({x, y}) / total_);
    return s;
}

float EnvironmentSampler::pdf(glm::vec3 worldDirection) const {
    if (!(total_ > 0.0)) return 0.0f;
    return static_cast<float>(meanRadiance(pixelOf(worldDirection)) / total_);
}

glm::vec3 EnvironmentSampler::radiance(glm::vec3 worldDirection) const {
    const glm::ivec2 p = pixelOf(worldDirection);
    return environment_.radiance.rgb(p.x, p.y);
}

}  // namespace deltagi
