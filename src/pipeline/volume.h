// Voxel volumes: a cubic grid of 4-value voxels with its mip chain (§3.1, Fig. 1).
//
// All four volumes of the method share this layout and the region of §3.4:
//   visibility volume: (occlusion, occlusion * average normal)  -- premultiplied, so a mip level is the plain
//                      mean of its 8 children: occlusion becomes the fraction of filled sub-voxels (§3.2) and
//                      the normal the occlusion-weighted mean normal, whose length says how coherent it is;
//   light volume:      (occlusion * radiance rgb, occlusion)     -- premultiplied the same way.
// The stages build level 0 in floats (Grid3); the mip volumes the cones read keep every level in bfloat16
// (PackedGrid3, 8 bytes a voxel): half the memory and memory traffic of floats, with a float's range (a
// radiance has no upper bound) and 8 significant bits, a relative rounding error under 2^-8.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <glm/glm.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/large_blocks.h"
#include "core/parallel.h"
#include "deltagi/renderer.h"

namespace deltagi {

// A box of level-0 voxels [lo, hi) (hi exclusive); empty when hi <= lo on any axis. The frame-to-frame
// updates of stages 1, 3 and 4 redo only the voxels of such boxes.
struct VoxelBox {
    glm::ivec3 lo{0}, hi{0};

    static VoxelBox all(int n) { return {glm::ivec3(0), glm::ivec3(n)}; }
    static VoxelBox voxel(glm::ivec3 v) { return {v, v + 1}; }
    bool empty() const { return hi.x <= lo.x || hi.y <= lo.y || hi.z <= lo.z; }
    size_t count() const {
        return empty() ? 0 : static_cast<size_t>(hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
    }
    // The bounding box of both (an empty box adds nothing).
    VoxelBox& extend(const VoxelBox& b) {
        if (b.empty()) return *this;
        if (empty()) return *this = b;
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
        return *this;
    }
    // The voxels of the next coarser mip level that hold these (resolution halved).
    VoxelBox parents() const { return empty() ? VoxelBox{} : VoxelBox{lo >> 1, (hi + 1) >> 1}; }
    // The voxels in both (empty when none).
    VoxelBox intersection(const VoxelBox& b) const {
        const VoxelBox r{glm::max(lo, b.lo), glm::min(hi, b.hi)};
        return r.empty() ? VoxelBox{} : r;
    }
    bool contains(const VoxelBox& b) const {
        return b.empty() ||
               (glm::all(glm::lessThanEqual(lo, b.lo)) && glm::all(glm::lessThanEqual(b.hi, hi)));
    }
    bool contains(int x, int y, int z) const {
        return x >= lo.x && y >= lo.y && z >= lo.z && x < hi.x && y < hi.y && z < hi.z;
    }
};

// One level in floats: n^3 voxels, x fastest. Move-only: volumes are large.
class Grid3 {
  public:
    Grid3() = default;
    explicit Grid3(int n) : n_(n), voxels_(static_cast<size_t>(n) * n * n, glm::vec4(0.0f)) {}
    Grid3(Grid3&&) noexcept = default;
    Grid3& operator=(Grid3&&) noexcept = default;
    Grid3(const Grid3&) = delete;
    Grid3& operator=(const Grid3&) = delete;

    Grid3 clone() const {
        Grid3 g;
        g.n_ = n_;
        g.voxels_ = voxels_;
        return g;
    }
    int resolution() const { return n_; }
    size_t size() const { return voxels_.size(); }
    size_t index(int x, int y, int z) const { return (static_cast<size_t>(z) * n_ + y) * n_ + x; }
    glm::vec4& at(int x, int y, int z) { return voxels_[index(x, y, z)]; }
    const glm::vec4& at(int x, int y, int z) const { return voxels_[index(x, y, z)]; }
    glm::vec4& operator[](size_t i) { return voxels_[i]; }
    const glm::vec4& operator[](size_t i) const { return voxels_[i]; }
    void set(size_t i, glm::vec4 v) { voxels_[i] = v; }

