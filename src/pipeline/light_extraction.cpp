#include "pipeline/light_extraction.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>

#include "core/environment.h"
#include "core/parallel.h"
#include "deltagi/scene.h"
#include "pipeline/sky_light.h"

namespace deltagi {

namespace {

constexpr double kPi = std::numbers::pi;

// A rectangle of map pixels [x0, x1) x [y0, y1).
struct Region {
    int x0, y0, x1, y1;
    double energy = 0.0;
};

// A summed-area table: sum(x0, y0, x1, y1) of a per-pixel quantity in O(1).
class SummedArea {
  public:
    SummedArea(int width, int height)
        : width_(width), sums_(static_cast<size_t>(width + 1) * (height + 1), 0.0) {}
    // Builds the table from values(x, y), row by row.
    template <typename Value>
    void build(int height, Value&& value) {
        for (int y = 0; y < height; ++y) {
            double row = 0.0;
            for (int x = 0; x < width_; ++x) {
                row += value(x, y);
                at(x + 1, y + 1) = at(x + 1, y) + row;
            }
        }
    }
    double sum(int x0, int y0, int x1, int y1) const {
        return at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0);
    }

  private:
    double& at(int x, int y) { return sums_[static_cast<size_t>(y) * (width_ + 1) + x]; }
    double at(int x, int y) const { return sums_[static_cast<size_t>(y) * (width_ + 1) + x]; }
    int width_;
    std::vector<double> sums_;
};

// Energy per pixel (luminance times solid angle) and, for the variance, the energy-weighted angular position
// (phi cos(theta), theta) and its square: Viriyothai & Debevec's metric, in which a step in longitude counts
// as much as its length on the sphere.
struct EnergyTables {
    int width, height;
    SummedArea energy, px, py, squares;

    // The variance's tables (px, py, squares) are built only `withVariance` (varianceCut reads them).
    EnergyTables(const Image& map, bool withVariance)
        : width(map.width()),
          height(map.height()),
          energy(width, height),
          px(withVariance ? width : 0, withVariance ? height : 0),
          py(withVariance ? width : 0, withVariance ? height : 0),
          squares(withVariance ? width : 0, withVariance ? height : 0) {
        std::vector<double> pixelEnergy(static_cast<size_t>(width) * height);
        for (int y = 0; y < height; ++y) {
            const double dOmega = equirectPixelSolidAngle(y, width, height);
            for (int x = 0; x < width; ++x)
                pixelEnergy[static_cast<size_t>(y) * width + x] = luminance(map.rgb(x, y)) * dOmega;
        }
        auto e = [&](int x, int y) { return pixelEnergy[static_cast<size_t>(y) * width + x]; };
        energy.build(height, e);
        if (!withVariance) return;
        px.build(height, [&](int x, int y) { return e(x, y) * position(x, y).x; });
        py.build(height, [&](int x, int y) { return e(x, y) * position(x, y).y; });
        squares.build(height, [&](int x, int y) {
            const glm::dvec2 p = position(x, y);
            return e(x, y) * (p.x * p.x + p.y * p.y);
        });
    }

