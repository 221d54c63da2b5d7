// Stage 6, the objects' light on the real surfaces near them, and the real light they block, by rays (beyond
// the paper).
//
// The diffuse cones of §3.1 gather the objects' light through coarse voxels: a cone that starts next to an
// object sees it through voxels larger than the gap, and the light a ball sends onto the ground beside it
// (its contact bounce) comes out at a third of the path tracer's. The same coarse voxels decide how much of
// the real scene's light the objects block: a coarse voxel that holds a statue and the floor under it is
// as opaque as the floor, so a cone from the ceiling hardly sees the statue in front of the lit floor, while
// cones near the statue see it over-wide (Cornell box + Happy Buddha with a black statue, against the path
// tracer: the ceiling's darkening 0.2 of the truth's, the floor in front of the statue twice the truth's).
// Here each relit point casts rays into the cone of directions that holds the objects' bounding sphere,
// against the objects' triangles and the real scene's. Where a ray meets an object first, it brings the
// objects' light there (the objects' light volume at level 0, the radiance of the object's voxels there)
// and takes away the real scene's light that the ray met before the objects were there (the light volume
// of the real scene alone where the ray, continued through the objects, meets a real surface). The diffuse
// cones then carry only the change of the real surfaces' own light (the objects' shadows on them), seen
// through the real scene's visibility.
#pragma once

#include <span>
#include <vector>

#include "deltagi/scene.h"
#include "pipeline/gbuffer.h"
#include "pipeline/shadow_rays.h"
#include "pipeline/volume.h"

namespace deltagi {

// For every point listed in `pixels` (all when empty): the change the objects make to the light reaching it
// along the directions where they are, as the diffuse cones' result (the cosine-weighted mean radiance over
// the hemisphere, E / pi), from options.diffuse.object_rays rays spread uniformly over the cone of directions
// of the objects' bounding sphere, as many from afar as from nearby: the objects' light
// (`objectLight`, their share of the full light volume, ObjectVolumes::objectLight) minus, with `realLight`,
// the real scene's light they hide. `realLight`: the full and the delta light volume, whose difference is the
// real scene's light without the objects; null: the objects' light only. Zero where the objects are behind
// the surface or the rays meet none.
struct RealLight {
    const MipVolume* full = nullptr;
    const MipVolume* delta = nullptr;
};
std::vector<glm::vec3> traceObjectBounceRays(std::span<const SurfacePoint> points,
                                             const MipVolume& objectLight, const ShadowRayScenes& rays,
                                             const Options& options, std::span<const uint32_t> pixels = {},
                                             RealLight realLight = {});

// The radiance of `light`'s level-0 voxels where a ray meets a surface, half a voxel out on the ray's side of
// it (the volume's values over their occupancy); zero where no voxel there is occupied. At a `level` above 0,
// the mean radiance of that mip level's voxels there.
glm::vec3 volumeRadianceAt(const MipVolume& light, const RayLanding& hit, float level = 0.0f);
// volumeRadianceAt(a, hit) - volumeRadianceAt(b, hit) for two volumes of one region, whose lookup is worked
// out once (the same values).
glm::vec3 volumeRadianceDifferenceAt(const MipVolume& a, const MipVolume& b, const RayLanding& hit);
// volumeRadianceAt(light, hit, level) with `change` added to `light`'s radiance channels (a volume of the
// same region whose w is 0: ObjectVolumes::roomChange), in the one lookup; at least 0.
glm::vec3 volumeRadianceWithChangeAt(const MipVolume& light, const MipVolume& change, const RayLanding& hit,
                                     float level = 0.0f);

}  // namespace deltagi
