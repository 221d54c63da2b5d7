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
#include <utility>
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
    bool operator==(const VoxelBox&) const = default;
    bool contains(int x, int y, int z) const {
        return x >= lo.x && y >= lo.y && z >= lo.z && x < hi.x && y < hi.y && z < hi.z;
    }
};

// Every element of `values` set to `value`, in parallel: a volume's tens of MiB on one thread took
// milliseconds of a frame in which the other core waited.
template <typename T, typename Allocator>
void fillInParallel(std::vector<T, Allocator>& values, const T& value) {
    constexpr int64_t kChunk = int64_t(1) << 16;
    const int64_t count = static_cast<int64_t>(values.size());
    parallelFor(0, (count + kChunk - 1) / kChunk, 1, [&](int64_t c) {
        std::fill(values.begin() + c * kChunk, values.begin() + std::min(count, (c + 1) * kChunk), value);
    });
}

// One level in floats: n^3 voxels, x fastest, zero-initialized; or only those of a window of them (the rest
// zero, which the accessors do not reach). Move-only: volumes are large.
class Grid3 {
  public:
    Grid3() = default;
    explicit Grid3(int n) : Grid3(n, VoxelBox::all(n)) {}
    Grid3(int n, const VoxelBox& window)
        : n_(n),
          window_(window.intersection(VoxelBox::all(n))),
          extent_(window_.hi - window_.lo),
          whole_(window_.count() == static_cast<size_t>(n) * n * n) {
        voxels_.resize(window_.count());
        fillInParallel(voxels_, glm::vec4(0.0f));
    }
    Grid3(Grid3&&) noexcept = default;
    Grid3& operator=(Grid3&&) noexcept = default;
    Grid3(const Grid3&) = delete;
    Grid3& operator=(const Grid3&) = delete;

    Grid3 clone() const {
        Grid3 g;
        g.n_ = n_;
        g.window_ = window_;
        g.extent_ = extent_;
        g.whole_ = whole_;
        g.voxels_ = voxels_;
        return g;
    }
    int resolution() const { return n_; }
    const VoxelBox& window() const { return window_; }
    // Whether every voxel is stored: then index(x, y, z) is (z * n + y) * n + x.
    bool whole() const { return whole_; }
    // Voxels stored.
    size_t size() const { return voxels_.size(); }
    // The place of voxel (x, y, z) of the window.
    size_t index(int x, int y, int z) const {
        return (static_cast<size_t>(z - window_.lo.z) * extent_.y + (y - window_.lo.y)) * extent_.x +
               (x - window_.lo.x);
    }
    glm::vec4& at(int x, int y, int z) { return voxels_[index(x, y, z)]; }
    const glm::vec4& at(int x, int y, int z) const { return voxels_[index(x, y, z)]; }
    glm::vec4& operator[](size_t i) { return voxels_[i]; }
    const glm::vec4& operator[](size_t i) const { return voxels_[i]; }
    void set(size_t i, glm::vec4 v) { voxels_[i] = v; }

  private:
    int n_ = 0;
    VoxelBox window_;
    glm::ivec3 extent_{0};
    bool whole_ = true;
    std::vector<glm::vec4, UnsetAllocator<glm::vec4>> voxels_;
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
    PackedGrid3(int n, const VoxelBox& window) : PackedGrid3(n, window, Unset{}) {
        fillInParallel(voxels_, PackedVoxel(0));
    }
    // `grid` rounded to bfloat16, inside `window` (zero outside it is the caller's promise).
    explicit PackedGrid3(const Grid3& grid) : PackedGrid3(grid, VoxelBox::all(grid.resolution())) {}
    PackedGrid3(const Grid3& grid, const VoxelBox& window);
    // Every voxel of an n^3 grid set to value(i) (a glm::vec4 for voxel index i), in parallel: no pass that
    // zeroes it first.
    template <typename Value>
    static PackedGrid3 fromEach(int n, Value&& value);
    // Its window's voxels left as the allocator gives them: the caller sets every one before any is read (a
    // mip level made from the level below, voxel by voxel).
    static PackedGrid3 unset(int n, const VoxelBox& window) { return PackedGrid3(n, window, Unset{}); }
    PackedGrid3(PackedGrid3&&) noexcept = default;
    PackedGrid3& operator=(PackedGrid3&&) noexcept = default;
    PackedGrid3(const PackedGrid3&) = delete;
    PackedGrid3& operator=(const PackedGrid3&) = delete;

