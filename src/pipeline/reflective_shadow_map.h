// Stage 2: reflective shadow maps (Dachsbacher & Stamminger 2005), one per light: the surfaces the light sees
// directly, with position, normal and the flux they reflect diffusely. Rendered by casting one ray per texel
// from the light; rendered once for the real scene with the virtual objects and once for the real scene alone
// (§3.2). Only texels whose surface lies inside the volume region are kept, since only they are injected.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "core/large_blocks.h"
#include "core/ray_scene.h"
#include "deltagi/renderer.h"

namespace deltagi {

// No default member initializers: a map's texels are sized without a value and copied in (RsmTexels);
// RsmTexel{} is all zeros.
struct RsmTexel {
    glm::vec3 position;
    glm::vec3 normal;  // the shading normal (without normal maps), facing the light
    glm::vec3 flux;    // reflected flux (W): Material::volumeReflectance() * flux arriving through the texel
    float area;        // surface area the texel covers (world units^2)
    uint32_t index;    // face * resolution^2 + row * resolution + column: the texel's place in the map
};

// A map's texels: large blocks (core/large_blocks.h), recycled from map to map, sized without a value.
using RsmTexels = std::vector<RsmTexel, UnsetAllocator<RsmTexel>>;

// The level-0 voxel that a texel at a position is injected into (the region's far faces count to the last
// voxel).
class TexelVoxels {
  public:
    explicit TexelVoxels(const VolumeRegion& region)
        : origin_(region.origin), invVoxel_(1.0f / region.voxelSize()), n_(region.resolution) {}
    glm::ivec3 operator()(glm::vec3 position) const {
        // Truncated rather than floored: the two differ only below 0, where both are clamped to 0.
        return glm::clamp(glm::ivec3((position - origin_) * invVoxel_), glm::ivec3(0), glm::ivec3(n_ - 1));
    }
    // Its index in the level-0 grid.
    uint32_t index(glm::vec3 position) const {
        const glm::ivec3 v = (*this)(position);
        return static_cast<uint32_t>((static_cast<size_t>(v.z) * n_ + v.y) * n_ + v.x);
    }

  private:
    glm::vec3 origin_;
    float invVoxel_;
    int n_;
};

struct ReflectiveShadowMap {
    int resolution = 0;  // texels per face side
    int faces = 0;       // 1 (a frustum fitted to the region, or orthographic) or 6 (light inside the region)
    float rayStart = 0.0f;  // directional lights: how far behind the region's centre the rays start
    RsmTexels texels;       // the texels that hit a surface inside the region, in texel order
    // Each texel's voxel in `voxelRegion` (TexelVoxels::index), in texel order: found as the map is rendered,
    // while its texels are at hand, so that the injection need not read their positions again (a few MiB
    // of texels a light, read twice at every light change). A map put together otherwise has none.
    std::vector<uint32_t, UnsetAllocator<uint32_t>> voxels;
    VolumeRegion voxelRegion;
    // The texels' voxels in `region`, or an empty span where the map does not hold them.
    std::span<const uint32_t> voxelsIn(const VolumeRegion& region) const {
        const bool held = voxels.size() == texels.size() && voxelRegion.origin == region.origin &&
                          voxelRegion.size == region.size && voxelRegion.resolution == region.resolution;
        return held ? std::span<const uint32_t>(voxels) : std::span<const uint32_t>{};
    }
};

// The face resolution of each light's map (options.rsm.resolution): the given one for all, or "auto": the
// ceiling (rsmResolutionCeiling) for the light that brings the most light into `region`, and for each other
// light the ceiling times sqrt(E / E_max), rounded down to a power of two and at least the ceiling /
// kAutoRsmMinShare, where E is a light's largest irradiance at the region's centre and corners (facing it).
std::vector<int> rsmResolutions(const Options& options, std::span<const Light> lights,
                                const VolumeRegion& region);

// With a `viewpoint` (the camera), a directional light's texel on a real surface is kept only where the
// surface's lit side faces the viewpoint: a voxel stores one radiance for both sides of its surfaces, and a
// light from outside the scene reaches sides of it that are not the room's (a reconstruction's other side is
// not modelled: the underside of a ground plane lit by an environment map's lower half would light the
// ground's top in the volume). The rays still stop there. A point or spot light stands in the room, so every
// surface its rays meet first is lit on the room's side: all of its texels are kept, also on the sides of
// real objects that face away from the camera (the Cornell box's short block, lit at a grazing angle on the
// side that faces the Buddha, lights the statue from there). Virtual objects are closed; their texels are
// all kept.
ReflectiveShadowMap renderReflectiveShadowMap(const RayScene& scene, const Light& light,
                                              const VolumeRegion& region, int resolution,
                                              std::optional<glm::vec3> viewpoint = std::nullopt);

// Which side of each real triangle's plane `viewpoint` is on, for the texels renderReflectiveShadowMap keeps:
// per triangle of `meshes` in order, +1 or -1, and 0 where the viewpoint is too close to the plane to tell
// (within a ten-thousandth of its distance to the triangle and the triangle's size, far more than the hit
// points' rounding). The maps of two viewpoints are the same where these are, with no 0 (FrameRenderer keeps
// them while the camera moves).
std::vector<int8_t> rsmViewSides(std::span<const TriangleMesh> meshes, glm::vec3 viewpoint);

// Texel indices [first, last).
struct TexelRange {
    uint32_t first = 0, last = 0;
};

// What objects change in a map, per frame: the texels whose rays can meet the objects, traced again.
struct RsmUpdate {
    // Increasing (one range per row of a face); every texel outside them is the base map's. One range over
    // every index when the map is rendered afresh.
    std::vector<TexelRange> retraced;
    RsmTexels texels;       // the retraced texels that hit a surface inside the region, in texel order
    float rayStart = 0.0f;  // the map's with the objects (ReflectiveShadowMap::rayStart)
};

// The update of `base` for `scene` = the scene `base` was rendered over (same light, region and resolution)
// plus objects inside `changed` (world bounds): the texels whose rays cannot meet `changed` (outside its
// projection onto each face, clipped to the light's front) are left to `base`, the others are traced again.
// When `scene` is layered over the base scene (RayScene's `base`), a ray that misses the top layer takes the
// base map's texel without being traced below it. A directional light whose ray origins the objects move is
// rendered afresh.
RsmUpdate traceRsmUpdate(const ReflectiveShadowMap& base, const RayScene& scene, const Light& light,
                         const VolumeRegion& region, const Bounds3f& changed,
                         std::optional<glm::vec3> viewpoint = std::nullopt);

// `base` with `update`'s texels: renderReflectiveShadowMap() over the update's scene, texel for texel.
ReflectiveShadowMap applyRsmUpdate(const ReflectiveShadowMap& base, const RsmUpdate& update);

// applyRsmUpdate(base, traceRsmUpdate(base, scene, light, region, changed)).
ReflectiveShadowMap updateReflectiveShadowMap(const ReflectiveShadowMap& base, const RayScene& scene,
                                              const Light& light, const VolumeRegion& region,
                                              const Bounds3f& changed);

}  // namespace deltagi