  private:
    int n_ = 0;
    std::vector<glm::vec4, LargeBlockAllocator<glm::vec4>> voxels_;
};

// bfloat16: a float's upper 16 bits (sign, 8-bit exponent, 7-bit mantissa), rounded to nearest even. (A
// quiet NaN stays one; the volumes hold none.)
inline uint16_t toBfloat16(float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof(bits));
    bits += 0x7FFFu + ((bits >> 16) & 1u);
    return static_cast<uint16_t>(bits >> 16);
}
inline float fromBfloat16(uint16_t h) {
    const uint32_t bits = static_cast<uint32_t>(h) << 16;
    float f;
    std::memcpy(&f, &bits, sizeof(f));
    return f;
}

// 4 floats in one SIMD register (GCC/Clang vector extension: SSE on x86-64, NEON on Arm).
using Float4 = float __attribute__((vector_size(16)));
inline Float4 loadFloat4(const glm::vec4& v) {
    Float4 r;
    std::memcpy(&r, &v, sizeof(r));
    return r;
}
inline glm::vec4 storeFloat4(Float4 v) {
    glm::vec4 r;
    std::memcpy(&r, &v, sizeof(r));
    return r;
}

// A voxel of 4 bfloat16, the first value in the lowest bits: toBfloat16 of each.
using PackedVoxel = uint64_t;
inline PackedVoxel packVoxel(Float4 v) {
#if defined(__SSE2__)
    __m128i bits = _mm_castps_si128(reinterpret_cast<__m128>(v));
    const __m128i odd = _mm_and_si128(_mm_srli_epi32(bits, 16), _mm_set1_epi32(1));
    bits = _mm_add_epi32(bits, _mm_add_epi32(odd, _mm_set1_epi32(0x7FFF)));
    // The upper halves, sign-extended, fit int16: the signed pack keeps them as they are.
    bits = _mm_srai_epi32(bits, 16);
    return static_cast<PackedVoxel>(_mm_cvtsi128_si64(_mm_packs_epi32(bits, bits)));
#else
    return static_cast<PackedVoxel>(toBfloat16(v[0])) | static_cast<PackedVoxel>(toBfloat16(v[1])) << 16 |
           static_cast<PackedVoxel>(toBfloat16(v[2])) << 32 |
           static_cast<PackedVoxel>(toBfloat16(v[3])) << 48;
#endif
}
inline PackedVoxel packVoxel(glm::vec4 v) {
    return packVoxel(loadFloat4(v));
}
// Each value's 16 bits become the upper half of a float (on x86-64 one SSE2 interleave with zeros).
inline Float4 unpackVoxel(const PackedVoxel& p) {
#if defined(__SSE2__)
    const __m128i bits =
        _mm_unpacklo_epi16(_mm_setzero_si128(), _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&p)));
    return reinterpret_cast<Float4>(_mm_castsi128_ps(bits));
#else
    using UInt4 = uint32_t __attribute__((vector_size(16)));
    const UInt4 bits = {static_cast<uint32_t>(p) << 16, static_cast<uint32_t>(p) & 0xFFFF0000u,
                        static_cast<uint32_t>(p >> 32) << 16, static_cast<uint32_t>(p >> 32) & 0xFFFF0000u};
    Float4 r;
    std::memcpy(&r, &bits, sizeof(r));
    return r;
#endif
}

// One level of a mip volume: n^3 voxels of 4 bfloat16 (PackedVoxel), of which those of a window (a box; all
// of them by default) are stored, x fastest, and those outside it are zero. Reads give floats; writes round
// to nearest. Move-only.
class PackedGrid3 {
  public:
    PackedGrid3() = default;
    explicit PackedGrid3(int n) : PackedGrid3(n, VoxelBox::all(n)) {}
    PackedGrid3(int n, const VoxelBox& window)
        : n_(n),
          window_(window.intersection(VoxelBox::all(n))),
          extent_(window_.hi - window_.lo),
          whole_(window_.count() == static_cast<size_t>(n) * n * n),
          voxels_(window_.count(), PackedVoxel(0)) {}
    // `grid` rounded to bfloat16, inside `window` (zero outside it is the caller's promise).
    explicit PackedGrid3(const Grid3& grid) : PackedGrid3(grid, VoxelBox::all(grid.resolution())) {}
    PackedGrid3(const Grid3& grid, const VoxelBox& window);
    PackedGrid3(PackedGrid3&&) noexcept = default;
    PackedGrid3& operator=(PackedGrid3&&) noexcept = default;
    PackedGrid3(const PackedGrid3&) = delete;
    PackedGrid3& operator=(const PackedGrid3&) = delete;

