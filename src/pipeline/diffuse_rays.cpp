#include "pipeline/diffuse_rays.h"

#include <algorithm>
#include <cmath>

#include "core/brdf_sampling.h"
#include "pipeline/cone_trace.h"
#include "pipeline/object_bounce_rays.h"
#include "pipeline/shadow_rays.h"

namespace deltagi {

namespace {
constexpr int64_t kPointGrain = 16;
constexpr uint32_t kGatherStream = 7300;  // hashToUnit streams of the grid's jitter
}  // namespace

namespace {
// The level of a footprint `width` level-0 voxels wide.
float footprintLevel(float width, float maxLevel) {
    return width > 1.0f ? std::min(std::log2(width), maxLevel) : 0.0f;
}
}  // namespace

float rayFootprintTan(int count) {
    // A cone of solid angle 2 pi / count: 2 pi (1 - cos a) = 2 pi / count.
    const float cosHalf = 1.0f - 1.0f / static_cast<float>(std::max(count, 1));
    return std::sqrt(std::max(0.0f, 1.0f - cosHalf * cosHalf)) / std::max(cosHalf, 1e-3f);
}

float rayFootprintLevel(float distance, int count, float voxelSize, float maxLevel) {
    return footprintLevel(distance * rayFootprintTan(count) / voxelSize, maxLevel);
}

glm::vec3 gatherOverHemisphere(const RayScene& scene, const MipVolume& light, glm::vec3 origin,
                               glm::vec3 normal, int side, glm::vec2 jitter, float tMin, float footprintTan,
                               const MipVolume* change) {
    const glm::mat3 frame = frameAround(normal);
    const float voxelSize = light.region().voxelSize();
    const float maxLevel = static_cast<float>(light.levelCount() - 1);
    glm::vec3 sum(0.0f);
    const int count = side * side;
    for (int k = 0; k < count; ++k) {
        const auto [u1, u2] = jitteredGridPoint(k, side, jitter.x, jitter.y);
        const glm::vec3 wi = frame * sampleCosineHemisphere(u1, u2);
        const RayLanding hit = scene.land(origin, wi, tMin);
        if (!hit.hit()) continue;
        const float level =
            footprintTan > 0.0f ? footprintLevel(hit.t * footprintTan / voxelSize, maxLevel) : 0.0f;
        sum += change ? volumeRadianceWithChangeAt(light, *change, hit, level)
                      : volumeRadianceAt(light, hit, level);
    }
    return sum / static_cast<float>(count);
}

std::vector<glm::vec3> traceDiffuseRays(std::span<const SurfacePoint> points, const MipVolume& light,
                                        const RayScene& scene, int rays, std::span<const uint32_t> pixels,
                                        const MipVolume* lightChange) {
    if (lightChange && lightChange->empty()) lightChange = nullptr;
    std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
    const int count = squareSampleCount(std::max(rays, 1));
    const int side = static_cast<int>(std::lround(std::sqrt(static_cast<float>(count))));
    const float offset = shadowRayOffset(scene);
    const float footprintTan = rayFootprintTan(count);
    forEachValidPoint(points, pixels, kPointGrain, [&](int64_t i) {
        const SurfacePoint& p = points[i];
        if (p.surface.diffuse == glm::vec3(0.0f)) return;
        const glm::vec2 jitter(hashToUnit(i, kGatherStream), hashToUnit(i, kGatherStream + 1));
        out[i] = gatherOverHemisphere(scene, light, p.position + offset * p.normal, p.normal, side, jitter,
                                      0.0f, footprintTan, lightChange);
    });
    return out;
}

}  // namespace deltagi