    int resolution() const { return n_; }
    const VoxelBox& window() const { return window_; }
    // Whether every voxel is stored: then index(x, y, z) is (z * n + y) * n + x.
    bool whole() const { return whole_; }
    // Voxels stored.
    size_t size() const { return count_; }
    size_t bytes() const { return voxels_.size() * sizeof(PackedVoxel); }
    // The stored voxels. A lookup reads two x-neighbours at once (TrilinearCorners), both in one row where
    // rows are two or more voxels long; a level one voxel wide keeps one more voxel, always zero, after its
    // last.
    const PackedVoxel* data() const { return voxels_.data(); }
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
    // Its voxels left as the allocator gives them (uninitialized): every one is written next (or zeroed). The
    // guard voxel of a level one voxel wide is zeroed.
    struct Unset {};
    PackedGrid3(int n, const VoxelBox& window, Unset)
        : n_(n),
          window_(window.intersection(VoxelBox::all(n))),
          extent_(window_.hi - window_.lo),
          whole_(window_.count() == static_cast<size_t>(n) * n * n),
          count_(window_.count()) {
        voxels_.resize(count_ + (extent_.x == 1 ? 1 : 0));
        if (extent_.x == 1) voxels_.back() = PackedVoxel(0);
    }

    int n_ = 0;
    VoxelBox window_;
    glm::ivec3 extent_{0};
    bool whole_ = false;
    size_t count_ = 0;
    std::vector<PackedVoxel, UnsetAllocator<PackedVoxel>> voxels_;
};

// The 8 voxels and weights of one trilinear lookup, as the 4 rows (along y and z) of two x-neighbours each,
// so that a row is one 16-byte read: voxel pair[r] and the one after it.
struct TrilinearCorners {
    uint32_t pair[4];
    Float4 weight[8];  // voxel k's weight in all four lanes: row k / 2, first (k even) or second voxel
};

// Where one quadrilinear lookup reads. It depends only on the region and resolution, so the volumes that
// share them (all four of the method) are read with one lookup.
struct VolumeLookup {
    glm::vec3 voxelPos{0.0f};       // level-0 voxel units
    int level0 = 0;                 // the finer of the two levels
    float blend = 0.0f;             // weight of level0 + 1
    TrilinearCorners fine, coarse;  // their weights times 1 - blend and blend
    // Placed in whole levels, or in these windows (a volume stored over windows prepared it).
    bool whole = true;
    VoxelBox fineWindow, coarseWindow;
};

// 2^-level, exactly (a float's exponent field).
inline float inversePowerOfTwo(int level) {
    const uint32_t bits = static_cast<uint32_t>(127 - level) << 23;
    float f;
    std::memcpy(&f, &bits, sizeof(f));
    return f;
}

// floor() of each lane, exact for |x| < 2^31 (SSE2 has no rounding instruction: truncate, then step down
// where truncation rounded up).
inline Float4 floor4(Float4 x) {
    using Int4 = int32_t __attribute__((vector_size(16)));
    const Float4 truncated = __builtin_convertvector(__builtin_convertvector(x, Int4), Float4);
    return truncated - (truncated > x ? Float4{1.0f, 1.0f, 1.0f, 1.0f} : Float4{0.0f, 0.0f, 0.0f, 0.0f});
}

// A trilinear lookup's weights: row r's weight (along y and z, times the level's share) w[r], times the
// weights wx0 and wx1 of its two voxels along x, each in all four lanes.
[[gnu::always_inline]] inline void setRowWeights(TrilinearCorners& c, Float4 w, float wx0, float wx1) {
    for (int r = 0; r < 4; ++r) {
        const Float4 wr = {w[r], w[r], w[r], w[r]};
        c.weight[2 * r] = wr * wx0;
        c.weight[2 * r + 1] = wr * wx1;
    }
}

