// Stage 4: mipmaps of a volume (§3.1, Fig. 1a). A coarse voxel is the mean of its 2x2x2 children, so the
// occlusion of a coarse voxel is the fraction of filled sub-voxels (§3.2) and the mean is kept exactly.
#pragma once

#include "volume.h"

namespace deltagi {

// Takes the level-0 grid (resolution a power of two) and returns it with levels down to 1^3.
MipVolume buildMipChain(const VolumeRegion& region, Grid3 level0);

// One level down: each voxel of the result is the mean of 8 voxels of `fine` (resolution must be even).
Grid3 downsample(const Grid3& fine);

}  // namespace deltagi
