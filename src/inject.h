// Stage 3: light injection (§3.2). The reflective shadow maps' texels are scattered into a light volume that
// stores, per voxel, the radiance its surfaces reflect diffusely. The delta volume is the full light volume
// (real scene + virtual objects) minus the real-scene-only one: negative where a virtual object now blocks
// light that reached real surfaces, positive on the lit virtual objects.
#pragma once

#include <span>

#include "reflective_shadow_map.h"
#include "voxelize.h"

namespace deltagi {

// Radiance of a voxel = the mean radiance of the texels that landed in it (reflected flux / (pi * footprint
// area)), times the lit fraction of the geometry's surface area in the voxel (footprint / area, saturating at
// kFullCoverage in inject.cpp, which absorbs the RSM's sampling jitter). Voxels are (radiance * occupancy,
// occupancy), with occupancy 1 where any of `geometry` touches the voxel. Emissive geometry adds its emitted
// radiance, averaged over the voxel's surface area: the cones then carry the light of emitters (one bounce of
// it: emitted light is not reflected into the volume again). Deterministic for any thread count.
Grid3 injectLight(std::span<const ReflectiveShadowMap> rsms, const VolumeRegion& region,
                  std::span<const VoxelGeometry* const> geometry);

// full - sceneOnly in the radiance channels; the occupancy of `full` (which covers both).
Grid3 deltaVolume(const Grid3& full, const Grid3& sceneOnly);

}  // namespace deltagi
