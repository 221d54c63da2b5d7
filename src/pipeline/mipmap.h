// Stage 4: mipmaps of a volume (§3.1, Fig. 1a). A coarse voxel is the mean of its 2x2x2 children, so the
// occlusion of a coarse voxel is the fraction of filled sub-voxels (§3.2). Each level is stored in bfloat16
// (PackedGrid3): a mean is taken in floats over the stored children and rounded once.
#pragma once

#include "pipeline/volume.h"

namespace deltagi {

// Takes the level-0 grid (resolution a power of two) and returns it with levels down to 1^3.
MipVolume buildMipChain(const VolumeRegion& region, PackedGrid3 level0);
// The same where the caller knows a box around level 0's non-zero voxels (MipVolume::occupiedBounds: a
// superset gives the same lookups), which is then not found by reading every voxel.
MipVolume buildMipChain(const VolumeRegion& region, PackedGrid3 level0, const VoxelBox& occupied);
// The same from a level 0 in floats, rounded to bfloat16 first.
MipVolume buildMipChain(const VolumeRegion& region, const Grid3& level0);

// One level down: each voxel of the result is the mean of 8 voxels of `fine` (resolution must be even).
PackedGrid3 downsample(const PackedGrid3& fine);

// The same chain after level 0 of `volume` was rewritten inside `changed` (level-0 voxels) and nowhere else:
// the voxels above `changed` are the means of their children again, level by level, and nothing else is
// touched, so the cost is that of the box. `occupied` must hold every non-zero level-0 voxel
// (mayReadNonZero). The levels equal buildMipChain's over the new level 0, bit for bit.
void updateMipChain(MipVolume& volume, const VoxelBox& changed, const VoxelBox& occupied);

}  // namespace deltagi
