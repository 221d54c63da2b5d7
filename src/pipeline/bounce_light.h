// Stage 3b: light that bounces more than once. The reflective shadow maps inject the surfaces the lights
// reach directly, so the cones of §3.1 gather one bounce of indirect light; in a closed room of bright walls
// the further bounces are a quarter or more of the light (the Cornell box: the real scene's mean radiance is
// 0.27 with one bounce and 0.37 with all of them, in the path tracer). bounceLight() gathers the light volume
// at every surface voxel of the real scene with options.render.bounce_cones cones, reflects it by the voxel's
// albedo, and adds it to the volume, as many times as asked: each pass adds one bounce. The bounces beyond
// the last are added as a geometric series of it (options.render.bounce_tail): in a closed room they are as
// much light as the last one gathered.
//
// It runs on the real scene alone, once while the real side stays the same (FrameRenderer keeps it), and the
// result is added to the full light volume as well, so that the delta volume keeps only what the objects
// change directly: the objects receive the room's bounced light, and the light they block between real
// surfaces (options.render.relight_cones "differential") carries it too. The objects' own light is not
// bounced again, and neither is the change they make.
#pragma once

#include <optional>

#include "core/ray_scene.h"
#include "deltagi/options.h"
#include "pipeline/inject.h"
#include "pipeline/volume.h"
#include "pipeline/voxelize.h"

namespace deltagi {

// The unit mean normal of a visibility voxel (occupancy, occupancy times the mean normal) to gather around:
// none where the voxel is empty or its surfaces face several ways (a mean normal shorter than 0.2, a corner's
// two faces), where a hemisphere is not defined.
std::optional<glm::vec3> gatheringNormal(glm::vec4 voxel);

// The surface of `scene` (its top layer) that a voxel of `size` about `centre` holds on the side of `normal`:
// the first one a ray meets coming in along -normal from a voxel away (within one and a half voxels).
RayLanding voxelSurfaceAlong(const RayScene& scene, glm::vec3 centre, glm::vec3 normal, float size);

// The light `bounces` further bounces add to `direct` (level 0 of the real scene's light volume: radiance
// times occupancy, occupancy): radiance at each surface voxel of `geometry`, to be added to it (addBounce).
// `geometry` is the scene's voxelization with albedo (voxelize's `withAlbedo`), `visibility` its visibility
// mip chain.
// The light is gathered at the voxels of the mip level that has 16^3 (level 3 at 128^3: each gathers for its
// 512 level-0 voxels, whose albedos reflect it), around the voxel's mean normal, turned to face `viewpoint`
// (the camera, which stands in the room it sees: surfaces are two-sided, and a reconstruction's winding does
// not say which side is the room's). With `rays` (the real scene) and options.render.bounce_rays > 0 a voxel
// gathers by that many rays from the surface its normal meets, or where none is met from its face
// (gatherOverHemisphere: the light of the level-0 voxels where they land); otherwise by the bounce cones of
// `options`. The
// cones read far surfaces through coarse voxels that average them with their surroundings: on the Cornell
// box's floor under a bare bulb 10 cm below the ceiling they gather a fifth of the ceiling's light. With
// options.render.bounce_tail the last bounce is added again times r / (1 - r), r the ratio of its light to
// the one before's over the geometry's surfaces (per colour channel). Deterministic for any thread count;
// zero for bounces <= 0.
// `written`: the voxels injectLight may have made non-zero in `direct` over `geometry` alone (null: any).
SurfaceRadiance bounceLight(const Grid3& direct, const VoxelGeometry& geometry, const MipVolume& visibility,
                            const Options& options, int bounces, glm::vec3 viewpoint,
                            const RayScene* rays = nullptr, const InjectedVoxels* written = nullptr);

// light += bounced at the surface voxels of `geometry` (occupancy unchanged), where `bounced` is
// bounceLight's result over it; in parallel.
void addBounce(Grid3& light, const SurfaceRadiance& bounced, const VoxelGeometry& geometry);

// Which side of each gathering voxel faces `viewpoint` (per voxel of bounceLight's gathering level: true
// where it is the side against the voxel's mean normal): bounceLight's result for two viewpoints is the same
// where these are (FrameRenderer keeps it while the camera moves).
std::vector<bool> bounceViewSides(const MipVolume& visibility, glm::vec3 viewpoint);

// The virtual objects' own reflection of the light they receive (their further bounce): the light volume
// `light` gathered at every mip-`level` voxel of the objects inside `box` (level-0 voxels), around its mean
// normal (objects are closed and wound outwards), occluded by the scene and the objects, and reflected by
// each level-0 voxel's albedo (`objects` voxelized with albedo). Returns the radiance to add per level-0
// voxel of `box`, row by row (box.count() entries, x fastest), zero where no object is.
std::vector<glm::vec3> gatherObjectBounce(const MipVolume& light, const VoxelGeometry& objects,
                                          const MipVolume& objectVisibility, const MipVolume& sceneVisibility,
                                          const Options& options, const VoxelBox& box, int level);

// gatherObjectBounce by rays (options.diffuse.object_rays of them per coarse voxel): the cones of a coarse
// voxel start half a voxel and more off its surfaces, so that under an object standing on the floor they
// start below the floor and the object's underside gets none of the floor's light. Each coarse voxel finds
// its objects' outer surface along its mean normal (a ray against `scene`'s top layer, the objects) and casts
// cosine-distributed rays from there against the objects and the real scene (`scene` and its base); a ray's
// light is that of `light`'s level-0 voxels where it ends. Voxels whose surface is not found gather through
// the cones as gatherObjectBounce does. Same form of result.
std::vector<glm::vec3> gatherObjectBounceByRays(const MipVolume& light, const VoxelGeometry& objects,
                                                const MipVolume& objectVisibility,
                                                const MipVolume& sceneVisibility, const RayScene& scene,
                                                const Options& options, const VoxelBox& box, int level);

}  // namespace deltagi
