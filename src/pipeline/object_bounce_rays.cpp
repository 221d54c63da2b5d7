#include "pipeline/object_bounce_rays.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include "core/brdf_sampling.h"
#include "pipeline/cone_trace.h"

namespace deltagi {

namespace {
constexpr int64_t kPointGrain = 64;
constexpr uint32_t kBounceStream = 7200;

// Where volumeRadianceAt reads `volume` (and any volume of its region) for `hit`: at `level`, half a voxel
// off the surface on the ray's side.
VolumeLookup lookupOffSurface(const MipVolume& volume, const RayLanding& hit, float level = 0.0f) {
    const VolumeRegion& region = volume.region();
    const float invVoxel = 1.0f / region.voxelSize();
    return volume.lookup(
        (hit.position + 0.5f * region.voxelSize() * hit.geometricNormal - region.origin) * invVoxel, level);
}

glm::vec3 radianceOf(glm::vec4 l) {
    return l.w > 1e-6f ? glm::vec3(l) / l.w : glm::vec3(0.0f);
}

}  // namespace

glm::vec3 volumeRadianceAt(const MipVolume& light, const RayLanding& hit, float level) {
    return radianceOf(light.gather(lookupOffSurface(light, hit, level)));
}

glm::vec3 volumeRadianceWithChangeAt(const MipVolume& light, const MipVolume& change, const RayLanding& hit,
                                     float level) {
    assert(light.region().origin == change.region().origin && light.region().size == change.region().size &&
           light.region().resolution == change.region().resolution &&
           light.levelCount() == change.levelCount());
    const VolumeLookup where = lookupOffSurface(light, hit, level);
    // The change is the light the objects hide from a surface (and theirs) against its light gathered
    // apart (the room's further bounces, by few rays from farther away): it may take away more than there
    // is. A surface reflects no less than nothing.
    return glm::max(radianceOf(light.gather(where) + change.gather(where)), glm::vec3(0.0f));
}

glm::vec3 volumeRadianceDifferenceAt(const MipVolume& a, const MipVolume& b, const RayLanding& hit) {
    assert(a.region().origin == b.region().origin && a.region().size == b.region().size &&
           a.region().resolution == b.region().resolution && a.levelCount() == b.levelCount());
    const VolumeLookup where = lookupOffSurface(a, hit);  // b's too: they share their region
    return radianceOf(a.gather(where)) - radianceOf(b.gather(where));
}

std::vector<glm::vec3> traceObjectBounceRays(std::span<const SurfacePoint> points,
                                             const MipVolume& objectLight, const ShadowRayScenes& rays,
                                             const Options& options, std::span<const uint32_t> pixels,
                                             RealLight realLight) {
    std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
    if (!rays.scene || !rays.objects || rays.objectBounds.empty()) return out;
    const float offset = shadowRayOffset(*rays.scene);
    const glm::vec3 centre = rays.objectBounds.center();
    const float radius = rays.boundingRadius();
    // At least one ray a point, also with object_rays 0: the relit cones leave the objects to these rays.
    const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(
                                     static_cast<float>(squareSampleCount(options.diffuse.objectRays))))));
    const int count = side * side;
    constexpr float kPi = std::numbers::pi_v<float>;

    forEachValidPoint(points, pixels, kPointGrain, [&](int64_t i) {
        const SurfacePoint& p = points[i];
        if (p.surface.diffuse == glm::vec3(0.0f)) return;
        const glm::vec3 origin = p.position + offset * p.normal;
        const glm::vec3 toCentre = centre - origin;
        const float distance = glm::length(toCentre);
        // The objects wholly behind the surface send it nothing.
        if (distance > radius && glm::dot(toCentre, p.normal) < -radius) return;
        // Inside the bounding sphere every direction may meet them: the cosine-weighted hemisphere.
        const bool inside = distance <= radius * 1.0001f;
        const float cosMax =
            inside ? 0.0f : std::sqrt(std::max(0.0f, 1.0f - (radius * radius) / (distance * distance)));
        const glm::mat3 frame = frameAround(inside ? p.normal : toCentre / distance);
        const float jitterU = hashToUnit(i, kBounceStream), jitterV = hashToUnit(i, kBounceStream + 1);
        glm::vec3 sum(0.0f);
        for (int k = 0; k < count; ++k) {
            const auto [u1, u2] = jitteredGridPoint(k, side, jitterU, jitterV);
            glm::vec3 wi;
            float weight;  // cos / (pi pdf)
            if (inside) {
                wi = frame * sampleCosineHemisphere(u1, u2);
                weight = 1.0f;
            } else {
                const float cosTheta = 1.0f - u1 * (1.0f - cosMax);
                const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
                const float phi = 2.0f * kPi * u2;
                wi = frame * glm::vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
                const float cosSurface = glm::dot(wi, p.normal);
                if (cosSurface <= 0.0f) continue;
                weight = cosSurface * 2.0f * (1.0f - cosMax);  // cos / (pi * 1 / (2 pi (1 - cosMax)))
            }
            // Only where it lands counts (volumeRadianceAt).
            const RayLanding hit = rays.objects->landTopLayer(origin, wi);
            if (!hit.hit()) continue;
            if (rays.scene->occluded(origin, wi, 0.0f, hit.t)) continue;
            glm::vec3 radiance = volumeRadianceAt(objectLight, hit);
            if (realLight.full && realLight.delta) {
                // The real surface the ray met before the objects were there, and its light then.
                const RayLanding hidden = rays.scene->land(origin, wi, hit.t);
                if (hidden.hit())
                    radiance -= volumeRadianceDifferenceAt(*realLight.full, *realLight.delta, hidden);
            }
            sum += radiance * weight;
        }
        out[i] = sum / static_cast<float>(count);
    });
    return out;
}

}  // namespace deltagi
