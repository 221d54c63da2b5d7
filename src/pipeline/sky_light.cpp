#include "pipeline/sky_light.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/brdf_sampling.h"
#include "core/environment.h"
#include "core/parallel.h"

namespace deltagi {

namespace {

constexpr double kPi = std::numbers::pi;
// The finest level is at most this wide: its kernel (2 pixels, 1.4 degrees at 512) is already narrower than
// the narrowest specular cone by default (options.specular.min_aperture_deg = 2).
constexpr int kMaxBaseWidth = 512;
// A level's kernel half-angle in its own pixels: wide enough to be sampled smoothly by them.
constexpr double kKernelPixels = 2.0;
// The kernel is cut off where kappa (1 - cos) exceeds this: exp(-10) of the peak.
constexpr double kKernelSupport = 10.0;
// The widest level covers a hemisphere-wide cone (90 degrees half-angle).
constexpr double kWidestHalfAngle = 0.5 * kPi;
constexpr int64_t kPointGrain = 256;
// exp(x) is 0 in doubles below this (the smallest denormal is exp(-744.44)).
constexpr double kExpIsZero = -746.0;

// Halves a map (odd sizes round up), each new pixel the solid-angle-weighted mean of the pixels it covers.
Image reduce(const Image& in) {
    const int w = (in.width() + 1) / 2, h = (in.height() + 1) / 2;
    Image out(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            glm::dvec3 sum(0.0);
            double weight = 0.0;
            for (int sy = 2 * y; sy < std::min(2 * y + 2, in.height()); ++sy) {
                const double dOmega = equirectPixelSolidAngle(sy, in.width(), in.height());
                for (int sx = 2 * x; sx < std::min(2 * x + 2, in.width()); ++sx) {
                    sum += glm::dvec3(in.rgb(sx, sy)) * dOmega;
                    weight += dOmega;
                }
            }
            out.setRgb(x, y, glm::vec3(sum / weight));
        }
    return out;
}

// One level: the residual of `in` (minus the lights) convolved with the kernel of `halfAngle`, at the
// resolution of `in`. For an output row and an input row the kernel depends only on the difference in
// longitude, i.e. on the column offset: each pair of rows is a 1D convolution with weights computed once.
Image convolve(const Image& in, double halfAngle, std::span<const ExtractedLight> lights) {
    const int w = in.width(), h = in.height();
    const double kappa = 1.0 / (1.0 - std::cos(halfAngle));
    const double cosSupport = std::max(1.0 - kKernelSupport / kappa, -1.0);
    const double support = std::acos(cosSupport);
    const double columnAngle = 2.0 * kPi / w;
    std::vector<double> rowSolidAngle(h), rowElevation(h);
    for (int y = 0; y < h; ++y) {
        rowSolidAngle[y] = equirectPixelSolidAngle(y, w, h);
        rowElevation[y] = kPi * (0.5 - (y + 0.5) / h);
    }
    const std::span<const float> pixels = in.data();
    Image out(w, h, 3);
    parallelFor(0, h, 1, [&](int64_t row) {
        const int y = static_cast<int>(row);
        const double theta = rowElevation[y];
        const int yLo = std::max(0, static_cast<int>(std::floor((0.5 - (theta + support) / kPi) * h)) - 1);
        const int yHi =
            std::min(h - 1, static_cast<int>(std::floor((0.5 - (theta - support) / kPi) * h)) + 1);
        std::vector<glm::dvec3> sums(w, glm::dvec3(0.0));
        std::vector<double> weights;
        double weightSum = 0.0;
        for (int sy = yLo; sy <= yHi; ++sy) {
            // Offsets -half .. half, at most one full turn (each column once).
            const int half = std::min(w / 2, static_cast<int>(std::ceil(support / columnAngle)) + 1);
            const int first = -half, last = std::min(half, w - 1 - half);
            weights.assign(static_cast<size_t>(last - first + 1), 0.0);
            const double t = rowElevation[sy];
            bool any = false;
            for (int k = first; k <= last; ++k) {
                const double cosine =
                    std::sin(theta) * std::sin(t) + std::cos(theta) * std::cos(t) * std::cos(k * columnAngle);
                if (cosine < cosSupport) continue;
                const double weight = std::exp(kappa * (cosine - 1.0)) * rowSolidAngle[sy];
                weights[k - first] = weight;
                weightSum += weight;
                any = true;
            }
            if (!any) continue;
            const float* rowPixels = &pixels[static_cast<size_t>(sy) * w * 3];
            for (int x = 0; x < w; ++x) {
                glm::dvec3 acc(0.0);
                for (int k = first; k <= last; ++k) {
                    const double weight = weights[k - first];
                    if (weight == 0.0) continue;
                    int sx = x + k;  // wrapped round the map (|k| <= w / 2)
                    if (sx < 0)
                        sx += w;
                    else if (sx >= w)
                        sx -= w;
                    acc +=
                        weight * glm::dvec3(rowPixels[3 * sx], rowPixels[3 * sx + 1], rowPixels[3 * sx + 2]);
                }
                sums[x] += acc;
            }
        }
        for (int x = 0; x < w; ++x) {
            const glm::dvec3 a(equirectDirection((static_cast<float>(x) + 0.5f) / static_cast<float>(w),
                                                 (static_cast<float>(y) + 0.5f) / static_cast<float>(h)));
            glm::dvec3 sum = sums[x];
            for (const ExtractedLight& light : lights) {
                // exp() of an exponent this low is 0 (its slow underflow path: most lights are far away).
                const double exponent = kappa * (glm::dot(a, glm::dvec3(light.direction)) - 1.0);
                if (exponent < kExpIsZero) continue;
                sum -= std::exp(exponent) * glm::dvec3(light.irradiance);
            }
            out.setRgb(x, y, weightSum > 0.0 ? glm::vec3(sum / weightSum) : glm::vec3(0.0f));
        }
    });
    return out;
}

}  // namespace

SkyPyramid prefilterSky(const Image& equirect, std::span<const ExtractedLight> lights) {
    SkyPyramid sky;
    if (equirect.empty()) return sky;
    Image input = equirect;
    while (input.width() > kMaxBaseWidth && input.width() % 2 == 0 && input.height() % 2 == 0)
        input = reduce(input);
    while (true) {
        const double halfAngle = std::min(kKernelPixels * kPi / input.height(), kWidestHalfAngle);
        sky.levels.push_back(convolve(input, halfAngle, lights));
        sky.halfAngles.push_back(static_cast<float>(halfAngle));
        if (halfAngle >= kWidestHalfAngle || input.height() <= 2) break;
        input = reduce(input);
    }
    return sky;
}

glm::vec3 skyRadiance(const SkyPyramid& sky, glm::vec3 direction, float tanHalfAngle) {
    if (sky.empty()) return glm::vec3(0.0f);
    const glm::vec2 uv = equirectUv(direction);
    const float halfAngle = std::atan(std::max(tanHalfAngle, 0.0f));
    const size_t last = sky.levels.size() - 1;
    if (halfAngle <= sky.halfAngles.front()) return sampleEquirect(sky.levels.front(), uv);
    if (halfAngle >= sky.halfAngles[last]) return sampleEquirect(sky.levels[last], uv);
    size_t l = 0;
    while (halfAngle > sky.halfAngles[l + 1]) ++l;
    const float t =
        std::log(halfAngle / sky.halfAngles[l]) / std::log(sky.halfAngles[l + 1] / sky.halfAngles[l]);
    return glm::mix(sampleEquirect(sky.levels[l], uv), sampleEquirect(sky.levels[l + 1], uv), t);
}

SkyLight traceSkyCones(std::span<const SurfacePoint> points, const Environment& environment,
                       const VisibilityVolumes& visibility, ShadowMode mode, const Options& options,
                       SkyParts parts, std::span<const uint32_t> pixels) {
    SkyLight out{std::vector<glm::vec3>(points.size(), glm::vec3(0.0f)),
                 std::vector<glm::vec3>(points.size(), glm::vec3(0.0f))};
    if (environment.sky.empty()) return out;
    const ConeTraceSettings settings = coneTraceSettings(options.trace);
    const DiffuseConeSet cones = makeDiffuseCones(options.diffuse.count, options.diffuse.apertureDeg);
    const glm::mat3 environmentFromWorld = environment.environmentFromWorld();
    const MipVolume* reference = visibility.scene ? visibility.scene : visibility.object;
    // The sky through one cone, times the part of it that `mode` lets through.
    auto coneSky = [&](glm::vec3 position, glm::vec3 normal, glm::vec3 direction, float tanHalf,
                       float jitter) {
        ShadowOcclusion occlusion;
        if (reference) {
            Cone cone;
            cone.direction = direction;
            cone.origin = coneOrigin(position, normal, direction, reference->region(), settings);
            cone.tanHalfAngle = tanHalf;
            cone.jitter = jitter;
            if (mode == ShadowMode::DeltaShadow && !shadowConeMeetsObjects(cone, visibility, settings))
                return glm::vec3(0.0f);
            occlusion = traceShadowCone(cone, visibility, settings);
        }
        return shadowFactor(occlusion, mode) *
               skyRadiance(environment.sky, environmentFromWorld * direction, tanHalf);
    };
    forEachValidPoint(points, pixels, kPointGrain, [&](int64_t i) {
        const SurfacePoint& p = points[i];
        if (parts != SkyParts::Specular && p.surface.diffuse != glm::vec3(0.0f)) {
            const glm::mat3 frame = frameAround(p.normal);
            glm::vec3 sum(0.0f);
            for (size_t k = 0; k < cones.directions.size(); ++k)
                sum += cones.weights[k] * coneSky(p.position, p.normal, frame * cones.directions[k],
                                                  cones.tanHalfAngle,
                                                  hashToUnit(i, static_cast<uint32_t>(3000 + k)));
            out.diffuse[i] = sum;
        }
        if (parts != SkyParts::Diffuse && p.surface.specular != glm::vec3(0.0f)) {
            const glm::vec3 mirror = glm::normalize(glm::reflect(-p.toEye, p.normal));
            const float tanHalf = specularConeTanHalfAngle(
                p.surface.phongExponent(), options.specular.minApertureDeg, options.specular.maxApertureDeg);
            out.specular[i] = coneSky(p.position, p.normal, mirror, tanHalf, hashToUnit(i, 4000u));
        }
    });
    return out;
}

}  // namespace deltagi