// Trilinear corners at a level, for a position in level-0 voxel units, of a level stored over its voxels
// [lo, hi), every weight times `scale` (a quadrilinear lookup's share of the level). Without branches: a
// corner outside [lo, hi) gets weight 0, and its row the nearest stored voxels.
[[gnu::always_inline]] inline void trilinearCornersOver(glm::vec3 voxelPos, int level, glm::ivec3 lo,
                                                        glm::ivec3 hi, TrilinearCorners& c,
                                                        float scale = 1.0f) {
    using Int4 = int32_t __attribute__((vector_size(16)));
    const Float4 q = Float4{voxelPos.x, voxelPos.y, voxelPos.z, 0.0f} * inversePowerOfTwo(level) - 0.5f;
    const Float4 base = floor4(q);
    const Float4 f = q - base;
    const Int4 p0 = __builtin_convertvector(base, Int4), p1 = p0 + 1;
    const Int4 lo4 = {lo.x, lo.y, lo.z, 0}, last4 = {hi.x - 1, hi.y - 1, hi.z - 1, 0};
    const uint32_t ex = static_cast<uint32_t>(hi.x - lo.x), ey = static_cast<uint32_t>(hi.y - lo.y);
    if (p0[0] >= lo.x && p0[1] >= lo.y && p0[2] >= lo.z && p1[0] <= last4[0] && p1[1] <= last4[1] &&
        p1[2] <= last4[2]) {
        // All eight inside (most lookups): one first voxel, rows a row or a slice apart.
        const Float4 g = 1.0f - f;
        setRowWeights(c, Float4{g[1], f[1], g[1], f[1]} * Float4{g[2], g[2], f[2], f[2]} * scale, g[0], f[0]);
        const Int4 rel = p0 - lo4;
        const uint32_t first = (static_cast<uint32_t>(rel[2]) * ey + static_cast<uint32_t>(rel[1])) * ex +
                               static_cast<uint32_t>(rel[0]);
        c.pair[0] = first;
        c.pair[1] = first + ex;
        c.pair[2] = first + ex * ey;
        c.pair[3] = first + ex * ey + ex;
        return;
    }
    const Float4 zero = {0.0f, 0.0f, 0.0f, 0.0f};
    const auto in0 = p0 >= lo4 && p0 <= last4, in1 = p1 >= lo4 && p1 <= last4;
    // Along y and z the weights of the first and the second row read, and the first's place in the stored
    // box: p0 and p1 where p0 is inside, else p1 alone (first) or nothing.
    const Float4 a0 = in0 ? 1.0f - f : (in1 ? f : zero);
    const Float4 a1 = (in0 && in1) ? f : zero;
    const Int4 c0 = (p0 < lo4 ? lo4 : (p0 > last4 ? last4 : p0)) - lo4;
    // y and z read the second voxel's own row: p1 clamped.
    const Int4 c1 = (p1 < lo4 ? lo4 : (p1 > last4 ? last4 : p1)) - lo4;
    // Along x the two voxels read stay in their row where it is two or more wide: the first at most the
    // row's last but one, each weighed by which of p0, p1 it is.
    const int px = p0[0], bx = std::clamp(px, lo.x, std::max(hi.x - 2, lo.x));
    auto weightX = [&](int x) {
        return x > last4[0] ? 0.0f : (x == px ? 1.0f - f[0] : (x == px + 1 ? f[0] : 0.0f));
    };
    const float wx0 = weightX(bx), wx1 = weightX(bx + 1);
    setRowWeights(c, Float4{a0[1], a1[1], a0[1], a1[1]} * Float4{a0[2], a0[2], a1[2], a1[2]} * scale, wx0,
                  wx1);
    const uint32_t x0 = static_cast<uint32_t>(bx - lo.x);
    const uint32_t y0 = static_cast<uint32_t>(c0[1]), y1 = static_cast<uint32_t>(c1[1]);
    const uint32_t z0 = static_cast<uint32_t>(c0[2]) * ey, z1 = static_cast<uint32_t>(c1[2]) * ey;
    c.pair[0] = (z0 + y0) * ex + x0;
    c.pair[1] = (z0 + y1) * ex + x0;
    c.pair[2] = (z1 + y0) * ex + x0;
    c.pair[3] = (z1 + y1) * ex + x0;
}

