// Stage 6, the virtual objects' diffuse light by rays into the light volume (beyond the paper).
//
// The diffuse cones of §3.1 read a far surface through voxels as wide as the cone there, and those voxels
// hold what lies around the surface too. A cone from a ball on the floor of a room towards its ceiling 0.4 m
// away reads voxels of 0.3-0.6 m, which average the ceiling with the walls and the floor and grow opaque on
// them before the cone reaches it: under a bare bulb 10 cm under the Cornell box's ceiling, the cones bring
// the ball 61-67 % of the path tracer's first two bounces, and the ball's top half of them. On a detailed
// statue lit by a spot light the same voxels bring too much (the dragon 105-118 %).
//
// Here each traced point casts rays over its hemisphere, cosine-distributed on a jittered grid, against the
// objects' triangles and the real scene's, and each takes the light volume's radiance where it lands, at the
// mip level whose voxels are as wide as the ray's share of the hemisphere is there: the visibility is the
// triangles', and the light is averaged over no more than the ray's footprint.
#pragma once

#include <span>
#include <vector>

#include "core/ray_scene.h"
#include "deltagi/options.h"
#include "pipeline/gbuffer.h"
#include "pipeline/volume.h"

namespace deltagi {

// For every point listed in `pixels` (all when empty): the cosine-weighted mean radiance over its hemisphere
// (the diffuse cones' result, E / pi) from `rays` rays (options.diffuse.object_gather_rays resolved, rounded
// down to a square number) against `scene` (the objects over the real scene), each taking `light`'s radiance
// where it lands (volumeRadianceAt) at the mip level of its footprint there. Zero for points without a
// diffuse part; a ray that meets nothing brings nothing (the environment's light comes through its own rays
// or cones). Deterministic for any thread count: the jitter is seeded by the point's index. With
// `lightChange` (the objects' change of the light around them, ObjectVolumes::roomChange) the rays read
// `light` plus it.
std::vector<glm::vec3> traceDiffuseRays(std::span<const SurfacePoint> points, const MipVolume& light,
                                        const RayScene& scene, int rays,
                                        std::span<const uint32_t> pixels = {},
                                        const MipVolume* lightChange = nullptr);

// The cosine-weighted mean radiance over the hemisphere around `normal` seen from `origin`: side^2 rays on a
// grid jittered by `jitter` (in [0, 1)^2), cosine-distributed, each taking `light`'s radiance where it lands
// on `scene` (from `tMin` on; volumeRadianceAt). At level 0, or with `footprintTan` > 0 at the mip level as
// wide as the distance times it; with `change`, the radiance of `light` plus it
// (volumeRadianceWithChangeAt). A ray that meets nothing brings nothing. traceDiffuseRays' points, the
// objects' coarse voxels (gatherObjectBounceByRays) and the real scene's (bounceLight) gather so.
glm::vec3 gatherOverHemisphere(const RayScene& scene, const MipVolume& light, glm::vec3 origin,
                               glm::vec3 normal, int side, glm::vec2 jitter, float tMin = 0.0f,
                               float footprintTan = 0.0f, const MipVolume* change = nullptr);

// The tangent of the half-angle of a cone of 2 pi / count steradians: a ray's share of the hemisphere when
// `count` rays share it.
float rayFootprintTan(int count);
// The mip level whose voxels are as wide as a ray's footprint at `distance` (world units) when `count` rays
// share the hemisphere: the distance times rayFootprintTan(count), in voxels of `voxelSize`; 0 within a
// voxel, at most `maxLevel`.
float rayFootprintLevel(float distance, int count, float voxelSize, float maxLevel);

}  // namespace deltagi
