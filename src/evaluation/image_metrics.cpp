// Image metrics and the false-colour difference image of `deltagi compare` (declared in
// evaluation/evaluation.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include <fmt/core.h>

#include "deltagi/error.h"
#include "evaluation/evaluation.h"

namespace deltagi {

namespace {

// Fig. 3c shows twice the squared difference.
constexpr float kSquaredDifferenceScale = 2.0f;
constexpr float kRobustPercentile = 0.99f;
constexpr float kMinimumScale = 1e-8f;

void checkSameSize(const Image& a, const Image& b) {
    if (a.width() != b.width() || a.height() != b.height())
        throw InputError("", fmt::format("images differ in size: {}x{} and {}x{}", a.width(), a.height(),
                                         b.width(), b.height()));
}

// Inferno-like colour ramp (sRGB-ish control points, converted to linear by the caller's writer).
glm::vec3 ramp(float t) {
    static constexpr std::array<glm::vec3, 6> kStops = {
        glm::vec3(0.0f, 0.0f, 0.015f),  glm::vec3(0.26f, 0.04f, 0.41f), glm::vec3(0.58f, 0.15f, 0.40f),
        glm::vec3(0.87f, 0.32f, 0.23f), glm::vec3(0.99f, 0.65f, 0.04f), glm::vec3(0.99f, 1.0f, 0.64f)};
    t = std::clamp(t, 0.0f, 1.0f) * static_cast<float>(kStops.size() - 1);
    const int i = std::min(static_cast<int>(t), static_cast<int>(kStops.size()) - 2);
    const glm::vec3 srgb = glm::mix(kStops[i], kStops[i + 1], t - static_cast<float>(i));
    // The image writer encodes PNGs as sRGB: store linear values so that the stops appear as written.
    return glm::pow(srgb, glm::vec3(2.2f));
}

}  // namespace

ImageMetrics compareImages(const Image& test, const Image& reference) {
    checkSameSize(test, reference);
    double squared = 0.0, relative = 0.0, absolute = 0.0;
    size_t n = 0;
    for (int y = 0; y < test.height(); ++y)
        for (int x = 0; x < test.width(); ++x) {
            const glm::dvec3 a(test.rgb(x, y)), b(reference.rgb(x, y));
            for (int c = 0; c < 3; ++c) {
                const double d = a[c] - b[c];
                squared += d * d;
                relative += d * d / (b[c] * b[c] + kRelMseEpsilon);
                absolute += std::abs(d);
                ++n;
            }
        }
    ImageMetrics m;
    if (n == 0) return m;
    m.rmse = std::sqrt(squared / n);
    m.relMse = relative / n;
    m.mae = absolute / n;
    return m;
}

Image squaredDifference(const Image& test, const Image& reference) {
    checkSameSize(test, reference);
    Image out(test.width(), test.height(), 1);
    for (int y = 0; y < test.height(); ++y)
        for (int x = 0; x < test.width(); ++x) {
            const glm::vec3 d = reference.rgb(x, y) - test.rgb(x, y);
            out.at(x, y, 0) = kSquaredDifferenceScale * (d.x * d.x + d.y * d.y + d.z * d.z) / 3.0f;
        }
    return out;
}

Image falseColour(const Image& values, float maxValue) {
    Image out(values.width(), values.height(), 3);
    const float scale = 1.0f / std::max(maxValue, kMinimumScale);
    for (int y = 0; y < values.height(); ++y)
        for (int x = 0; x < values.width(); ++x) {
            const float v = values.at(x, y, 0);
            out.setRgb(x, y, ramp(std::isfinite(v) ? v * scale : 0.0f));
        }
    return out;
}

float robustMaximum(const Image& values) {
    std::vector<float> v;
    v.reserve(values.pixelCount());
    for (int y = 0; y < values.height(); ++y)
        for (int x = 0; x < values.width(); ++x)
            if (std::isfinite(values.at(x, y, 0))) v.push_back(values.at(x, y, 0));
    if (v.empty()) return kMinimumScale;
    const size_t k =
        std::min(v.size() - 1, static_cast<size_t>(kRobustPercentile * static_cast<float>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return std::max(v[k], kMinimumScale);
}

}  // namespace deltagi