    glm::dvec2 position(int x, int y) const {
        const double theta = kPi * (0.5 - (y + 0.5) / height), phi = 2.0 * kPi * ((x + 0.5) / width - 0.5);
        return {phi * std::cos(theta), theta};
    }
    double energyOf(int x0, int y0, int x1, int y1) const { return energy.sum(x0, y0, x1, y1); }
    // sum E |p - centroid|^2 over the rectangle.
    double varianceOf(int x0, int y0, int x1, int y1) const {
        const double e = energy.sum(x0, y0, x1, y1);
        if (!(e > 0.0)) return 0.0;
        const double sx = px.sum(x0, y0, x1, y1), sy = py.sum(x0, y0, x1, y1);
        return std::max(squares.sum(x0, y0, x1, y1) - (sx * sx + sy * sy) / e, 0.0);
    }
};

std::pair<Region, Region> cutAt(const Region& r, bool alongX, int cut, const EnergyTables& t) {
    Region a = r, b = r;
    if (alongX) {
        a.x1 = b.x0 = cut;
    } else {
        a.y1 = b.y0 = cut;
    }
    a.energy = t.energyOf(a.x0, a.y0, a.x1, a.y1);
    b.energy = t.energyOf(b.x0, b.y0, b.x1, b.y1);
    return {a, b};
}

// Is the region wider than high, measured on the sphere (longitude times the cosine of the middle latitude)?
bool widerThanHigh(const Region& r, const EnergyTables& t) {
    const double middle = kPi * (0.5 - 0.5 * (r.y0 + r.y1) / t.height);
    const double width = (r.x1 - r.x0) * (2.0 * kPi / t.width) * std::cos(middle);
    const double height = (r.y1 - r.y0) * (kPi / t.height);
    return width >= height;
}

std::optional<std::pair<Region, Region>> medianCut(const Region& r, const EnergyTables& t) {
    const bool canX = r.x1 - r.x0 >= 2, canY = r.y1 - r.y0 >= 2;
    if (!canX && !canY) return std::nullopt;
    const bool alongX = canX && (!canY || widerThanHigh(r, t));
    const int lo = alongX ? r.x0 : r.y0, hi = alongX ? r.x1 : r.y1;
    if (!(r.energy > 0.0)) return cutAt(r, alongX, (lo + hi) / 2, t);
    // The first cut whose lower part holds at least half of the energy, or the one before it if closer.
    auto lower = [&](int cut) {
        return alongX ? t.energyOf(r.x0, r.y0, cut, r.y1) : t.energyOf(r.x0, r.y0, r.x1, cut);
    };
    int first = lo + 1, last = hi - 1;
    while (first < last) {
        const int mid = (first + last) / 2;
        if (lower(mid) >= 0.5 * r.energy)
            last = mid;
        else
            first = mid + 1;
    }
    int cut = first;
    if (cut > lo + 1 && std::abs(lower(cut - 1) - 0.5 * r.energy) < std::abs(lower(cut) - 0.5 * r.energy))
        --cut;
    return cutAt(r, alongX, cut, t);
}

std::optional<std::pair<Region, Region>> varianceCut(const Region& r, const EnergyTables& t) {
    const bool canX = r.x1 - r.x0 >= 2, canY = r.y1 - r.y0 >= 2;
    if (!canX && !canY) return std::nullopt;
    if (!(r.energy > 0.0)) return medianCut(r, t);
    double best = std::numeric_limits<double>::infinity();
    std::pair<bool, int> bestCut{canX, canX ? (r.x0 + r.x1) / 2 : (r.y0 + r.y1) / 2};
    if (canX)
        for (int c = r.x0 + 1; c < r.x1; ++c) {
            const double v = t.varianceOf(r.x0, r.y0, c, r.y1) + t.varianceOf(c, r.y0, r.x1, r.y1);
            if (v < best) best = v, bestCut = {true, c};
        }
    if (canY)
        for (int c = r.y0 + 1; c < r.y1; ++c) {
            const double v = t.varianceOf(r.x0, r.y0, r.x1, c) + t.varianceOf(r.x0, c, r.x1, r.y1);
            if (v < best) best = v, bestCut = {false, c};
        }
    return cutAt(r, bestCut.first, bestCut.second, t);
}

std::vector<Region> splitRegions(const EnergyTables& t, int count, ExtractionMethod method) {
    std::vector<Region> regions{{0, 0, t.width, t.height, t.energyOf(0, 0, t.width, t.height)}};
    while (static_cast<int>(regions.size()) < count) {
        // One round: every region once, the most energetic first (they matter most when the round stops
        // early).
        std::vector<size_t> order(regions.size());
        std::iota(order.begin(), order.end(), size_t{0});
        std::stable_sort(order.begin(), order.end(),
                         [&](size_t a, size_t b) { return regions[a].energy > regions[b].energy; });
        std::vector<Region> next = regions;
        bool split = false;
        for (size_t i : order) {
            if (static_cast<int>(next.size()) >= count) break;
            const auto halves =
                method == ExtractionMethod::MedianCut ? medianCut(regions[i], t) : varianceCut(regions[i], t);
            if (!halves) continue;
            next[i] = halves->first;
            next.push_back(halves->second);
            split = true;
        }
        regions = std::move(next);
        if (!split) break;
    }
    return regions;
}

// The directions of a map's pixel centres, equirectDirection()'s, from the sines and cosines of each
// column's longitude and each row's elevation: equirectDirection() of the column on the equator is
// (sin phi, 0, -cos phi), of the row on the meridian u = 1/2 (0, sin theta, -cos theta).
struct PixelDirections {
    std::vector<float> sinPhi, cosPhi, sinTheta, cosTheta;
    explicit PixelDirections(const Image& map) {
        const float w = static_cast<float>(map.width()), h = static_cast<float>(map.height());
        for (int x = 0; x < map.width(); ++x) {
            const glm::vec3 d = equirectDirection((static_cast<float>(x) + 0.5f) / w, 0.5f);
            sinPhi.push_back(d.x);
            cosPhi.push_back(-d.z);
        }
        for (int y = 0; y < map.height(); ++y) {
            const glm::vec3 d = equirectDirection(0.5f, (static_cast<float>(y) + 0.5f) / h);
            sinTheta.push_back(d.y);
            cosTheta.push_back(-d.z);
        }
    }
    glm::vec3 operator()(int x, int y) const {
        return {sinPhi[x] * cosTheta[y], sinTheta[y], -cosPhi[x] * cosTheta[y]};
    }
};

ExtractedLight lightOf(const Region& r, const Image& map, const PixelDirections& directions) {
    glm::dvec3 irradiance(0.0), centroid(0.0);
    double solidAngle = 0.0, energy = 0.0;
    for (int y = r.y0; y < r.y1; ++y) {
        const double dOmega = equirectPixelSolidAngle(y, map.width(), map.height());
        for (int x = r.x0; x < r.x1; ++x) {
            const glm::vec3 l = map.rgb(x, y);
            const glm::vec3 d = directions(x, y);
            irradiance += glm::dvec3(l) * dOmega;
            const double e = static_cast<double>(luminance(l)) * dOmega;
            centroid += glm::dvec3(d) * e;
            energy += e;
            solidAngle += dOmega;
        }
    }
    ExtractedLight light;
    light.irradiance = glm::vec3(irradiance);
    light.solidAngle = static_cast<float>(solidAngle);
    // The energy centroid on the sphere; a region whose directions cancel (a whole uniform sphere) uses its
    // centre.
    const double length = glm::length(centroid);
    light.direction =
        length > 1e-6 * energy
            ? glm::vec3(centroid / length)
            : equirectDirection(0.5f * static_cast<float>(r.x0 + r.x1) / static_cast<float>(map.width()),
                                0.5f * static_cast<float>(r.y0 + r.y1) / static_cast<float>(map.height()));
    return light;
}

}  // namespace