    int resolution() const { return n_; }
    const VoxelBox& window() const { return window_; }
    // Whether every voxel is stored: then index(x, y, z) is (z * n + y) * n + x.
    bool whole() const { return whole_; }
    // Voxels stored.
    size_t size() const { return voxels_.size(); }
    size_t bytes() const { return voxels_.size() * sizeof(PackedVoxel); }
    // The place of voxel (x, y, z) of the window.
    size_t index(int x, int y, int z) const {
        return (static_cast<size_t>(z - window_.lo.z) * extent_.y + (y - window_.lo.y)) * extent_.x +
               (x - window_.lo.x);
    }
    glm::vec4 operator[](size_t i) const { return storeFloat4(unpackVoxel(voxels_[i])); }
    // Zero outside the window.
    glm::vec4 at(int x, int y, int z) const {
        return window_.contains(x, y, z) ? (*this)[index(x, y, z)] : glm::vec4(0.0f);
    }
    Float4 load(size_t i) const { return unpackVoxel(voxels_[i]); }
    void set(size_t i, glm::vec4 v) { voxels_[i] = packVoxel(v); }
    void set(size_t i, Float4 v) { voxels_[i] = packVoxel(v); }
    void set(int x, int y, int z, Float4 v) { set(index(x, y, z), v); }
    void set(int x, int y, int z, glm::vec4 v) { set(index(x, y, z), v); }
    PackedVoxel packed(size_t i) const { return voxels_[i]; }

  private:
    int n_ = 0;
    VoxelBox window_;
    glm::ivec3 extent_{0};
    bool whole_ = false;
    std::vector<PackedVoxel, LargeBlockAllocator<PackedVoxel>> voxels_;
};

// The 8 voxels and weights of one trilinear lookup (corners outside the grid have weight 0).
struct TrilinearCorners {
    uint32_t index[8];
    float weight[8];
    glm::ivec3 first{0};  // the voxel of corner 0 (the others are +1 along x, y, z by the bits of k)
};

// Where one quadrilinear lookup reads. It depends only on the region and resolution, so the volumes that
// share them (all four of the method) are read with one lookup.
struct VolumeLookup {
    glm::vec3 voxelPos{0.0f};  // level-0 voxel units
    int level0 = 0;            // the finer of the two levels
    float blend = 0.0f;        // weight of level0 + 1
    TrilinearCorners fine, coarse;
};

// The indices of the corners `c` (c.first and its neighbours at +1 along x, y, z by the bits of k) in a level
// stored over its voxels [lo, hi), x fastest; a corner outside gets index 0 and weight 0.
[[gnu::always_inline]] inline void placeCorners(glm::ivec3 lo, glm::ivec3 hi, TrilinearCorners& c) {
    const glm::ivec3 p = c.first, extent = hi - lo;
    auto index = [&](int x, int y, int z) {
        return static_cast<uint32_t>((static_cast<size_t>(z - lo.z) * extent.y + (y - lo.y)) * extent.x +
                                     (x - lo.x));
    };
    if (p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x + 1 < hi.x && p.y + 1 < hi.y && p.z + 1 < hi.z) {
        // All 8 corners inside: one base index and fixed offsets.
        const uint32_t base = index(p.x, p.y, p.z);
        const uint32_t row = static_cast<uint32_t>(extent.x), slice = static_cast<uint32_t>(extent.y) * row;
        const uint32_t offsets[8] = {0, 1, row, row + 1, slice, slice + 1, slice + row, slice + row + 1};
        for (int k = 0; k < 8; ++k) c.index[k] = base + offsets[k];
        return;
    }
    for (int k = 0; k < 8; ++k) {
        const int x = p.x + (k & 1), y = p.y + ((k >> 1) & 1), z = p.z + (k >> 2);
        const bool valid = x >= lo.x && y >= lo.y && z >= lo.z && x < hi.x && y < hi.y && z < hi.z;
        c.index[k] = valid ? index(x, y, z) : 0u;
        if (!valid) c.weight[k] = 0.0f;
    }
}

// Trilinear corners at a level, for a position in level-0 voxel units, of a level stored over its voxels
// [lo, hi) (placeCorners).
[[gnu::always_inline]] inline void trilinearCornersOver(glm::vec3 voxelPos, int level, glm::ivec3 lo,
                                                        glm::ivec3 hi, TrilinearCorners& c) {
    const glm::vec3 q = voxelPos * (1.0f / static_cast<float>(1 << level)) - 0.5f;
    const glm::vec3 base = glm::floor(q);
    const glm::vec3 f = q - base;
    c.first = glm::ivec3(base);
    const float wx[2] = {1.0f - f.x, f.x}, wy[2] = {1.0f - f.y, f.y}, wz[2] = {1.0f - f.z, f.z};
    const float wxy[4] = {wx[0] * wy[0], wx[1] * wy[0], wx[0] * wy[1], wx[1] * wy[1]};
    for (int k = 0; k < 8; ++k) c.weight[k] = wxy[k & 3] * wz[k >> 2];
    placeCorners(lo, hi, c);
}

