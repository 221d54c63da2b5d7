// Stage 3: light injection (§3.2). The reflective shadow maps' texels are scattered into a light volume that
// stores, per voxel, the radiance its surfaces reflect diffusely. The delta volume is the full light volume
// (real scene + virtual objects) minus the real-scene-only one: negative where a virtual object now blocks
// light that reached real surfaces, positive on the lit virtual objects.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/parallel.h"
#include "pipeline/reflective_shadow_map.h"
#include "pipeline/voxelize.h"

namespace deltagi {

// The voxels injectLight may have made non-zero (its `written`): every other voxel of its grid is zero.
struct InjectedVoxels {
    // Whether they are listed: the geometries' surface voxels (VoxelGeometry::surfaceVoxels) and
    // `offSurface`, the lit voxels beside them (a texel rounded into the voxel next to its surface). False:
    // any voxel.
    bool listed = false;
    std::vector<uint32_t> offSurface;
};

// Radiance of a voxel = the mean radiance of the texels that landed in it (reflected flux / (pi * footprint
// area)), times the lit fraction of the geometry's surface area in the voxel (footprint / area; where the map
// has many texels across a voxel, saturating at 3/4, which absorbs their count's jitter: lightRadiance in
// inject.cpp). Voxels are (radiance * occupancy, occupancy), with occupancy 1 where any of `geometry` touches
// the voxel. Emissive geometry adds its emitted radiance, averaged over the voxel's surface area: the cones
// then carry the light of emitters (one bounce of it: emitted light is not reflected into the volume again).
// Deterministic for any thread count. `written` (if given) gets the voxels it may have made non-zero.
// `recycled` (if given): a grid injectLight made for the same `geometry` before, and the voxels it wrote
// (plus any changes at the geometries' surface voxels since, as addBounce's). Its memory is taken, and only
// those voxels are zeroed, where a new grid zeroes every voxel (32 MiB at 128^3, at every light change).
struct RecycledGrid {
    Grid3 grid;
    InjectedVoxels written;
};
Grid3 injectLight(std::span<const ReflectiveShadowMap> rsms, const VolumeRegion& region,
                  std::span<const VoxelGeometry* const> geometry, InjectedVoxels* written = nullptr,
                  RecycledGrid* recycled = nullptr);

// nonZeroBounds over the whole of `grid` (a level-0 grid stored whole: injectLight's, packed or not, and
// changed since at the geometries' surface voxels only), found among the voxels `written` lists instead of
// reading every voxel; nullopt when they are not listed.
std::optional<VoxelBox> injectedBounds(const Grid3& grid, std::span<const VoxelGeometry* const> geometry,
                                       const InjectedVoxels& written);
std::optional<VoxelBox> injectedBounds(const PackedGrid3& grid,
                                       std::span<const VoxelGeometry* const> geometry,
                                       const InjectedVoxels& written);

// body(i) for every voxel that `written` (listed) lists: the geometries' surface voxels and the lit voxels
// off them, in parallel; a voxel on two geometries' surfaces is visited once for each.
template <typename Body>
void forEachListedVoxel(std::span<const VoxelGeometry* const> geometry, const InjectedVoxels& written,
                        Body&& body) {
    for (const VoxelGeometry* g : geometry)
        forEachSurfaceVoxel(*g, [&](size_t, size_t, size_t i) { body(i); });
    constexpr int64_t kGrain = 4096;
    const std::vector<uint32_t>& off = written.offSurface;
    parallelFor(0, (static_cast<int64_t>(off.size()) + kGrain - 1) / kGrain, 1, [&](int64_t c) {
        const size_t end = std::min(off.size(), static_cast<size_t>((c + 1) * kGrain));
        for (size_t k = static_cast<size_t>(c * kGrain); k < end; ++k) body(size_t{off[k]});
    });
}

// An n^3 grid, zeroed, with value(i) (a glm::vec4) packed at each voxel `written` (listed) lists: as
// PackedGrid3::fromEach(n, value) where value is zero at every other voxel, for a third of its bytes.
template <typename Value>
PackedGrid3 packListed(int n, std::span<const VoxelGeometry* const> geometry, const InjectedVoxels& written,
                       Value&& value) {
    PackedGrid3 packed(n);
    forEachListedVoxel(geometry, written, [&](size_t i) { packed.set(i, glm::vec4(value(i))); });
    return packed;
}

// PackedGrid3(grid) for injectLight's grid (changed since at the geometries' surface voxels only): only the
// voxels `written` lists are packed, into a grid zeroed first (a third of the bytes that reading every voxel
// of `grid` takes); every voxel when they are not listed.
PackedGrid3 packInjected(const Grid3& grid, std::span<const VoxelGeometry* const> geometry,
                         const InjectedVoxels& written);

// full - sceneOnly in the radiance channels; the occupancy of `full` (which covers both). Packed as it is
// made (no float grid in between: 32 MiB at 128^3 that a first frame would fault in for nothing).
PackedGrid3 deltaVolume(const Grid3& full, const Grid3& sceneOnly);

// ---- Injecting again where the objects change the light, frame after frame (FrameRenderer) ----
//
// With the objects, the RSMs differ from the real scene's own only in a few texels, and the full light volume
// differs from the scene's only in the voxels those texels land in (before and after) and in the objects'
// voxels; the delta volume is (0, 0, 0, scene occupancy) everywhere else. So a frame re-injects a box of
// voxels around them, each from all the texels that land in it, summed in the order injectLight sums them:
// the voxels are injectLight's bit for bit (no differences of sums, which would round differently).

// A set of level-0 voxels held as one x-range per row (y, z) of the grid: as cheap to walk as a box, and far
// tighter than one box around regions apart (the objects' shadows towards many lights).
class VoxelRows {
  public:
    VoxelRows() = default;
    explicit VoxelRows(int resolution);  // empty
    static VoxelRows all(int resolution);
    int resolution() const { return n_; }
    // Adds voxels; a row keeps one range, so the voxels between two ranges of a row are added too.
    void add(const VoxelBox& box);
    void add(int x, int y, int z);
    void add(const VoxelRows& other);  // of the same resolution
    bool contains(const VoxelRows& other) const;
    bool contains(int x, int y, int z) const {
        const size_t r = static_cast<size_t>(z) * n_ + y;
        return lo_[r] <= x && x < hi_[r];
    }
    size_t count() const;
    VoxelBox bounds() const;
    // body(y, z, x0, x1) for each row with voxels, rows in parallel.
    template <typename RowBody>
    void forEachRow(RowBody&& body) const;

