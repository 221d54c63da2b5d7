// Stage 1: voxelization into a visibility volume (§3.2): occlusion 1 in every voxel that any triangle touches
// (closed voxels) and the area-weighted average normal of the geometry in it; also the area of the geometry
// in each voxel and, for emissive materials, the radiance they emit. Each triangle is cut by the grid planes
// it crosses, one plane at a time, into its pieces in each voxel: what a triangle/box overlap test
// (Akenine-Möller 2001) and clipping the triangle to each voxel of its bounds give, at a fraction of the
// cost.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/parallel.h"
#include "deltagi/scene.h"
#include "pipeline/volume.h"

namespace deltagi {

struct VoxelGeometry {
    // Level 0: (occlusion, occlusion * average normal); occlusion is 0 or 1. Over the whole grid, or (a
    // voxelization with a window margin) over a window around the geometry: the other arrays are indexed
    // alike (visibility.index), and every voxel outside the window is empty.
    Grid3 visibility;
    std::vector<float, LargeBlockAllocator<float>>
        area;  // surface area of the geometry inside each voxel (world units^2), same indexing
    // Emitted radiance times area of the emissive surfaces in each voxel, summed (same indexing); empty when
    // no mesh emits. Divided by `area` it is the voxel's mean emitted radiance (light injection).
    std::vector<glm::vec3, LargeBlockAllocator<glm::vec3>> emission;
    // With albedo (voxelize's `withAlbedo`: the multi-bounce light of bounceLight() reflects by it): the
    // area-weighted mean reflectance (Material::volumeReflectance) of the surfaces in each surface voxel, one
    // per entry of `surfaceVoxels`, in their order (only they have surfaces: 1 MiB for the Cornell box at
    // 128^3, where a grid of them is 24).
    std::vector<glm::vec3> albedo;
    // Every voxel outside it is zero in all three: the voxels that the triangles' bounding boxes touch.
    VoxelBox bounds;
    bool withAlbedo = false;  // voxelize's: `albedo` and `surfaceVoxels` are kept
    // < 0: the arrays cover the whole grid. Else they cover `bounds` grown by this many voxels on each side
    // (within the grid), and a voxelization again whose bounds leave that window starts over a new one.
    int windowMargin = -1;
    // With albedo: the voxels any triangle touches (occupancy 1), by their index in the whole grid
    // ((z * n + y) * n + x), and where each row of `bounds` starts among them (row (y, z) at (z - lo.z) *
    // extent.y + (y - lo.y); one entry more for the end), so that the passes over the surfaces alone
    // (bounceLight) skip the empty grid.
    std::vector<uint32_t> surfaceVoxels;
    std::vector<uint32_t> surfaceRowStart;
    // Textured objects' triangles (meshes placed from an object-space mesh, TriangleMesh::objectSpace): each
    // triangle's voxel material, its emission and reflectance at its centre filtered over a voxel, used for
    // the triangles smaller than a voxel (most of a detailed mesh's), for each of their pieces. Kept from one
    // voxelization to the next while the mesh, its material, the voxel size and the scale of its transform
    // stay the same (an object that moves or turns), so that moving a textured object does not look its
    // textures up again. One entry per mesh, in order.
    struct TriangleMaterials {
        const TriangleMesh* objectSpace = nullptr;
        uint64_t signature = 0;
        std::vector<std::array<glm::vec3, 2>> values;  // emission, reflectance
    };
    std::vector<TriangleMaterials> triangleMaterials;

    // Packed (voxelize's `packed`: the real scene, voxelized once, whose level 0 the visibility mip chain
    // takes): `visibility` stores no voxel (its resolution is the grid's); level 0 is in `packedVisibility`
    // (bfloat16, made from the same floats) until the mip chain takes it, and each voxel's occupancy in
    // `occupied`. The other arrays cover the whole grid. Such a geometry is not voxelized again in place.
    bool packed = false;
    PackedGrid3 packedVisibility;
    std::vector<uint8_t, LargeBlockAllocator<uint8_t>> occupied;