// Trilinear corners at a level of resolution n (stored whole).
inline void trilinearCorners(glm::vec3 voxelPos, int level, int n, TrilinearCorners& c) {
    trilinearCornersOver(voxelPos, level, glm::ivec3(0), glm::ivec3(n), c);
}

// Calls rowBody(y, z) for every row of voxels of `box` (x from box.lo.x to box.hi.x), rows in parallel.
template <typename RowBody>
void forEachRow(const VoxelBox& box, RowBody&& rowBody);

// The box around every non-zero voxel of `grid` (a Grid3 or a PackedGrid3) inside `within` (empty when there
// is none).
template <typename Grid>
VoxelBox nonZeroBounds(const Grid& grid, const VoxelBox& within);

// A level-0 grid and its mip chain over a region. Level l has resolution n / 2^l; its voxels are 2^l level-0
// voxels wide. A volume whose levels are stored over windows (the objects' own volumes, zero outside the
// objects' box) is read as one stored whole.
class MipVolume {
  public:
    MipVolume() = default;
    MipVolume(VolumeRegion region, std::vector<PackedGrid3> levels)
        : region_(region), levels_(std::move(levels)) {
        whole_ = std::all_of(levels_.begin(), levels_.end(), [](const PackedGrid3& g) { return g.whole(); });
        findOccupiedBounds();
    }

    const VolumeRegion& region() const { return region_; }
    int levelCount() const { return static_cast<int>(levels_.size()); }
    const PackedGrid3& level(int l) const { return levels_[l]; }
    bool empty() const { return levels_.empty(); }
    // Bytes of all the levels.
    size_t bytes() const {
        size_t sum = 0;
        for (const PackedGrid3& g : levels_) sum += g.bytes();
        return sum;
    }

    // Prepares a quadrilinear lookup at `voxelPos` (level-0 voxel units, 0 at the region's corner) between
    // the two levels around the fractional `level`.
    VolumeLookup lookup(glm::vec3 voxelPos, float level) const {
        VolumeLookup l;
        l.voxelPos = voxelPos;
        level = glm::clamp(level, 0.0f, static_cast<float>(levelCount() - 1));
        l.level0 = static_cast<int>(level);
        l.blend = l.level0 + 1 < levelCount() ? level - static_cast<float>(l.level0) : 0.0f;
        trilinearCorners(voxelPos, l.level0, levels_[l.level0].resolution(), l.fine);
        if (l.blend > 0.0f)
            trilinearCorners(voxelPos, l.level0 + 1, levels_[l.level0 + 1].resolution(), l.coarse);
        return l;
    }
    // Reads a lookup prepared by any volume of the same region and resolution. Returns 0 at once where the
    // lookup's footprint cannot reach a non-zero voxel.
    glm::vec4 gather(const VolumeLookup& l) const {
        if (!mayReadNonZero(l.voxelPos, l.level0)) return glm::vec4(0.0f);
        if (!whole_) return gatherWindowed(l);
        Float4 v = gatherLevel(l.level0, l.fine);
        if (l.blend > 0.0f) v += (gatherLevel(l.level0 + 1, l.coarse) - v) * l.blend;
        return storeFloat4(v);
    }
    // False where a lookup at `voxelPos` between levels level0 and level0 + 1 cannot reach a non-zero voxel.
    bool mayReadNonZero(glm::vec3 voxelPos, int level0) const {
        const float reach = static_cast<float>(4 << level0);  // level-0 voxels a lookup can read from
        return !glm::any(glm::lessThan(voxelPos, occupiedMin_ - reach)) &&
               !glm::any(glm::greaterThan(voxelPos, occupiedMax_ + reach));
    }
    // The level-0 voxels outside which every voxel is zero, as used by mayReadNonZero (a superset of the
    // non-zero voxels gives the same lookups, only fewer early outs).
    VoxelBox occupiedBounds() const { return occupied_; }
    // For updates in place (mipmap.h's updateMipChain): a level to write, and the occupied bounds to use
    // instead of scanning level 0 again. The caller keeps the levels a mip chain and the bounds a superset of
    // the non-zero voxels.
    PackedGrid3& levelForUpdate(int l) { return levels_[l]; }
    void setOccupiedBounds(const VoxelBox& box) {
        occupied_ = box;
        if (box.empty()) {
            occupiedMin_ = glm::vec3(std::numeric_limits<float>::max());
            occupiedMax_ = glm::vec3(-std::numeric_limits<float>::max());
        } else {
            occupiedMin_ = glm::vec3(box.lo);
            occupiedMax_ = glm::vec3(box.hi);
        }
    }
    // Trilinear sample of level `l`.
    glm::vec4 sampleLevel(glm::vec3 voxelPos, int l) const {
        TrilinearCorners c;
        trilinearCornersOver(voxelPos, l, levels_[l].window().lo, levels_[l].window().hi, c);
        return storeFloat4(gatherLevel(l, c));
    }
    // Quadrilinear sample: trilinear in the two levels around the fractional `level`, blended.
    glm::vec4 sample(glm::vec3 voxelPos, float level) const { return gather(lookup(voxelPos, level)); }