  private:
    int n_ = 0;
    std::vector<uint16_t> lo_, hi_;  // per row z * n + y: [lo, hi), no voxel when lo >= hi
};

// The texels of the real scene's RSMs, binned by row of voxels (built once, kept while the maps are): the
// texels of any voxel of `box` are found without going through the maps.
struct TexelBins {
    struct Entry {
        uint16_t x, light;  // the voxel's x, the map
        uint32_t texel;     // position in the map's texels
    };
    int resolution = 0;
    VoxelRows voxels;                // the voxels whose texels are binned
    std::vector<uint32_t> rowStart;  // resolution^2 + 1 offsets into entries; row (y, z) is z * n + y
    std::vector<Entry> entries;      // each row's texels by x, then in injectLight's order (map, texel)
};
// The texels landing in `voxels` (VoxelRows::all for every voxel of the region): where the maps change every
// frame (a live light), only those that frame re-injects.
TexelBins binTexels(std::span<const ReflectiveShadowMap> rsms, const VolumeRegion& region,
                    const VoxelRows& voxels);

// Where the maps with the objects differ from the real scene's own: the scene's texels that are gone or
// changed, and the texels that are new or changed.
struct RsmChanges {
    struct Texel {
        uint32_t voxel;  // index in the level-0 grid
        uint32_t light;
        const RsmTexel* texel;  // into the scene's maps (removed) or the updates (added)
        uint32_t position;      // removed: in its map's texels
    };
    std::vector<Texel> removed;  // by light and texel
    std::vector<Texel> added;    // by voxel, light and texel: injectLight's order in each voxel
    VoxelRows voxels;            // the voxels all of them land in
};
// Compares each map of `sceneAlone` with its update for the objects (traceRsmUpdate, one per light) in the
// texels the update traced again: the others are the same. Added texels point into the updates.
RsmChanges compareRsms(std::span<const ReflectiveShadowMap> sceneAlone, std::span<const RsmUpdate> updates,
                       const VolumeRegion& region);

// injectLight(withObjects, region, geometry) and deltaVolume(it, sceneLight), written into `fullLight` and
// `deltaLight` in `voxels` only, where withObjects = the maps of `sceneTexels` (binTexels of `sceneAlone`)
// with `changes`. The result there is bit for bit the same as those functions' rounded to bfloat16.
// `bounce` (the real scene's further bounces at the surface voxels of geometry[0], if any) is added to the
// full volume, as to the scene's light.
void reinjectLight(const VoxelRows& voxels, const TexelBins& sceneTexels,
                   std::span<const ReflectiveShadowMap> sceneAlone, const RsmChanges& changes,
                   std::span<const VoxelGeometry* const> geometry, const Grid3& sceneLight,
                   PackedGrid3& fullLight, PackedGrid3& deltaLight, const SurfaceRadiance* bounce = nullptr);

template <typename RowBody>
void VoxelRows::forEachRow(RowBody&& body) const {
    parallelFor(0, static_cast<int64_t>(lo_.size()), 64, [&](int64_t r) {
        if (lo_[r] < hi_[r])
            body(static_cast<int>(r % n_), static_cast<int>(r / n_), int{lo_[r]}, int{hi_[r]});
    });
}

}  // namespace deltagi
