#include "pipeline/mipmap.h"

#include <cassert>

#include "core/parallel.h"

namespace deltagi {

namespace {

// The mean of the 8 children of coarse voxel (x, y, z), summed in one fixed order: every path gives the same
// bits.
[[gnu::always_inline]] inline Float4 childMean(const PackedGrid3& fine, int x, int y, int z) {
    Float4 sum = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy) {
            const size_t i = fine.index(2 * x, 2 * y + dy, 2 * z + dz);
            sum += fine.load(i);
            sum += fine.load(i + 1);
        }
    return sum * 0.125f;
}

}  // namespace

PackedGrid3 downsample(const PackedGrid3& fine) {
    assert(fine.resolution() % 2 == 0);
    const int n = fine.resolution() / 2;
    PackedGrid3 coarse(n);
    parallelFor(0, static_cast<int64_t>(n) * n, 16, [&](int64_t zy) {
        const int z = static_cast<int>(zy / n), y = static_cast<int>(zy % n);
        for (int x = 0; x < n; ++x) coarse.set(x, y, z, childMean(fine, x, y, z));
    });
    return coarse;
}

MipVolume buildMipChain(const VolumeRegion& region, PackedGrid3 level0) {
    std::vector<PackedGrid3> levels;
    levels.push_back(std::move(level0));
    while (levels.back().resolution() > 1) levels.push_back(downsample(levels.back()));
    return MipVolume(region, std::move(levels));
}

MipVolume buildMipChain(const VolumeRegion& region, const Grid3& level0) {
    return buildMipChain(region, PackedGrid3(level0));
}

void updateMipChain(MipVolume& volume, const VoxelBox& changed, const VoxelBox& occupied) {
    VoxelBox box = changed;
    for (int l = 1; l < volume.levelCount() && !box.empty(); ++l) {
        box = box.parents();
        const PackedGrid3& fine = volume.level(l - 1);
        PackedGrid3& coarse = volume.levelForUpdate(l);
        forEachRow(box, [&](int y, int z) {
            for (int x = box.lo.x; x < box.hi.x; ++x) coarse.set(x, y, z, childMean(fine, x, y, z));
        });
    }
    volume.setOccupiedBounds(occupied);
}

}  // namespace deltagi