  private:
    Float4 gatherLevel(int l, const TrilinearCorners& c) const {
        const PackedGrid3& g = levels_[l];
        Float4 acc = {0.0f, 0.0f, 0.0f, 0.0f};
        for (int k = 0; k < 8; ++k) acc += g.load(c.index[k]) * c.weight[k];
        return acc;
    }
    // gather() of a volume stored over windows, from a lookup with the whole grid's corners: their voxels and
    // weights, placed in each level's window.
    glm::vec4 gatherWindowed(const VolumeLookup& l) const {
        Float4 v = gatherWindowedLevel(l.level0, l.fine);
        if (l.blend > 0.0f) v += (gatherWindowedLevel(l.level0 + 1, l.coarse) - v) * l.blend;
        return storeFloat4(v);
    }
    Float4 gatherWindowedLevel(int l, TrilinearCorners c) const {
        placeCorners(levels_[l].window().lo, levels_[l].window().hi, c);
        return gatherLevel(l, c);
    }
    // The level-0 voxel-space box around every non-zero voxel (inverted when there is none).
    void findOccupiedBounds() {
        setOccupiedBounds(levels_.empty() ? VoxelBox{} : nonZeroBounds(levels_[0], levels_[0].window()));
    }

    VolumeRegion region_;
    std::vector<PackedGrid3> levels_;
    bool whole_ = true;
    VoxelBox occupied_;
    glm::vec3 occupiedMin_{0.0f}, occupiedMax_{0.0f};  // occupied_ as floats, for mayReadNonZero
};

template <typename RowBody>
void forEachRow(const VoxelBox& box, RowBody&& rowBody) {
    if (box.empty()) return;
    const int rows = box.hi.y - box.lo.y;
    parallelFor(0, static_cast<int64_t>(box.hi.z - box.lo.z) * rows, 4, [&](int64_t r) {
        rowBody(box.lo.y + static_cast<int>(r % rows), box.lo.z + static_cast<int>(r / rows));
    });
}

template <typename Grid>
VoxelBox nonZeroBounds(const Grid& grid, const VoxelBox& within) {
    glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
    for (int z = within.lo.z; z < within.hi.z; ++z)
        for (int y = within.lo.y; y < within.hi.y; ++y) {
            // The first and the last non-zero voxel of the row.
            int first = within.lo.x;
            while (first < within.hi.x && grid.at(first, y, z) == glm::vec4(0.0f)) ++first;
            if (first == within.hi.x) continue;
            int last = within.hi.x - 1;
            while (grid.at(last, y, z) == glm::vec4(0.0f)) --last;
            lo = glm::min(lo, glm::ivec3(first, y, z));
            hi = glm::max(hi, glm::ivec3(last + 1, y + 1, z + 1));
        }
    return lo.x <= hi.x ? VoxelBox{lo, hi} : VoxelBox{};
}

inline PackedGrid3::PackedGrid3(const Grid3& grid, const VoxelBox& window)
    : PackedGrid3(grid.resolution(), window) {
    if (whole_) {
        parallelFor(0, static_cast<int64_t>(voxels_.size()), 1 << 14,
                    [&](int64_t i) { voxels_[i] = packVoxel(grid[i]); });
        return;
    }
    forEachRow(window_, [&](int y, int z) {
        for (int x = window_.lo.x; x < window_.hi.x; ++x) set(x, y, z, grid.at(x, y, z));
    });
}

}  // namespace deltagi
