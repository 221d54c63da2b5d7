#include "pipeline/bounce_light.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/brdf_sampling.h"
#include "core/parallel.h"
#include "pipeline/cone_trace.h"
#include "pipeline/diffuse_rays.h"
#include "pipeline/mipmap.h"
#include "pipeline/object_bounce_rays.h"
#include "pipeline/shadow_rays.h"

namespace deltagi {

namespace {

// The mip level whose voxels gather: the one of kGatherResolution^3 voxels (level 3 at 128^3, each gathering
// for 8 x 8 x 8 level-0 voxels), or level 0 in smaller volumes. At 128^3 level 2 gathered 8 times as many
// (the live frame's bounce_ms 42 -> 22, `deltagi bench --live`) for the same quality-suite figures (every
// delta_rel_error 0.0003-0.0012 better, object_rel_rmse within 0.001 or better), and level 1 64 times as many
// (bounce_ms 98 -> 35 to level 2, delta_rel_error within 0.0001).
constexpr int kGatherResolution = 16;
int gatherLevel(const MipVolume& visibility) {
    int level = 0;
    while ((visibility.region().resolution >> (level + 1)) >= kGatherResolution) ++level;
    return level;
}
constexpr uint32_t kBounceStream = 9000;  // hashToUnit streams of the cones' jitter

// Surfaces are two-sided and the winding of a reconstruction is not reliable: the side of a voxel that
// gathers is the one facing the viewpoint; true where that is the side against its mean normal.
bool facesAway(glm::vec3 meanNormal, glm::vec3 centre, glm::vec3 viewpoint) {
    return glm::dot(meanNormal, viewpoint - centre) < 0.0f;
}

// A coarse voxel to gather at: its centre, the normal it gathers around, its index (the cones' jitter).
struct VoxelGather {
    glm::vec3 centre{0.0f}, normal{0.0f};
    size_t index = 0;
};

// The diffuse cones' light (cosine-weighted, so that albedo times it is the reflected radiance) gathered at
// coarse voxels of `size` (world units) around their normals, from each voxel's face along the normal so that
// its own surfaces do not occlude; jittered by the voxel's index. The cones of all the voxels are traced
// together (in SIMD lanes).
void gatherAtVoxels(std::span<const VoxelGather> voxels, float size, const MipVolume& light,
                    const VisibilityVolumes& occluders, const DiffuseConeSet& cones,
                    const ConeTraceSettings& settings, std::span<glm::vec3> out) {
    const size_t perVoxel = cones.directions.size();
    std::vector<Cone> batch;
    batch.reserve(voxels.size() * perVoxel);
    for (const VoxelGather& v : voxels)
        appendDiffuseCones(batch, cones, v.centre + (0.5f * size) * v.normal, v.normal, light.region(),
                           settings, v.index, kBounceStream);
    std::vector<glm::vec3> arriving(batch.size());
    traceLightCones(batch, light, occluders, settings, arriving);
    for (size_t j = 0; j < voxels.size(); ++j) out[j] = diffuseConesLight(cones, &arriving[j * perVoxel]);
}

glm::vec3 gatherAtVoxel(glm::vec3 centre, glm::vec3 normal, float size, size_t index, const MipVolume& light,
                        const VisibilityVolumes& occluders, const DiffuseConeSet& cones,
                        const ConeTraceSettings& settings) {
    const VoxelGather voxel{centre, normal, index};
    glm::vec3 gathered;
    gatherAtVoxels(std::span(&voxel, 1), size, light, occluders, cones, settings, std::span(&gathered, 1));
    return gathered;
}

// How a voxel of `size` gathers by rays: from the surface of `scene` that its normal meets coming in from a
// voxel away (the outermost one on that side), `side` x `side` cosine-distributed rays that take the light of
// `light`'s level-0 voxels where they land. Where no surface is met (a voxel whose surfaces lie across its
// normal), nullopt: the caller gathers by cones.
struct RayGather {
    const RayScene& scene;
    const MipVolume& light;
    int side;
    float offset;  // shadowRayOffset(scene)
    std::optional<glm::vec3> operator()(glm::vec3 centre, glm::vec3 normal, float size, size_t index,
                                        uint32_t stream) const {
        const RayLanding surface = voxelSurfaceAlong(scene, centre, normal, size);
        if (!surface.hit()) return std::nullopt;
        return from(surface.position + offset * normal, normal, index, stream, offset);
    }
    // The same, from the voxel's face on the normal's side where no surface is met.
    glm::vec3 fromSurfaceOrFace(glm::vec3 centre, glm::vec3 normal, float size, size_t index,
                                uint32_t stream) const {
        if (const auto g = (*this)(centre, normal, size, index, stream)) return *g;
        return from(centre + 0.5f * size * normal, normal, index, stream, 0.0f);
    }

