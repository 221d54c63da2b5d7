#include "inject.h"

#include <algorithm>
#include <numbers>

#include "parallel.h"

namespace deltagi {

namespace {
// Texel footprints tile a lit surface only up to the RSM's sampling: a fully lit voxel collects between about
// (k-1)^2 and (k+1)^2 texels of k^2. A voxel whose footprints cover this fraction of its area counts as fully
// lit; below it, the radiance is scaled by the covered fraction (partly shadowed voxels).
constexpr float kFullCoverage = 0.75f;
}  // namespace

Grid3 injectLight(std::span<const ReflectiveShadowMap> rsms, const VolumeRegion& region,
                  std::span<const VoxelGeometry* const> geometry) {
    const int n = region.resolution;
    const float invVoxel = 1.0f / region.voxelSize();

    // All texels of all lights, in light and texel order, each with its voxel.
    struct Splat {
        const RsmTexel* texel;
        uint32_t voxel;
        int z;
    };
    std::vector<Splat> splats;
    for (const ReflectiveShadowMap& rsm : rsms) {
        for (const RsmTexel& t : rsm.texels) {
            glm::ivec3 v = glm::clamp(glm::ivec3(glm::floor((t.position - region.origin) * invVoxel)),
                                      glm::ivec3(0), glm::ivec3(n - 1));
            splats.push_back(
                {&t, static_cast<uint32_t>((static_cast<size_t>(v.z) * n + v.y) * n + v.x), v.z});
        }
    }
    const int slabCount = (n + kSlabThickness - 1) / kSlabThickness;
    const SlabBins bins = binBySlab(splats.size(), slabCount, [&](size_t i) {
        int s = splats[i].z / kSlabThickness;
        return std::pair{s, s};
    });

    // Per voxel: reflected flux (rgb) and the texels' footprint area.
    Grid3 accum(n);
    parallelFor(0, slabCount, 1, [&](int64_t s) {
        for (uint32_t i : bins.slab(s)) {
            const Splat& sp = splats[i];
            accum[sp.voxel] += glm::vec4(sp.texel->flux, sp.texel->area);
        }
    });

    Grid3 light(n);
    parallelFor(0, static_cast<int64_t>(light.size()), 1 << 14, [&](int64_t i) {
        float occupancy = 0.0f, area = 0.0f;
        glm::vec3 emitted(0.0f);  // radiance times area
        for (const VoxelGeometry* g : geometry) {
            occupancy = std::max(occupancy, g->visibility[i].x);
            area += g->area[i];
            if (!g->emission.empty()) emitted += g->emission[i];
        }
        const glm::vec4 a = accum[i];  // (reflected flux, footprint area)
        glm::vec3 radiance(0.0f);
        if (a.w > 0.0f) {
            occupancy = 1.0f;
            // Mean radiance of the lit texels, times the lit fraction of the voxel's surface.
            const float litFraction = area > 0.0f ? std::min(1.0f, a.w / (kFullCoverage * area)) : 1.0f;
            radiance = glm::vec3(a) * (litFraction / (std::numbers::pi_v<float> * a.w));
        }
        // Emissive surfaces add their own radiance, averaged over all the surface area in the voxel.
        if (area > 0.0f && emitted != glm::vec3(0.0f)) radiance += emitted / area;
        light[i] = glm::vec4(radiance * occupancy, occupancy);
    });
    return light;
}

Grid3 deltaVolume(const Grid3& full, const Grid3& sceneOnly) {
    Grid3 delta(full.resolution());
    parallelFor(0, static_cast<int64_t>(delta.size()), 1 << 14, [&](int64_t i) {
        const glm::vec4 f = full[i], s = sceneOnly[i];
        delta[i] = glm::vec4(f.x - s.x, f.y - s.y, f.z - s.z, f.w);
    });
    return delta;
}

}  // namespace deltagi