    // Whether the arrays cover the whole grid, indexed as (z * n + y) * n + x.
    bool whole() const { return packed || visibility.whole(); }
    // The arrays' index of voxel (x, y, z), or kOutside where they do not reach it (an empty voxel).
    static constexpr size_t kOutside = ~size_t(0);
    size_t indexOf(int x, int y, int z) const {
        if (packed) {
            const size_t n = static_cast<size_t>(visibility.resolution());
            return (static_cast<size_t>(z) * n + static_cast<size_t>(y)) * n + static_cast<size_t>(x);
        }
        return visibility.window().contains(x, y, z) ? visibility.index(x, y, z) : kOutside;
    }
    // The same for the voxel of index `voxel` in the whole grid.
    size_t indexOf(size_t voxel) const {
        if (whole()) return voxel;
        const size_t n = static_cast<size_t>(visibility.resolution());
        return indexOf(static_cast<int>(voxel % n), static_cast<int>(voxel / n % n),
                       static_cast<int>(voxel / n / n));
    }
    // The occupancy (0 or 1) of the voxel at index `i` of the arrays.
    float occupancy(size_t i) const { return packed ? static_cast<float>(occupied[i]) : visibility[i].x; }
};

// Calls body(row, k, i) for every surface voxel i (its index in the whole grid) of `geometry`, the k-th of
// VoxelGeometry::surfaceVoxels, in index order within each row of its bounds, rows in parallel (`row` their
// place in the bounds' rows).
template <typename Body>
inline void forEachSurfaceVoxel(const VoxelGeometry& geometry, Body&& body) {
    const size_t rows = geometry.surfaceRowStart.empty() ? 0 : geometry.surfaceRowStart.size() - 1;
    parallelFor(0, static_cast<int64_t>(rows), 64, [&](int64_t row) {
        for (uint32_t k = geometry.surfaceRowStart[row]; k < geometry.surfaceRowStart[row + 1]; ++k)
            body(static_cast<size_t>(row), static_cast<size_t>(k),
                 static_cast<size_t>(geometry.surfaceVoxels[k]));
    });
}

// Radiance at the surface voxels of a geometry, one per entry of its VoxelGeometry::surfaceVoxels, in their
// order; zero at every other voxel (the real scene's further bounces: a few MiB, where a grid is 32 at
// 128^3).
using SurfaceRadiance = std::vector<glm::vec3>;

// The surface voxels of `geometry` in row (y, z) at x0 and after: [first, last) of its surfaceVoxels (empty
// where the row holds none).
std::pair<uint32_t, uint32_t> surfaceVoxelsInRow(const VoxelGeometry& geometry, int y, int z, int x0);

// Voxelizes `meshes` over `region`. Deterministic for any thread count (each voxel sums its triangles in
// mesh and triangle order).
// `withEmission` false leaves emitting surfaces' radiance out (VoxelGeometry::emission empty): their light
// reaches the scene through shadow rays and reflective shadow maps instead (options.shadow.method "rays").
// `windowMargin` >= 0 keeps the arrays over the meshes' voxels and that many around them only
// (VoxelGeometry::windowMargin): the virtual objects, small in a large grid (64 MiB less at 128^3).
VoxelGeometry voxelize(std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                       bool withEmission = true, bool withAlbedo = false, int windowMargin = -1);
// The same, packed (VoxelGeometry::packed: the visibility's level 0 straight in bfloat16 with an occupancy
// byte per voxel, the floats summed a slab at a time), over the whole grid: 32 MiB less at 128^3 for a
// geometry that is voxelized once.
VoxelGeometry voxelizePacked(std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                             bool withEmission = true, bool withAlbedo = false);

// Voxelizes `meshes` again into `geometry`, a voxelization over the same region (of other or moved meshes):
// the voxels of its old bounds are cleared and the new geometry is written, so the cost is that of the
// triangles and the two boxes, not of the grid (with a window margin, a new window when they leave the old
// one). Afterwards `geometry` equals voxelize(meshes, region) over its window bit for bit. Returns the old
// bounds.
VoxelBox revoxelize(VoxelGeometry& geometry, std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                    bool withEmission = true);

// Counting sort of items into consecutive z-slabs of a grid, keeping item order inside a slab: the basis of
// the deterministic parallel scatter used by voxelization and light injection. `slabOf(item, first, last)`
// gives the range of slabs an item touches.
struct SlabBins {
    std::vector<uint32_t> offsets;  // slabCount + 1 entries
    std::vector<uint32_t> items;    // item indices, grouped by slab
    std::span<const uint32_t> slab(size_t s) const {
        return std::span<const uint32_t>(items).subspan(offsets[s], offsets[s + 1] - offsets[s]);
    }
};
template <typename SlabRange>
SlabBins binBySlab(size_t itemCount, size_t slabCount, SlabRange&& slabRange) {
    // In chunks of items, in parallel: each chunk counts its items per slab, a prefix sum over slabs and then
    // chunks gives every chunk its place in each slab, and each chunk writes its items there: the same
    // order as one pass over the items (100k triangles were 1-2 ms of a frame on one core).
    constexpr size_t kChunk = 8192;
    const size_t chunks = (itemCount + kChunk - 1) / kChunk;
    std::vector<uint32_t> counts(chunks * slabCount, 0);  // chunk-major
    parallelFor(0, static_cast<int64_t>(chunks), 1, [&](int64_t c) {
        uint32_t* count = &counts[static_cast<size_t>(c) * slabCount];
        const size_t end = std::min(itemCount, static_cast<size_t>(c + 1) * kChunk);
        for (size_t i = static_cast<size_t>(c) * kChunk; i < end; ++i) {
            auto [first, last] = slabRange(i);
            for (int s = first; s <= last; ++s) ++count[s];
        }
    });
    SlabBins bins;
    bins.offsets.assign(slabCount + 1, 0);
    std::vector<uint32_t> cursor(counts.size());  // per chunk and slab: where its next item goes
    uint32_t next = 0;
    for (size_t s = 0; s < slabCount; ++s) {
        bins.offsets[s] = next;
        for (size_t c = 0; c < chunks; ++c) {
            cursor[c * slabCount + s] = next;
            next += counts[c * slabCount + s];
        }
    }
    bins.offsets[slabCount] = next;
    bins.items.resize(next);
    parallelFor(0, static_cast<int64_t>(chunks), 1, [&](int64_t c) {
        uint32_t* at = &cursor[static_cast<size_t>(c) * slabCount];
        const size_t end = std::min(itemCount, static_cast<size_t>(c + 1) * kChunk);
        for (size_t i = static_cast<size_t>(c) * kChunk; i < end; ++i) {
            auto [first, last] = slabRange(i);
            for (int s = first; s <= last; ++s) bins.items[at[s]++] = static_cast<uint32_t>(i);
        }
    });
    return bins;
}

// Level-0 voxel layers per slab of the scatter passes.
inline constexpr int kSlabThickness = 2;

}  // namespace deltagi
