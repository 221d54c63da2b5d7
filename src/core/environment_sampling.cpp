#include "core/environment_sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/environment.h"
#include "core/parallel.h"

namespace deltagi {

namespace {

// How far (in y of a unit direction) below the lowest lit row a direction must be to count as dark, and how
// much further the highest direction of a cone (darkCone).
constexpr float kDarkMargin = 1e-4f, kDarkConeMargin = 1e-3f;

// Index k with cdf[k] <= u < cdf[k + 1] among the n intervals of a cdf of n + 1 entries, skipping empty ones
// (the last k with cdf[k] <= u, clamped to [0, n - 1]), from where `guide` (guideOf) says to start.
int findInterval(const double* cdf, const int* guide, int n, double u) {
    int k = guide[std::clamp(static_cast<int>(u * n), 0, n - 1)];
    while (k > 0 && cdf[k] > u) --k;  // u * n rounded up past a bin
    while (k < n && cdf[k + 1] <= u) ++k;
    return std::clamp(k, 0, n - 1);
}

float meanOf(glm::vec3 l) {
    return (l.x + l.y + l.z) / 3.0f;
}

// The guide of a cdf of n + 1 entries: entry j is the last k with cdf[k] <= j / n.
void guideOf(const double* cdf, int n, int* guide) {
    int k = 0;
    for (int j = 0; j < n; ++j) {
        const double u = static_cast<double>(j) / n;
        while (k < n && cdf[k + 1] <= u) ++k;
        guide[j] = k;
    }
}

}  // namespace

EnvironmentSampler::EnvironmentSampler(const Environment& environment)
    : environment_(environment),
      environmentFromWorld_(environment.environmentFromWorld()),
      pixels_(environment.radiance.data().data()),
      width_(environment.radiance.width()),
      height_(environment.radiance.height()) {
    if (!environment.radiance.empty() && environment.radiance.channels() != 3)
        throw std::invalid_argument("EnvironmentSampler: the environment's radiance must be RGB");
    rowCdf_.assign(height_ + 1, 0.0);
    columnCdfs_.assign(static_cast<size_t>(height_) * (width_ + 1), 0.0);
    columnGuides_.resize(static_cast<size_t>(height_) * width_);
    // Each row's column cdf and its guide, rows in parallel (a light camera's new map every frame); each
    // row's weight (its sum times its pixels' solid angle), then the row cdf in order.
    std::vector<double> rowWeights(height_);
    parallelFor(0, height_, 8, [&](int64_t row) {
        const int y = static_cast<int>(row);
        double* cdf = &columnCdfs_[static_cast<size_t>(y) * (width_ + 1)];
        for (int x = 0; x < width_; ++x) cdf[x + 1] = cdf[x] + meanRadiance({x, y});
        const double sum = cdf[width_];
        for (int x = 1; x <= width_; ++x) cdf[x] = sum > 0.0 ? cdf[x] / sum : static_cast<double>(x) / width_;
        guideOf(cdf, width_, &columnGuides_[static_cast<size_t>(y) * width_]);
        rowWeights[y] = sum * equirectPixelSolidAngle(y, width_, height_);
    });
    for (int y = 0; y < height_; ++y) rowCdf_[y + 1] = rowCdf_[y] + rowWeights[y];
    total_ = rowCdf_[height_];
    // Below the bottom edge of the lowest lit row, by a margin far wider than the floats' error in the
    // elevation that pixelOf() computes, so that no direction that maps to a lit row counts as dark.
    int lowestLit = -1;
    for (int y = 0; y < height_; ++y)
        if (rowCdf_[y + 1] > rowCdf_[y]) lowestLit = y;
    darkBelowY_ = lowestLit < 0 ? 2.0f
                                : static_cast<float>(std::sin(equirectRowElevation(lowestLit + 1, height_))) -
                                      kDarkMargin;
    for (double& c : rowCdf_) c = total_ > 0.0 ? c / total_ : 0.0;
    rowGuide_.resize(height_);
    guideOf(rowCdf_.data(), height_, rowGuide_.data());
    rowCentres_.resize(height_);
    rowElevations_.resize(height_);
    for (int y = 0; y < height_; ++y) {
        const double elevation =
            0.5 * (equirectRowElevation(y, height_) + equirectRowElevation(y + 1, height_));
        rowCentres_[y] = {static_cast<float>(std::cos(elevation)), static_cast<float>(std::sin(elevation)),
                          0.0f};
        rowElevations_[y] = static_cast<float>(elevation);
    }
    columnCentres_.resize(width_);
    for (int x = 0; x < width_; ++x) {
        const double phi = 2.0 * std::numbers::pi * ((x + 0.5) / width_ - 0.5);
        columnCentres_[x] = {static_cast<float>(std::sin(phi)), static_cast<float>(-std::cos(phi))};
    }
    // A point of a pixel is within half its height in elevation plus half its width (at most, at the
    // equator) in longitude of the centre; a little more for the floats.
    pixelRadius_ = static_cast<float>(0.5 * std::numbers::pi / height_ + std::numbers::pi / width_) + 1e-4f;
}

int EnvironmentSampler::rowOf(float u1) const {
    return findInterval(rowCdf_.data(), rowGuide_.data(), height_, u1);
}

int EnvironmentSampler::columnOf(int row, float u2) const {
    return findInterval(&columnCdfs_[static_cast<size_t>(row) * (width_ + 1)],
                        &columnGuides_[static_cast<size_t>(row) * width_], width_, u2);
}

glm::ivec2 EnvironmentSampler::pixelOf(float u1, float u2) const {
    const int y = rowOf(u1);
    return {columnOf(y, u2), y};
}

float EnvironmentSampler::elevationOf(glm::vec3 worldDirection) const {
    const glm::vec3 d = glm::normalize(environmentFromWorld_ * worldDirection);
    return std::asin(std::clamp(d.y, -1.0f, 1.0f));
}

glm::vec3 EnvironmentSampler::pixelCentre(glm::ivec2 p) const {
    const glm::vec3 row = rowCentres_[p.y];
    const glm::vec2 column = columnCentres_[p.x];
    return environment_.worldFromEnvironment * glm::vec3(column.x * row.x, row.y, column.y * row.x);
}

float EnvironmentSampler::meanRadiance(glm::ivec2 p) const {
    return meanOf(rgbAt(p));
}

glm::ivec2 EnvironmentSampler::pixelOf(glm::vec3 worldDirection) const {
    return pixelAt(environmentFromWorld_ * worldDirection);
}

glm::ivec2 EnvironmentSampler::pixelAt(glm::vec3 localDirection) const {
    const glm::vec2 uv = equirectUv(localDirection);
    return {std::clamp(static_cast<int>(uv.x * static_cast<float>(width_)), 0, width_ - 1),
            std::clamp(static_cast<int>(uv.y * static_cast<float>(height_)), 0, height_ - 1)};
}

EnvironmentSampler::Sample EnvironmentSampler::sample(float u1, float u2) const {
    if (!(total_ > 0.0)) return {};
    return sample(u1, u2, pixelOf(u1, u2));
}

EnvironmentSampler::Sample EnvironmentSampler::sample(float u1, float u2, glm::ivec2 pixel) const {
    Sample s;
    if (!(total_ > 0.0)) return s;
    const auto [x, y] = pixel;
    const double* cdf = &columnCdfs_[static_cast<size_t>(y) * (width_ + 1)];
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
    s.radiance = rgbAt(pixel);
    s.pdf = static_cast<float>(meanOf(s.radiance) / total_);
    return s;
}

float EnvironmentSampler::pdf(glm::vec3 worldDirection) const {
    if (!(total_ > 0.0)) return 0.0f;
    return static_cast<float>(meanRadiance(pixelOf(worldDirection)) / total_);
}

glm::vec3 EnvironmentSampler::radiance(glm::vec3 worldDirection) const {
    return rgbAt(pixelOf(worldDirection));
}

EnvironmentSampler::Value EnvironmentSampler::value(glm::vec3 worldDirection) const {
    if (!(total_ > 0.0)) return {radiance(worldDirection), 0.0f};
    const glm::vec3 d = environmentFromWorld_ * worldDirection;
    if (d.y < darkBelowY_) return {};
    const glm::vec3 radiance = rgbAt(pixelAt(d));
    return {radiance, static_cast<float>(meanOf(radiance) / total_)};
}

bool EnvironmentSampler::darkCone(glm::vec3 worldAxis, float halfAngle) const {
    if (!(total_ > 0.0)) return true;
    const glm::vec3 d = environmentFromWorld_ * worldAxis;
    // The cone's highest direction is halfAngle nearer the zenith than its axis (or the zenith itself).
    const float fromZenith = std::acos(std::clamp(d.y, -1.0f, 1.0f)) - halfAngle;
    const float highest = fromZenith > 0.0f ? std::cos(fromZenith) : 1.0f;
    return highest + kDarkConeMargin < darkBelowY_;
}

}  // namespace deltagi