std::vector<ExtractedLight> extractLights(const Image& equirect, int count, ExtractionMethod method) {
    std::vector<ExtractedLight> lights;
    if (count <= 0 || equirect.empty()) return lights;
    const EnergyTables tables(equirect, method == ExtractionMethod::VarianceMinimization);
    const std::vector<Region> regions = splitRegions(tables, count, method);
    const PixelDirections directions(equirect);
    // Each region's light apart, in parallel; kept in region order.
    std::vector<ExtractedLight> all(regions.size());
    parallelFor(0, static_cast<int64_t>(regions.size()), 1,
                [&](int64_t i) { all[i] = lightOf(regions[i], equirect, directions); });
    for (const ExtractedLight& light : all)
        if (light.irradiance != glm::vec3(0.0f)) lights.push_back(light);
    return lights;
}

void setEnvironment(Scene& scene, Environment environment) {
    const EnvironmentOptions& o = scene.options.environment;
    const std::vector<ExtractedLight> extracted =
        extractLights(environment.radiance, o.lightCount, o.extraction);
    // The sky term is gathered by the cones only: with the map's light traced by rays it is not needed.
    const bool skyByCones = o.sky && scene.options.shadow.method == ShadowMethod::Cones;
    environment.sky = skyByCones ? prefilterSky(environment.radiance, extracted) : SkyPyramid{};
    std::erase_if(scene.lights, [](const Light& l) { return l.fromEnvironment; });
    // A light's shadow cone is as wide as its region of sky, but never narrower than other lights' cones.
    const float minHalfAngle = 0.5f * glm::radians(scene.options.shadow.apertureDeg);
    const float maxHalfAngle = std::max(0.5f * glm::radians(o.maxLightApertureDeg), minHalfAngle);
    for (const ExtractedLight& e : extracted) {
        Light light;
        light.type = Light::Type::Directional;
        light.direction = -glm::normalize(environment.worldFromEnvironment * e.direction);
        light.color = e.irradiance;
        light.intensity = 1.0f;
        light.fromEnvironment = true;
        const float regionHalfAngle =
            std::acos(std::clamp(1.0f - e.solidAngle / (2.0f * std::numbers::pi_v<float>), -1.0f, 1.0f));
        light.angularRadius = std::clamp(regionHalfAngle, minHalfAngle, maxHalfAngle);
        scene.lights.push_back(light);
    }
    scene.environment = std::move(environment);
}

}  // namespace deltagi