// The weighted sum of a trilinear lookup's voxels in a level: a 16-byte read per row, four partial sums.
[[gnu::always_inline]] inline Float4 gatherCorners(const PackedVoxel* voxels, const TrilinearCorners& c) {
    Float4 row[4];
    for (int r = 0; r < 4; ++r) {
#if defined(__SSE2__)
        const __m128i two = _mm_loadu_si128(reinterpret_cast<const __m128i*>(voxels + c.pair[r]));
        const __m128i zero = _mm_setzero_si128();
        const Float4 first = reinterpret_cast<Float4>(_mm_castsi128_ps(_mm_unpacklo_epi16(zero, two)));
        const Float4 second = reinterpret_cast<Float4>(_mm_castsi128_ps(_mm_unpackhi_epi16(zero, two)));
#else
        const Float4 first = unpackVoxel(voxels[c.pair[r]]), second = unpackVoxel(voxels[c.pair[r] + 1]);
#endif
        row[r] = first * c.weight[2 * r] + second * c.weight[2 * r + 1];
    }
    return (row[0] + row[1]) + (row[2] + row[3]);
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
    // The same where the caller knows the box around level 0's non-zero voxels (what nonZeroBounds would
    // find), e.g. injectedBounds.
    MipVolume(VolumeRegion region, std::vector<PackedGrid3> levels, const VoxelBox& occupied)
        : region_(region), levels_(std::move(levels)) {
        whole_ = std::all_of(levels_.begin(), levels_.end(), [](const PackedGrid3& g) { return g.whole(); });
        setOccupiedBounds(occupied);
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
        // Each level's weights times its share, so that a gather adds the two; placed in this volume's
        // windows (the whole levels for a volume stored whole).
        l.whole = whole_;
        if (!whole_) {
            l.fineWindow = levels_[l.level0].window();
            if (l.blend > 0.0f) l.coarseWindow = levels_[l.level0 + 1].window();
        }
        placeIn(l.level0, voxelPos, 1.0f - l.blend, l.fine);
        if (l.blend > 0.0f) placeIn(l.level0 + 1, voxelPos, l.blend, l.coarse);
        return l;
    }
    // Reads a lookup prepared by any volume of the same region and resolution (at once where it was placed in
    // levels stored as this volume's are: whole, or over the same windows). Returns 0 at once where the
    // lookup's footprint cannot reach a non-zero voxel.
    glm::vec4 gather(const VolumeLookup& l) const { return storeFloat4(gatherFloat4(l)); }
    // gather() in one SIMD register.
    [[gnu::always_inline]] Float4 gatherFloat4(const VolumeLookup& l) const {
        if (!mayReadNonZero(l.voxelPos, l.level0)) return Float4{0.0f, 0.0f, 0.0f, 0.0f};
        if (whole_ ? !l.whole : !placedInOwnWindows(l)) return gatherWindowed(l);
        Float4 v = gatherLevel(l.level0, l.fine);
        if (l.blend > 0.0f) v += gatherLevel(l.level0 + 1, l.coarse);
        return v;
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
        placeIn(l, voxelPos, 1.0f, c);
        return storeFloat4(gatherLevel(l, c));
    }
    // Quadrilinear sample: trilinear in the two levels around the fractional `level`, blended.
    glm::vec4 sample(glm::vec3 voxelPos, float level) const { return gather(lookup(voxelPos, level)); }

  private:
    bool placedInOwnWindows(const VolumeLookup& l) const {
        return !l.whole && l.fineWindow == levels_[l.level0].window() &&
               (!(l.blend > 0.0f) || l.coarseWindow == levels_[l.level0 + 1].window());
    }
    // Level l's trilinear corners at `voxelPos`, placed in its window, the weights times `share`.
    [[gnu::always_inline]] void placeIn(int l, glm::vec3 voxelPos, float share, TrilinearCorners& c) const {
        trilinearCornersOver(voxelPos, l, levels_[l].window().lo, levels_[l].window().hi, c, share);
    }
    [[gnu::always_inline]] Float4 gatherLevel(int l, const TrilinearCorners& c) const {
        return gatherCorners(levels_[l].data(), c);
    }
    // gather() of a lookup placed otherwise: its corners again, placed in each level's window.
    [[gnu::noinline]] Float4 gatherWindowed(const VolumeLookup& l) const {
        Float4 v = gatherWindowedLevel(l.voxelPos, l.level0, 1.0f - l.blend);
        if (l.blend > 0.0f) v += gatherWindowedLevel(l.voxelPos, l.level0 + 1, l.blend);
        return v;
    }
    Float4 gatherWindowedLevel(glm::vec3 voxelPos, int l, float share) const {
        TrilinearCorners c;
        placeIn(l, voxelPos, share, c);
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

// Whether voxel (x, y, z) of a grid is zero (all four channels == 0), read without unpacking it: a
// bfloat16 is +-0 exactly where its bits but the sign are.
inline bool zeroVoxel(const Grid3& grid, int x, int y, int z) {
    return grid.at(x, y, z) == glm::vec4(0.0f);
}
inline bool zeroVoxel(const PackedGrid3& grid, size_t i) {
    constexpr PackedVoxel kAllButSigns = 0x7FFF7FFF7FFF7FFFull;
    return (grid.packed(i) & kAllButSigns) == 0;
}
inline bool zeroVoxel(const PackedGrid3& grid, int x, int y, int z) {
    return !grid.window().contains(x, y, z) || zeroVoxel(grid, grid.index(x, y, z));
}

template <typename Grid>
VoxelBox nonZeroBounds(const Grid& grid, const VoxelBox& within) {
    if (within.empty()) return {};
    // Slices of z in parallel, each its own box; joined in order (min and max: the same for any thread
    // count).
    const int slices = within.hi.z - within.lo.z;
    std::vector<VoxelBox> sliceBounds(static_cast<size_t>(slices));
    parallelFor(0, slices, 1, [&](int64_t s) {
        const int z = within.lo.z + static_cast<int>(s);
        glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
        for (int y = within.lo.y; y < within.hi.y; ++y) {
            // The first and the last non-zero voxel of the row.
            int first = within.lo.x;
            while (first < within.hi.x && zeroVoxel(grid, first, y, z)) ++first;
            if (first == within.hi.x) continue;
            int last = within.hi.x - 1;
            while (zeroVoxel(grid, last, y, z)) --last;
            lo = glm::min(lo, glm::ivec3(first, y, z));
            hi = glm::max(hi, glm::ivec3(last + 1, y + 1, z + 1));
        }
        if (lo.x <= hi.x) sliceBounds[static_cast<size_t>(s)] = VoxelBox{lo, hi};
    });
    VoxelBox bounds;
    for (const VoxelBox& b : sliceBounds) bounds.extend(b);
    return bounds;
}

inline PackedGrid3::PackedGrid3(const Grid3& grid, const VoxelBox& window)
    : PackedGrid3(grid.resolution(), window, Unset{}) {
    if (whole_ && grid.whole()) {
        parallelFor(0, static_cast<int64_t>(count_), 1 << 14,
                    [&](int64_t i) { voxels_[i] = packVoxel(grid[i]); });
        return;
    }
    forEachRow(window_, [&](int y, int z) {
        for (int x = window_.lo.x; x < window_.hi.x; ++x) set(x, y, z, grid.at(x, y, z));
    });
}

template <typename Value>
PackedGrid3 PackedGrid3::fromEach(int n, Value&& value) {
    PackedGrid3 grid(n, VoxelBox::all(n), Unset{});
    parallelFor(0, static_cast<int64_t>(grid.count_), 1 << 14,
                [&](int64_t i) { grid.voxels_[i] = packVoxel(glm::vec4(value(static_cast<size_t>(i)))); });
    return grid;
}

}  // namespace deltagi
