// Stage 6, the objects' light on the real surfaces near them, by rays (beyond the paper).
//
// The diffuse cones of §3.1 gather the objects' light through coarse voxels: a cone that starts next to an
// object sees it through voxels larger than the gap, and the light a ball sends onto the ground beside it
// (its contact bounce) comes out at a third of the path tracer's. Here each relit point casts rays into the
// cone of directions that holds the objects' bounding sphere, against the objects' triangles and the real
// scene's; where a ray meets an object first, the objects' light volume (level 0, the radiance of the
// object's voxels there) gives the light it sends back. The diffuse cones then carry only the real scene's
// light (with the objects' occlusion), and this adds the objects' own.
#pragma once

#include <span>
#include <vector>

#include "deltagi/scene.h"
#include "pipeline/gbuffer.h"
#include "pipeline/shadow_rays.h"
#include "pipeline/volume.h"

namespace deltagi {

// For every point listed in `pixels` (all when empty): the objects' light reaching it, as the diffuse cones'
// result (the cosine-weighted mean radiance over the hemisphere, E / pi), from options.diffuse.object_rays
// rays spread uniformly over the cone of directions of the objects' bounding sphere. `objectLight` is the
// objects' share of the full light volume (ObjectVolumes::objectLight). Zero where the objects are behind the
// surface or the rays meet none.
std::vector<glm::vec3> traceObjectBounceRays(std::span<const SurfacePoint> points,
                                             const MipVolume& objectLight, const ShadowRayScenes& rays,
                                             const Options& options, std::span<const uint32_t> pixels = {});

// The radiance of `light`'s level-0 voxels where a ray meets a surface, half a voxel out on the ray's side of
// it (the volume's values over their occupancy); zero where no voxel there is occupied.
glm::vec3 volumeRadianceAt(const MipVolume& light, const RayHit& hit);

}  // namespace deltagi