  private:
    glm::vec3 from(glm::vec3 origin, glm::vec3 normal, size_t index, uint32_t stream, float tMin) const {
        const glm::vec2 jitter(hashToUnit(index, stream), hashToUnit(index, stream + 1));
        return gatherOverHemisphere(scene, light, origin, normal, side, jitter, tMin);
    }
};

// The side of the square grid of `count` rays (rounded down to a square number).
int raySide(int count) {
    return static_cast<int>(
        std::lround(std::sqrt(static_cast<float>(squareSampleCount(std::max(count, 1))))));
}

// The cones of a further bounce's gathers (options.render.bounce_cones, with the diffuse cones' aperture).
DiffuseConeSet bounceConeSet(const Options& options) {
    return makeDiffuseCones(options.render.bounceCones, options.diffuse.apertureDeg);
}

// The bounces beyond the last one gathered (options.render.bounce_tail). Each bounce passes on about the same
// share of the light before it (the surfaces' albedo times how much of the scene they see), so the bounces
// after the last form a geometric series of it: last x (r + r^2 + ...) = last x r / (1 - r), where r is the
// ratio of the last bounce's light to the one before's, summed over the scene's surfaces (per colour
// channel). In the path tracer's Cornell box under a bare bulb the third and further bounces are as much as
// the second (r = 0.50-0.54 from bounce to bounce); an open scene, a plane that does not see itself, has
// r near 0. At most kMaxTailRatio: a tail at most 4 times the last bounce.
constexpr double kMaxTailRatio = 0.8;
glm::vec3 tailScale(glm::dvec3 last, glm::dvec3 before) {
    glm::vec3 scale(0.0f);
    for (int c = 0; c < 3; ++c) {
        if (!(before[c] > 0.0) || !(last[c] > 0.0)) continue;
        const double r = std::min(last[c] / before[c], kMaxTailRatio);
        scale[c] = static_cast<float>(r / (1.0 - r));
    }
    return scale;
}

// The sum over the voxels of `geometry`'s surfaces of their surface area times value(k, voxel index), k the
// voxel's place among them: the light of a bounce over the scene's surfaces, up to a constant. Rows are
// summed in parallel and added in order (the same for any thread count).
template <typename Value>
glm::dvec3 areaWeightedSum(const VoxelGeometry& geometry, Value&& value) {
    if (geometry.surfaceRowStart.empty()) return glm::dvec3(0.0);
    std::vector<glm::dvec3> rows(geometry.surfaceRowStart.size() - 1, glm::dvec3(0.0));
    forEachSurfaceVoxel(geometry, [&](size_t row, size_t k, size_t i) {
        const float area = geometry.area[i];
        if (area > 0.0f) rows[row] += glm::dvec3(value(k, i)) * static_cast<double>(area);
    });
    glm::dvec3 total(0.0);
    for (const glm::dvec3& r : rows) total += r;
    return total;
}

}  // namespace

std::optional<glm::vec3> gatheringNormal(glm::vec4 voxel) {
    // A mean normal shorter than this (surfaces facing several ways in one voxel) gathers nothing.
    constexpr float kMinCoherence = 0.2f;
    if (voxel.x <= 0.0f) return std::nullopt;
    const glm::vec3 meanNormal = glm::vec3(voxel.y, voxel.z, voxel.w) / voxel.x;
    const float coherence = glm::length(meanNormal);
    if (coherence < kMinCoherence) return std::nullopt;
    return meanNormal / coherence;
}

RayLanding voxelSurfaceAlong(const RayScene& scene, glm::vec3 centre, glm::vec3 normal, float size) {
    return scene.landTopLayer(centre + size * normal, -normal, 0.0f, 1.5f * size);
}

SurfaceRadiance bounceLight(const Grid3& direct, const VoxelGeometry& geometry, const MipVolume& visibility,
                            const Options& options, int bounces, glm::vec3 viewpoint, const RayScene* rays,
                            const InjectedVoxels* written) {
    const int n = direct.resolution();
    const int level = gatherLevel(visibility);
    SurfaceRadiance indirect(geometry.surfaceVoxels.size(), glm::vec3(0.0f));
    if (bounces <= 0 || !geometry.withAlbedo || visibility.levelCount() <= level) return indirect;
    // Only the surface voxels (VoxelGeometry::surfaceVoxels) reflect light: the passes below visit them
    // alone. (`geometry` covers the whole grid: its arrays are indexed as `direct` is.)
    const int nn = n * n;
    const VolumeRegion& region = visibility.region();
    const PackedGrid3& coarse = visibility.level(level);
    const int m = coarse.resolution();
    const int factor = n / m;  // level-0 voxels per coarse voxel along each axis
    const float coarseSize = region.voxelSize() * static_cast<float>(factor);
    const ConeTraceSettings settings = coneTraceSettings(options.trace);
    const DiffuseConeSet cones = bounceConeSet(options);
    const VisibilityVolumes occluders{&visibility, nullptr, VisibilityVolumes::Self::Scene};
    const bool byRays = rays && options.render.bounceRays > 0;
    const int side = raySide(options.render.bounceRays);
    const float rayOffset = rays ? shadowRayOffset(*rays) : 0.0f;
    std::vector<glm::vec3> gathered(coarse.size());
    const bool tail = options.render.bounceTail;
    // The light the last pass gathered from: the volume's own (emitters' included), then each pass's bounce.
    glm::dvec3 before =
        tail ? areaWeightedSum(geometry, [&](size_t, size_t i) { return glm::vec3(direct[i]); })
             : glm::dvec3(0.0);
    glm::dvec3 gatheredSoFar(0.0);  // the passes' bounces before this one, summed alike
    SurfaceRadiance previous;       // indirect before the last pass (tail with bounces > 1)
    // Rays read level 0 where they land: only the cones need the coarser levels, built every pass. The rays'
    // level 0 is made once and its surface voxels set again each pass: the same voxels as made anew.
    std::optional<MipVolume> rayLight;
    // The box around the rays' level 0's non-zero voxels: found among those the injection wrote where it
    // lists them, else by reading the whole grid.
    const VoxelGeometry* geometries[] = {&geometry};
    auto occupiedBounds = [&](const PackedGrid3& level0) {
        const std::optional<VoxelBox> listed =
            written ? injectedBounds(level0, geometries, *written) : std::nullopt;
        return listed ? *listed : nonZeroBounds(level0, level0.window());
    };
    for (int bounce = 0; bounce < bounces; ++bounce) {
        if (tail && bounce == bounces - 1 && bounces > 1) previous = indirect;
        // The light so far: direct plus the bounces gathered before (at the surface voxels; adding zero
        // elsewhere keeps the bits a sum with a zero grid had).
        auto lightSoFar = [&](size_t k, size_t i) { return direct[i] + glm::vec4(indirect[k], 0.0f); };
        std::optional<MipVolume> coneLight;
        if (byRays && rayLight) {
            PackedGrid3& level0 = rayLight->levelForUpdate(0);
            forEachSurfaceVoxel(geometry,
                                [&](size_t, size_t k, size_t i) { level0.set(i, lightSoFar(k, i)); });
            rayLight->setOccupiedBounds(occupiedBounds(level0));
        } else {
            // Where the injection lists its voxels only they are non-zero.
            auto directLight = [&](size_t i) { return direct[i] + glm::vec4(0.0f); };
            PackedGrid3 total = written && written->listed && direct.whole()
                                    ? packListed(n, geometries, *written, directLight)
                                    : PackedGrid3::fromEach(n, directLight);
            if (bounce > 0)
                forEachSurfaceVoxel(geometry,
                                    [&](size_t, size_t k, size_t i) { total.set(i, lightSoFar(k, i)); });
            if (byRays) {
                const VoxelBox occupied = occupiedBounds(total);
                std::vector<PackedGrid3> levels;
                levels.push_back(std::move(total));
                rayLight.emplace(region, std::move(levels), occupied);
            } else {
                coneLight.emplace(buildMipChain(region, std::move(total)));
            }
        }
        const MipVolume& light = byRays ? *rayLight : *coneLight;
        // Gather at each surface voxel of the coarse level.
        parallelFor(0, static_cast<int64_t>(m) * m, 4, [&](int64_t row) {
            const int z = static_cast<int>(row / m), y = static_cast<int>(row % m);
            std::vector<VoxelGather> voxels;
            for (int x = 0; x < m; ++x) {
                const size_t i = coarse.index(x, y, z);
                const glm::vec4 v = coarse[i];
                gathered[i] = glm::vec3(0.0f);
                const std::optional<glm::vec3> meanNormal = gatheringNormal(v);
                if (!meanNormal) continue;
                const glm::vec3 centre = region.origin + (glm::vec3(x, y, z) + 0.5f) * coarseSize;
                voxels.push_back(
                    {centre, (facesAway(*meanNormal, centre, viewpoint) ? -1.0f : 1.0f) * *meanNormal, i});
            }
            if (byRays) {
                // From the surface the voxel's normal meets, or else from its face on that side.
                const RayGather gather{*rays, light, side, rayOffset};
                for (const VoxelGather& v : voxels)
                    gathered[v.index] = gather.fromSurfaceOrFace(v.centre, v.normal, coarseSize, v.index,
                                                                 kBounceStream + 200);
                return;
            }
            std::vector<glm::vec3> rowLight(voxels.size());
            gatherAtVoxels(voxels, coarseSize, light, occluders, cones, settings, rowLight);
            for (size_t j = 0; j < voxels.size(); ++j) gathered[voxels[j].index] = rowLight[j];
        });
        // Reflect it at every surface voxel of level 0 by the voxel's albedo.
        forEachSurfaceVoxel(geometry, [&](size_t, size_t k, size_t i) {
            const float occupancy = geometry.occupancy(i);
            const int z = static_cast<int>(i / nn), y = static_cast<int>(i % nn) / n,
                      x = static_cast<int>(i % n);
            const glm::vec3 g = gathered[coarse.index(x / factor, y / factor, z / factor)];
            indirect[k] = geometry.albedo[k] * g * occupancy;
        });
        if (!tail) continue;
        const glm::dvec3 sum = areaWeightedSum(geometry, [&](size_t k, size_t) { return indirect[k]; });
        const glm::dvec3 last = sum - gatheredSoFar;
        if (bounce < bounces - 1) {
            before = last;
            gatheredSoFar = sum;
            continue;
        }
        const glm::vec3 scale = tailScale(last, before);
        const bool lastOnly = !previous.empty();
        forEachSurfaceVoxel(geometry, [&](size_t, size_t k, size_t) {
            glm::vec3 b = indirect[k];
            if (lastOnly) b -= previous[k];
            indirect[k] += b * scale;
        });
    }
    return indirect;
}

void addBounce(Grid3& light, const SurfaceRadiance& bounced, const VoxelGeometry& geometry) {
    forEachSurfaceVoxel(geometry,
                        [&](size_t, size_t k, size_t i) { light[i] += glm::vec4(bounced[k], 0.0f); });
}

std::vector<bool> bounceViewSides(const MipVolume& visibility, glm::vec3 viewpoint) {
    const int level = gatherLevel(visibility);
    if (visibility.levelCount() <= level) return {};
    const VolumeRegion& region = visibility.region();
    const PackedGrid3& coarse = visibility.level(level);
    const int m = coarse.resolution();
    const float coarseSize = region.voxelSize() * static_cast<float>(region.resolution / m);
    std::vector<bool> sides(coarse.size(), false);
    for (int z = 0; z < m; ++z)
        for (int y = 0; y < m; ++y)
            for (int x = 0; x < m; ++x) {
                const size_t i = coarse.index(x, y, z);
                const glm::vec4 v = coarse[i];
                if (v.x <= 0.0f) continue;
                const glm::vec3 centre = region.origin + (glm::vec3(x, y, z) + 0.5f) * coarseSize;
                sides[i] = facesAway(glm::vec3(v.y, v.z, v.w) / v.x, centre, viewpoint);
            }
    return sides;
}

namespace {

// Reflects the light `gathered` at each mip-`level` voxel over `box` (coarse voxels lo..hi, row by row) at
// its level-0 voxels by their albedo: gatherObjectBounce's result.
std::vector<glm::vec3> reflectAtObjectVoxels(const VoxelGeometry& objects, const VoxelBox& box, int factor,
                                             glm::ivec3 lo, glm::ivec3 size,
                                             const std::vector<glm::vec3>& gathered) {
    std::vector<glm::vec3> added(box.count(), glm::vec3(0.0f));
    const glm::ivec3 extent = box.hi - box.lo;
    parallelFor(0, static_cast<int64_t>(extent.y) * extent.z, 4, [&](int64_t row) {
        const int z = box.lo.z + static_cast<int>(row / extent.y),
                  y = box.lo.y + static_cast<int>(row % extent.y);
        // The row's surface voxels (the occupied ones), walked along with x for their albedo.
        auto [k, kEnd] = surfaceVoxelsInRow(objects, y, z, box.lo.x);
        for (int x = box.lo.x; x < box.hi.x; ++x) {
            const size_t i = objects.indexOf(x, y, z);
            if (i == VoxelGeometry::kOutside) continue;
            const float occupancy = objects.occupancy(i);
            if (occupancy <= 0.0f || k >= kEnd) continue;
            const glm::vec3 albedo = objects.albedo[k++];
            const glm::ivec3 c = glm::ivec3(x, y, z) / factor - lo;
            const glm::vec3 g = gathered[(static_cast<size_t>(c.z) * size.y + c.y) * size.x + c.x];
            added[(static_cast<size_t>(z - box.lo.z) * extent.y + (y - box.lo.y)) * extent.x +
                  (x - box.lo.x)] = albedo * g * occupancy;
        }
    });
    return added;
}

// Calls gather(x, y, z, centre, normal, size) for every coherent mip-`level` voxel of the objects over `box`,
// in parallel, and returns reflectAtObjectVoxels of what it gives.
template <typename Gather>
std::vector<glm::vec3> gatherAtObjectVoxels(const VoxelGeometry& objects, const MipVolume& objectVisibility,
                                            const VoxelBox& box, int level, Gather&& gather) {
    if (box.empty() || !objects.withAlbedo || objectVisibility.levelCount() <= level)
        return std::vector<glm::vec3>(box.empty() ? 0 : box.count(), glm::vec3(0.0f));
    const VolumeRegion& region = objectVisibility.region();
    const PackedGrid3& coarse = objectVisibility.level(level);
    const int factor = region.resolution / coarse.resolution();
    const float coarseSize = region.voxelSize() * static_cast<float>(factor);
    // The coarse voxels over the box, gathered once each.
    const glm::ivec3 lo = box.lo / factor, hi = (box.hi + factor - 1) / factor;
    const glm::ivec3 size = hi - lo;
    std::vector<glm::vec3> gathered(static_cast<size_t>(size.x) * size.y * size.z, glm::vec3(0.0f));
    parallelFor(0, static_cast<int64_t>(size.y) * size.z, 1, [&](int64_t row) {
        const int z = lo.z + static_cast<int>(row / size.y), y = lo.y + static_cast<int>(row % size.y);
        for (int x = lo.x; x < hi.x; ++x) {
            const glm::vec4 v = coarse.at(x, y, z);
            const std::optional<glm::vec3> meanNormal = gatheringNormal(v);
            if (!meanNormal) continue;
            const glm::vec3 centre = region.origin + (glm::vec3(x, y, z) + 0.5f) * coarseSize;
            // The voxel's index in the whole level seeds its jitter (the level is stored over a window).
            const size_t index = (static_cast<size_t>(z) * coarse.resolution() + y) * coarse.resolution() + x;
            gathered[(static_cast<size_t>(z - lo.z) * size.y + (y - lo.y)) * size.x + (x - lo.x)] =
                gather(index, centre, *meanNormal, coarseSize);
        }
    });
    return reflectAtObjectVoxels(objects, box, factor, lo, size, gathered);
}

}  // namespace

std::vector<glm::vec3> gatherObjectBounce(const MipVolume& light, const VoxelGeometry& objects,
                                          const MipVolume& objectVisibility, const MipVolume& sceneVisibility,
                                          const Options& options, const VoxelBox& box, int level) {
    const ConeTraceSettings settings = coneTraceSettings(options.trace);
    const DiffuseConeSet cones = bounceConeSet(options);
    const VisibilityVolumes occluders{&sceneVisibility, &objectVisibility, VisibilityVolumes::Self::Object};
    return gatherAtObjectVoxels(objects, objectVisibility, box, level,
                                [&](size_t index, glm::vec3 centre, glm::vec3 normal, float size) {
                                    return gatherAtVoxel(centre, normal, size, index, light, occluders, cones,
                                                         settings);
                                });
}

std::vector<glm::vec3> gatherObjectBounceByRays(const MipVolume& light, const VoxelGeometry& objects,
                                                const MipVolume& objectVisibility,
                                                const MipVolume& sceneVisibility, const RayScene& scene,
                                                const Options& options, const VoxelBox& box, int level) {
    const ConeTraceSettings settings = coneTraceSettings(options.trace);
    const DiffuseConeSet cones = bounceConeSet(options);
    const VisibilityVolumes occluders{&sceneVisibility, &objectVisibility, VisibilityVolumes::Self::Object};
    // The objects' outer surface in the voxel: the first one met coming in along the normal (the objects'
    // layer of `scene`, landTopLayer).
    const RayGather gather{scene, light, raySide(options.diffuse.objectRays), shadowRayOffset(scene)};
    return gatherAtObjectVoxels(
        objects, objectVisibility, box, level,
        [&](size_t index, glm::vec3 centre, glm::vec3 normal, float size) {
            if (const auto g = gather(centre, normal, size, index, kBounceStream + 100)) return *g;
            return gatherAtVoxel(centre, normal, size, index, light, occluders, cones, settings);
        });
}

}  // namespace deltagi
