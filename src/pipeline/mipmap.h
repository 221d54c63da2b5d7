// Stage 4: mipmaps of a volume (§3.1, Fig. 1a). A coarse voxel is the mean of its 2x2x2 children, so the
// occlusion of a coarse voxel is the fraction of filled sub-voxels (§3.2) and the mean is kept exactly.
#pragma once

#include "pipeline/volume.h"

namespace deltagi {

// Takes the level-0 grid (resolution a power of two) and returns it with levels down to 1^3.
MipVolume buildMipChain(const VolumeRegion& region, Grid3 level0);

// One level down: each voxel of the result is the mean of 8 voxels of `fine` (resolution must be even).
Grid3 downsample(const Grid3& fine);

// The same chain after level 0 of `volume` was rewritten inside `changed` (level-0 voxels) and nowhere else:
// the voxels above `changed` are the means of their children again, level by level, and nothing else is
// touched, so the cost is that of the box. `occupied` must hold every non-zero level-0 voxel
// (mayReadNonZero). The levels equal buildMipChain's over the new level 0, bit for bit.
void updateMipChain(MipVolume& volume, const VoxelBox& changed, const VoxelBox& occupied);

}  // namespace deltagi
