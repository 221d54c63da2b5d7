#include "pipeline/mipmap.h"

#include <cassert>

#include "core/parallel.h"

namespace deltagi {

namespace {

// The mean of the 8 children of coarse voxel (x, y, z), summed in one fixed order: every path gives the same
// bits (children outside a window are zero and add nothing).
[[gnu::always_inline]] inline Float4 childMean(const PackedGrid3& fine, int x, int y, int z) {
    Float4 sum = {0.0f, 0.0f, 0.0f, 0.0f};
    if (fine.whole()) {
        for (int dz = 0; dz < 2; ++dz)
            for (int dy = 0; dy < 2; ++dy) {
                const size_t i = fine.index(2 * x, 2 * y + dy, 2 * z + dz);
                sum += fine.load(i);
                sum += fine.load(i + 1);
            }
        return sum * 0.125f;
    }
    for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) sum += loadFloat4(fine.at(2 * x + dx, 2 * y + dy, 2 * z + dz));
    return sum * 0.125f;
}

}  // namespace

PackedGrid3 downsample(const PackedGrid3& fine) {
    assert(fine.resolution() % 2 == 0);
    const int n = fine.resolution() / 2;
    // Every voxel of its window is set below: no zeroing first.
    PackedGrid3 coarse = PackedGrid3::unset(n, fine.window().parents());
    const VoxelBox& box = coarse.window();
    forEachRow(box, [&](int y, int z) {
        for (int x = box.lo.x; x < box.hi.x; ++x) coarse.set(x, y, z, childMean(fine, x, y, z));
    });
    return coarse;
}

namespace {

std::vector<PackedGrid3> mipLevels(PackedGrid3 level0) {
    std::vector<PackedGrid3> levels;
    levels.push_back(std::move(level0));
    while (levels.back().resolution() > 1) levels.push_back(downsample(levels.back()));
    return levels;
}

}  // namespace

MipVolume buildMipChain(const VolumeRegion& region, PackedGrid3 level0) {
    return MipVolume(region, mipLevels(std::move(level0)));
}

MipVolume buildMipChain(const VolumeRegion& region, PackedGrid3 level0, const VoxelBox& occupied) {
    return MipVolume(region, mipLevels(std::move(level0)), occupied);
}

MipVolume buildMipChain(const VolumeRegion& region, const Grid3& level0) {
    return buildMipChain(region, PackedGrid3(level0));
}

void updateMipChain(MipVolume& volume, const VoxelBox& changed, const VoxelBox& occupied) {
    VoxelBox box = changed;
    for (int l = 1; l < volume.levelCount() && !box.empty(); ++l) {
        const PackedGrid3& fine = volume.level(l - 1);
        PackedGrid3& coarse = volume.levelForUpdate(l);
        box = box.parents().intersection(coarse.window());
        forEachRow(box, [&](int y, int z) {
            for (int x = box.lo.x; x < box.hi.x; ++x) coarse.set(x, y, z, childMean(fine, x, y, z));
        });
    }
    volume.setOccupiedBounds(occupied);
}

}  // namespace deltagi
