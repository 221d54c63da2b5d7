// Stage 6's light cones eight at a time: traceLightCones and traceLightChangeCones march the cones of a batch
// in the lanes of 8-float vectors and give each cone's light as traceLightCone and traceLightChangeCone
// (cone_trace.cpp, the definition) give it, to within float rounding. A lane whose cone ends takes the next
// cone of the batch, so that cones of different lengths keep every lane busy; lanes never share anything,
// so a cone's light does not depend on the cones traced beside it.
//
// A step of the eight lanes: the march (distance, mip level, position) and where the quadrilinear lookup
// reads (each level's trilinear corners and weights) in lanes; then lane by lane each volume's voxels, two
// rows of a level in one 8-float register (a row is two x-neighbours, 16 bytes of bfloat16); then the
// occlusion model and the compositing in lanes again.
//
// The kernels are compiled for AVX2 with FMA (built with GCC for x86-64) and run where the CPU has both;
// elsewhere, and built with Clang (which refuses to pass an 8-float vector from an AVX function to a helper
// without AVX, even one it inlines), each cone is traced alone. Without AVX2 an 8-float vector is lowered to
// SSE2 instructions that shuffle 16-bit values one by one: slower than tracing the cones alone.
//
// The volumes the lookup is shared by (the light volumes and the scene's visibility) must be stored whole, as
// the pipeline's are; the objects' own volumes, stored over windows around them, are read lane by lane as
// the one-cone tracers read them, only where a lane's lookup can reach them.
#include "pipeline/cone_march.h"
#include "pipeline/cone_trace.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DELTAGI_CONE_LANES 1
#endif

#include <bit>
#include <cstring>

#if DELTAGI_CONE_LANES
#include <immintrin.h>

// The 8-float helpers are always inlined into the kernels: the note that 32-byte vectors are passed
// differently with AVX than without does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

// The kernels' target; everything they call is inlined into them and compiled for it too, so that it may use
// AVX instructions on whole 8-float vectors.
#define DELTAGI_LANE_KERNEL __attribute__((target("avx2,fma")))
#define DELTAGI_LANE_INLINE [[gnu::always_inline]] inline __attribute__((target("avx2,fma")))

namespace deltagi {
namespace {

using namespace cone_march;

constexpr int kLanes = 8;
using FloatL = float __attribute__((vector_size(32)));
using IntL = int32_t __attribute__((vector_size(32)));
using UInt16x8 = uint16_t __attribute__((vector_size(16)));
using UInt16x16 = uint16_t __attribute__((vector_size(32)));

DELTAGI_LANE_INLINE FloatL splat(float x) {
    return FloatL{} + x;
}
DELTAGI_LANE_INLINE IntL splatInt(int32_t x) {
    return IntL{} + x;
}
DELTAGI_LANE_INLINE FloatL select(IntL mask, FloatL a, FloatL b) {
    return mask ? a : b;
}
DELTAGI_LANE_INLINE IntL selectInt(IntL mask, IntL a, IntL b) {
    return mask ? a : b;
}
DELTAGI_LANE_INLINE FloatL minL(FloatL a, FloatL b) {
    return a < b ? a : b;
}
DELTAGI_LANE_INLINE FloatL maxL(FloatL a, FloatL b) {
    return a > b ? a : b;
}
DELTAGI_LANE_INLINE IntL clampInt(IntL x, IntL lo, IntL hi) {
    x = x < lo ? lo : x;
    return x > hi ? hi : x;
}
DELTAGI_LANE_INLINE FloatL toFloat(IntL x) {
    return __builtin_convertvector(x, FloatL);
}
DELTAGI_LANE_INLINE IntL truncateToInt(FloatL x) {
    return __builtin_convertvector(x, IntL);
}
// One bit per lane, lane 0 lowest.
// Both in registers: a vector passed through memory in halves costs a failed store forwarding per use.
DELTAGI_LANE_INLINE unsigned laneBits(IntL mask) {
    return static_cast<unsigned>(_mm256_movemask_ps(std::bit_cast<__m256>(mask)));
}
DELTAGI_LANE_INLINE FloatL sqrtL(FloatL x) {
    return std::bit_cast<FloatL>(_mm256_sqrt_ps(std::bit_cast<__m256>(x)));
}
// floor() of each lane, exact for |x| < 2^31: truncate, then step down where truncation rounded up.
DELTAGI_LANE_INLINE FloatL floorL(FloatL x) {
    const FloatL truncated = toFloat(truncateToInt(x));
    return select(truncated > x, truncated - 1.0f, truncated);
}
// 2^-level of each lane (a float's exponent field).
DELTAGI_LANE_INLINE FloatL inversePowersOfTwo(IntL level) {
    return std::bit_cast<FloatL>((127 - level) << 23);
}
// fastLog2 (cone_march.h) of each lane.
DELTAGI_LANE_INLINE FloatL log2L(FloatL x) {
    IntL bits = std::bit_cast<IntL>(x);
    const FloatL exponent = toFloat(((bits >> 23) & 0xFF) - 127);
    bits = (bits & 0x007FFFFF) | 0x3F800000;
    const FloatL u = std::bit_cast<FloatL>(bits) - 1.0f;
    const FloatL p =
        ((((kLog2Poly[0] * u + kLog2Poly[1]) * u + kLog2Poly[2]) * u + kLog2Poly[3]) * u + kLog2Poly[4]) * u;
    return exponent + p;
}
// stepOpacity (cone_march.h) of each lane.
DELTAGI_LANE_INLINE FloatL stepOpacityL(FloatL alpha, float stepScale) {
    const FloatL transmittance = maxL(1.0f - alpha, splat(0.0f));
    if (stepScale == 0.5f) return 1.0f - sqrtL(transmittance);
    if (stepScale == 1.0f) return alpha;
    FloatL r;
    for (int i = 0; i < kLanes; ++i) r[i] = 1.0f - std::pow(transmittance[i], stepScale);
    return r;
}

// A sample of four channels in lanes: c[0] is the occupancy of a visibility sample, c[3] the occupancy of a
// light sample.
struct Channels {
    FloatL c[4];
};
DELTAGI_LANE_INLINE Channels zeroChannels() {
    return {{splat(0.0f), splat(0.0f), splat(0.0f), splat(0.0f)}};
}

// Eight lanes' samples of one volume, each four channels as gathered (Float4), as four channel vectors.
DELTAGI_LANE_INLINE Channels transpose(const Float4 (&lanes)[kLanes]) {
    FloatL pairs[4];  // lanes 2k and 2k + 1
    for (int k = 0; k < 4; ++k)
        pairs[k] = __builtin_shufflevector(lanes[2 * k], lanes[2 * k + 1], 0, 1, 2, 3, 4, 5, 6, 7);
    // Channels 0 and 1 (2 and 3) of lanes 0-3 and of lanes 4-7.
    const FloatL c01a = __builtin_shufflevector(pairs[0], pairs[1], 0, 4, 8, 12, 1, 5, 9, 13);
    const FloatL c23a = __builtin_shufflevector(pairs[0], pairs[1], 2, 6, 10, 14, 3, 7, 11, 15);
    const FloatL c01b = __builtin_shufflevector(pairs[2], pairs[3], 0, 4, 8, 12, 1, 5, 9, 13);
    const FloatL c23b = __builtin_shufflevector(pairs[2], pairs[3], 2, 6, 10, 14, 3, 7, 11, 15);
    return {{__builtin_shufflevector(c01a, c01b, 0, 1, 2, 3, 8, 9, 10, 11),
             __builtin_shufflevector(c01a, c01b, 4, 5, 6, 7, 12, 13, 14, 15),
             __builtin_shufflevector(c23a, c23b, 0, 1, 2, 3, 8, 9, 10, 11),
             __builtin_shufflevector(c23a, c23b, 4, 5, 6, 7, 12, 13, 14, 15)}};
}

// adaptedOcclusion (cone_trace.cpp) of each lane: the occlusion of a visibility sample seen along the cone's
// axis (dx, dy, dz) at a level 2^level voxels wide.
DELTAGI_LANE_INLINE FloatL adaptedOcclusionL(const Channels& v, const FloatL (&dir)[3], FloatL levelScale,
                                             const ConeTraceSettings& s, float backfaceWeight) {
    const FloatL occupancy = v.c[0];
    const IntL filled = occupancy > kEmpty;
    const FloatL inverse = 1.0f / select(filled, occupancy, splat(1.0f));
    const FloatL nx = v.c[1] * inverse, ny = v.c[2] * inverse, nz = v.c[3] * inverse;
    const FloatL coherence = minL(sqrtL(nx * nx + ny * ny + nz * nz), splat(1.0f));
    const IntL coherent = coherence > kEmpty;
    const FloatL cosine = nx * dir[0] + ny * dir[1] + nz * dir[2];
    const FloatL facing = select(coherent, cosine / select(coherent, coherence, splat(1.0f)), splat(0.0f));
    const FloatL directional =
        select(facing > 0.0f, 1.0f - backfaceWeight * minL(splat(1.0f), kBackfaceRamp * facing), splat(1.0f));
    const FloatL adapted = (1.0f - coherence) * kIsotropicCoverage + coherence * directional;
    const FloatL weight = (1.0f - s.normalWeight) * kIsotropicCoverage + s.normalWeight * adapted;
    const FloatL occlusion = minL(maxL(occupancy * levelScale * weight, splat(0.0f)), splat(1.0f));
    return select(filled, occlusion, splat(0.0f));
}

// rgb / w of a light sample where w is not empty, else 0 (radiance of a premultiplied light voxel).
DELTAGI_LANE_INLINE Channels radianceL(const Channels& v) {
    const IntL lit = v.c[3] > kEmpty;
    const FloatL inverse = 1.0f / select(lit, v.c[3], splat(1.0f));
    Channels r;
    for (int c = 0; c < 3; ++c) r.c[c] = select(lit, v.c[c] * inverse, splat(0.0f));
    r.c[3] = select(lit, splat(1.0f), splat(0.0f));
    return r;
}

// A volume read in lanes: its levels' voxels (stored whole).
struct LaneVolume {
    const PackedVoxel* levels[kMaxLevels] = {};
    explicit LaneVolume(const MipVolume* v) {
        if (v)
            for (int l = 0; l < v->levelCount(); ++l) levels[l] = v->level(l).data();
    }
};

// Where one step's lookup reads in each lane, for both levels (0 the finer, 1 the coarser).
struct LaneCorners {
    alignas(32) int32_t level[2][kLanes];
    alignas(32) int32_t pair[2][4][kLanes];  // the first voxel of each row (along y and z)
    alignas(32) FloatL weight[2][kLanes];  // each lane's corner weights, corner 2 r + x: row r, x-neighbour x
    alignas(32) int32_t coarse[kLanes];    // whether the coarser level is read (its share is not 0)
};

// An 8 x 8 transpose: lanes[j][k] = values[k][j].
DELTAGI_LANE_INLINE void transposeToLanes(const FloatL (&values)[8], FloatL (&lanes)[kLanes]) {
    FloatL t[8], u[8];
    for (int k = 0; k < 4; ++k) {
        t[2 * k] = __builtin_shufflevector(values[2 * k], values[2 * k + 1], 0, 8, 1, 9, 4, 12, 5, 13);
        t[2 * k + 1] = __builtin_shufflevector(values[2 * k], values[2 * k + 1], 2, 10, 3, 11, 6, 14, 7, 15);
    }
    for (int h = 0; h < 2; ++h)  // values 0-3, then 4-7
        for (int k = 0; k < 2; ++k) {
            u[4 * h + 2 * k] =
                __builtin_shufflevector(t[4 * h + k], t[4 * h + 2 + k], 0, 1, 8, 9, 4, 5, 12, 13);
            u[4 * h + 2 * k + 1] =
                __builtin_shufflevector(t[4 * h + k], t[4 * h + 2 + k], 2, 3, 10, 11, 6, 7, 14, 15);
        }
    for (int j = 0; j < 4; ++j) {
        lanes[j] = __builtin_shufflevector(u[j], u[4 + j], 0, 1, 2, 3, 8, 9, 10, 11);
        lanes[4 + j] = __builtin_shufflevector(u[j], u[4 + j], 4, 5, 6, 7, 12, 13, 14, 15);
    }
}

// MipVolume::lookup's trilinear corners of a whole level (per lane: `level`, its resolution `n`) at `p`,
// every weight times `share`: a corner outside the level gets weight 0, and its row the nearest voxels.
DELTAGI_LANE_INLINE void placeInLevel(const FloatL (&p)[3], IntL level, FloatL share, float resolution,
                                      LaneCorners& c, int which) {
    const FloatL scale = inversePowersOfTwo(level);
    const IntL n = truncateToInt(resolution * scale), last = n - 1;
    FloatL f[3], a0[3], a1[3];
    IntL p0[3], c0[3], c1[3];
    for (int axis = 0; axis < 3; ++axis) {
        const FloatL q = p[axis] * scale - 0.5f;
        const FloatL base = floorL(q);
        f[axis] = q - base;
        p0[axis] = truncateToInt(base);
        const IntL p1 = p0[axis] + 1;
        const IntL in0 = (p0[axis] >= 0) & (p0[axis] <= last), in1 = (p1 >= 0) & (p1 <= last);
        a0[axis] = select(in0, 1.0f - f[axis], select(in1, f[axis], splat(0.0f)));
        a1[axis] = select(in0 & in1, f[axis], splat(0.0f));
        c0[axis] = clampInt(p0[axis], splatInt(0), last);
        c1[axis] = clampInt(p1, splatInt(0), last);
    }
    // Along x the two voxels read stay in their row where it is two or more wide.
    const IntL px = p0[0];
    const IntL bx = clampInt(px, splatInt(0), selectInt(n - 2 > 0, n - 2, splatInt(0)));
    auto weightX = [&](IntL x) __attribute__((always_inline, target("avx2,fma"))) {
        return select(x > last, splat(0.0f),
                      select(x == px, 1.0f - f[0], select(x == px + 1, f[0], splat(0.0f))));
    };
    const FloatL wx[2] = {weightX(bx), weightX(bx + 1)};
    const FloatL row[4] = {a0[1] * a0[2] * share, a1[1] * a0[2] * share, a0[1] * a1[2] * share,
                           a1[1] * a1[2] * share};
    const IntL y[2] = {c0[1], c1[1]}, z[2] = {c0[2] * n, c1[2] * n};
    FloatL corner[8];
    for (int r = 0; r < 4; ++r) {
        const IntL first = (z[r >> 1] + y[r & 1]) * n + bx;
        std::memcpy(c.pair[which][r], &first, sizeof(first));
        for (int x = 0; x < 2; ++x) corner[2 * r + x] = row[r] * wx[x];
    }
    transposeToLanes(corner, c.weight[which]);
    std::memcpy(c.level[which], &level, sizeof(level));
}

// gatherCorners of one lane in one volume: the weighted sum of its corners in both levels. A level's weights
// as 8-float registers, one for each pair of rows (0-1, 2-3) and x-neighbour: {row 2k's weight x 4, row
// 2k+1's weight x 4}.
DELTAGI_LANE_INLINE Float4 gatherLane(const LaneVolume& v, const LaneCorners& c, int lane) {
    const UInt16x16 zero = {};
    FloatL sum = splat(0.0f);
    const int levels = c.coarse[lane] ? 2 : 1;
    for (int l = 0; l < levels; ++l) {
        const PackedVoxel* voxels = v.levels[c.level[l][lane]];
        const FloatL w = c.weight[l][lane];
        const FloatL weights[2][2] = {{__builtin_shufflevector(w, w, 0, 0, 0, 0, 2, 2, 2, 2),
                                       __builtin_shufflevector(w, w, 1, 1, 1, 1, 3, 3, 3, 3)},
                                      {__builtin_shufflevector(w, w, 4, 4, 4, 4, 6, 6, 6, 6),
                                       __builtin_shufflevector(w, w, 5, 5, 5, 5, 7, 7, 7, 7)}};
        for (int rp = 0; rp < 2; ++rp) {
            UInt16x8 a, b;
            std::memcpy(&a, voxels + c.pair[l][2 * rp][lane], sizeof(a));
            std::memcpy(&b, voxels + c.pair[l][2 * rp + 1][lane], sizeof(b));
            const UInt16x16 rows =
                __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
            // Each bfloat16 the upper half of a float: the first voxels of both rows, then the second.
            const FloatL first = std::bit_cast<FloatL>(
                __builtin_shufflevector(zero, rows, 0, 16, 0, 17, 0, 18, 0, 19, 0, 24, 0, 25, 0, 26, 0, 27));
            const FloatL second = std::bit_cast<FloatL>(
                __builtin_shufflevector(zero, rows, 0, 20, 0, 21, 0, 22, 0, 23, 0, 28, 0, 29, 0, 30, 0, 31));
            sum += first * weights[rp][0] + second * weights[rp][1];
        }
    }
    return __builtin_shufflevector(sum, sum, 0, 1, 2, 3) + __builtin_shufflevector(sum, sum, 4, 5, 6, 7);
}

// The lanes' cones and their march. A lane's state is set when it takes a cone (start) and advanced by
// step; `active` marks the lanes with a cone.
struct LaneMarch {
    std::span<const Cone> cones;
    const VolumeRegion& region;
    const ConeTraceSettings& settings;
    const float resolution, maxLevel;
    const int levelCount;
    size_t next = 0;
    FloatL origin[3] = {}, dir[3] = {}, tanHalf = {}, t = {}, end = {};
    IntL active = {};
    int32_t cone[kLanes] = {};
    // This step's samples.
    FloatL diameter = {}, level = {}, levelScale = {}, position[3] = {};

    LaneMarch(std::span<const Cone> c, const MipVolume& reference, const ConeTraceSettings& s)
        : cones(c),
          region(reference.region()),
          settings(s),
          resolution(static_cast<float>(reference.region().resolution)),
          maxLevel(std::log2(static_cast<float>(reference.region().resolution))),
          levelCount(reference.levelCount()) {}

    // Gives the lane the batch's next cone that meets the volume (a cone that does not is given `empty`
    // light at once); false when none is left.
    template <typename Empty>
    DELTAGI_LANE_INLINE bool start(int lane, Empty&& empty) {
        while (next < cones.size()) {
            const size_t i = next++;
            const Cone& c = cones[i];
            const ConeSpan span = coneSpan(c, region, settings);
            if (!(span.first < span.end)) {
                empty(i);
                continue;
            }
            for (int a = 0; a < 3; ++a) origin[a][lane] = span.origin[a], dir[a][lane] = c.direction[a];
            tanHalf[lane] = c.tanHalfAngle;
            t[lane] = span.first;
            end[lane] = span.end;
            cone[lane] = static_cast<int32_t>(i);
            active[lane] = -1;
            return true;
        }
        active[lane] = 0;
        return false;
    }

    // This step's samples (marchCone's), and where they read.
    DELTAGI_LANE_INLINE void sample(LaneCorners& corners) {
        diameter = maxL(splat(1.0f), 2.0f * t * tanHalf);
        level = minL(log2L(diameter), splat(maxLevel));
        levelScale = minL(diameter, splat(resolution));
        for (int a = 0; a < 3; ++a) position[a] = origin[a] + t * dir[a];
        // MipVolume::lookup: the two levels around the clamped level, the coarser one's share `blend`.
        const FloatL clamped = minL(maxL(level, splat(0.0f)), splat(static_cast<float>(levelCount - 1)));
        const IntL fine = truncateToInt(clamped);
        const IntL hasCoarse = fine + 1 < levelCount;
        const FloatL blend = select(hasCoarse, clamped - toFloat(fine), splat(0.0f));
        placeInLevel(position, fine, 1.0f - blend, resolution, corners, 0);
        placeInLevel(position, selectInt(hasCoarse, fine + 1, fine), blend, resolution, corners, 1);
        const IntL coarse = blend > 0.0f;
        std::memcpy(corners.coarse, &coarse, sizeof(coarse));
    }
    // The lanes whose lookup may reach a non-zero voxel of `volume` (MipVolume::mayReadNonZero).
    DELTAGI_LANE_INLINE IntL mayRead(const MipVolume* volume, const LaneCorners& corners) const {
        if (!volume || volume->occupiedBounds().empty()) return IntL{};
        IntL fine;
        std::memcpy(&fine, corners.level[0], sizeof(fine));
        const FloatL reach = std::bit_cast<FloatL>((fine + 129) << 23);  // 4 << level
        const VoxelBox box = volume->occupiedBounds();
        IntL inside = active;
        for (int a = 0; a < 3; ++a)
            inside &= (position[a] >= static_cast<float>(box.lo[a]) - reach) &
                      (position[a] <= static_cast<float>(box.hi[a]) + reach);
        return inside;
    }
    DELTAGI_LANE_INLINE glm::vec3 positionOf(int lane) const {
        return {position[0][lane], position[1][lane], position[2][lane]};
    }
    // Moves the lanes on; returns the lanes whose cone ended (with `going` false, or past its end).
    DELTAGI_LANE_INLINE unsigned advance(IntL going) {
        t += diameter * settings.stepScale;
        const IntL was = active;
        active = active & going & (t < end);
        return laneBits(was & ~active);
    }
};

// A volume's samples in the lanes `near` (the others 0): read in lanes where it is stored whole like the
// reference, else lane by lane at its own lookup. `lookups` keeps a lane's own lookup, for the
// volume stored over the same windows (the objects' light).
DELTAGI_LANE_INLINE Channels gatherNear(const MipVolume& volume, bool whole, const LaneVolume& lanes,
                                        const LaneMarch& march, const LaneCorners& corners, unsigned near,
                                        VolumeLookup* lookups) {
    Float4 samples[kLanes] = {};
    for (int lane = 0; lane < kLanes; ++lane) {
        if (!(near >> lane & 1u)) continue;
        if (whole) {
            samples[lane] = gatherLane(lanes, corners, lane);
        } else {
            lookups[lane] = volume.lookup(march.positionOf(lane), march.level[lane]);
            samples[lane] = volume.gatherFloat4(lookups[lane]);
        }
    }
    return transpose(samples);
}

struct LightConeVolumes {
    const MipVolume& light;
    const MipVolume* scene;
    const MipVolume* object;
    bool objectWhole;
};

DELTAGI_LANE_KERNEL void traceLightConeLanes(std::span<const Cone> cones, const LightConeVolumes& volumes,
                                             const VisibilityVolumes& visibility,
                                             const ConeTraceSettings& settings, std::span<glm::vec3> out,
                                             int64_t* steps) {
    const LaneVolume light(&volumes.light), scene(volumes.scene),
        object(volumes.objectWhole ? volumes.object : nullptr);
    const auto [sceneBackface, objectBackface] = backfaceWeights(visibility, settings);
    LaneMarch march(cones, volumes.light, settings);
    Channels acc = zeroChannels();  // rgb and the occlusion (c[3])
    auto empty = [&](size_t i) { out[i] = glm::vec3(0.0f); };
    for (int lane = 0; lane < kLanes; ++lane) march.start(lane, empty);
    int64_t count = 0;
    LaneCorners corners;
    VolumeLookup lookups[kLanes];
    while (const unsigned active = laneBits(march.active)) {
        march.sample(corners);
        count += std::popcount(active);
        FloatL transmittance = splat(1.0f);
        if (volumes.scene) {
            const Channels v = gatherNear(*volumes.scene, true, scene, march, corners, active, lookups);
            transmittance *=
                1.0f - adaptedOcclusionL(v, march.dir, march.levelScale, settings, sceneBackface);
        }
        if (const unsigned near = laneBits(march.mayRead(volumes.object, corners))) {
            const Channels v =
                gatherNear(*volumes.object, volumes.objectWhole, object, march, corners, near, lookups);
            transmittance *=
                1.0f - adaptedOcclusionL(v, march.dir, march.levelScale, settings, objectBackface);
        }
        const FloatL occlusionLocal = stepOpacityL(1.0f - transmittance, settings.stepScale);
        const IntL lit = march.active & (occlusionLocal > 0.0f);
        if (const unsigned litLanes = laneBits(lit)) {
            const Channels l =
                radianceL(gatherNear(volumes.light, true, light, march, corners, litLanes, lookups));
            // §3.1's accumulation, as traceLightCone.
            const FloatL share = occlusionLocal * (1.0f - acc.c[3]);
            for (int c = 0; c < 3; ++c) {
                const FloatL contribution = l.c[c] * share;
                acc.c[c] = select(
                    lit,
                    settings.paperAccumulation ? acc.c[c] * acc.c[3] + contribution : acc.c[c] + contribution,
                    acc.c[c]);
            }
            acc.c[3] = select(lit, acc.c[3] + share, acc.c[3]);
        }
        unsigned ended = march.advance(acc.c[3] < settings.maxOcclusion);
        for (; ended; ended &= ended - 1) {
            const int lane = std::countr_zero(ended);
            out[march.cone[lane]] = {acc.c[0][lane], acc.c[1][lane], acc.c[2][lane]};
            for (int c = 0; c < 4; ++c) acc.c[c][lane] = 0.0f;
            march.start(lane, empty);
        }
    }
    if (steps) *steps += count;
}

struct ChangeConeVolumes {
    const MipVolume& full;
    const MipVolume& delta;
    const MipVolume* scene;
    const MipVolume* object;
    const MipVolume* objectLight;
};

DELTAGI_LANE_KERNEL void traceLightChangeConeLanes(std::span<const Cone> cones,
                                                   const ChangeConeVolumes& volumes,
                                                   const VisibilityVolumes& visibility,
                                                   const ConeTraceSettings& settings,
                                                   std::span<glm::vec3> out) {
    const LaneVolume full(&volumes.full), delta(&volumes.delta), scene(volumes.scene);
    const auto [sceneBackface, objectBackface] = backfaceWeights(visibility, settings);
    LaneMarch march(cones, volumes.full, settings);
    // With the objects (a) and without them (b): rgb and the occlusion (c[3]).
    Channels a = zeroChannels(), b = zeroChannels();
    auto empty = [&](size_t i) { out[i] = glm::vec3(0.0f); };
    for (int lane = 0; lane < kLanes; ++lane) march.start(lane, empty);
    LaneCorners corners;
    VolumeLookup objectLookups[kLanes], fullLookups[kLanes];
    // `emitted`: the step's light times its opacity, in the lanes `where`.
    auto composite = [&](Channels & light, const FloatL(&emitted)[3], FloatL opacity, IntL where)
        __attribute__((always_inline, target("avx2,fma"))) {
        const FloatL clear = 1.0f - light.c[3];
        for (int c = 0; c < 3; ++c) {
            const FloatL contribution = emitted[c] * clear;
            light.c[c] = select(where,
                                settings.paperAccumulation ? light.c[c] * light.c[3] + contribution
                                                           : light.c[c] + contribution,
                                light.c[c]);
        }
        light.c[3] = select(where, light.c[3] + opacity * clear, light.c[3]);
    };
    while (const unsigned active = laneBits(march.active)) {
        march.sample(corners);
        const Channels sceneVisibility =
            volumes.scene ? gatherNear(*volumes.scene, true, scene, march, corners, active, objectLookups)
                          : zeroChannels();
        const FloatL sceneOcclusion =
            adaptedOcclusionL(sceneVisibility, march.dir, march.levelScale, settings, sceneBackface);
        // Near the objects, a lookup of their own: their volumes (visibility, light) are stored over the same
        // windows around them.
        const IntL nearObjects = march.mayRead(volumes.object, corners);
        const unsigned near = laneBits(nearObjects);
        FloatL objectOcclusion = splat(0.0f);
        if (near)
            objectOcclusion = adaptedOcclusionL(
                gatherNear(*volumes.object, false, scene, march, corners, near, objectLookups), march.dir,
                march.levelScale, settings, objectBackface);
        const FloatL opacityA = stepOpacityL(
            sceneOcclusion + objectOcclusion - sceneOcclusion * objectOcclusion, settings.stepScale);
        const FloatL opacityB = stepOpacityL(sceneOcclusion, settings.stepScale);
        const IntL seen = march.active & (opacityA > 0.0f);
        if (const unsigned seenLanes = laneBits(seen)) {
            const Channels fullSample =
                gatherNear(volumes.full, true, full, march, corners, seenLanes, fullLookups);
            const Channels deltaSample =
                gatherNear(volumes.delta, true, delta, march, corners, seenLanes, fullLookups);
            if (volumes.objectLight) {
                // The objects' light at their own lookup near them, elsewhere (where it may be non-zero) at
                // the full volume's.
                Float4 samples[kLanes] = {};
                const unsigned elsewhere = laneBits(march.mayRead(volumes.objectLight, corners)) & ~near;
                for (int lane = 0; lane < kLanes; ++lane) {
                    if (!(seenLanes >> lane & 1u)) continue;
                    if (near >> lane & 1u)
                        samples[lane] = volumes.objectLight->gatherFloat4(objectLookups[lane]);
                    else if (elsewhere >> lane & 1u)
                        samples[lane] = volumes.objectLight->gatherFloat4(
                            volumes.full.lookup(march.positionOf(lane), march.level[lane]));
                }
                const Channels objects = transpose(samples);
                Channels sceneLight;
                for (int c = 0; c < 4; ++c) sceneLight.c[c] = fullSample.c[c] - objects.c[c];
                const Channels sceneRadiance = radianceL(sceneLight);
                FloatL emitted[3];
                if (settings.objectLightByRays) {  // the rays bring the objects' light and what they hide
                    for (int c = 0; c < 3; ++c) emitted[c] = sceneRadiance.c[c] * opacityB;
                    composite(a, emitted, opacityB, seen);
                } else {
                    const Channels objectRadiance = radianceL(objects);
                    for (int c = 0; c < 3; ++c)
                        emitted[c] =
                            sceneRadiance.c[c] * opacityB + objectRadiance.c[c] * (opacityA - opacityB);
                    composite(a, emitted, opacityA, seen);
                }
            } else {
                const Channels radiance = radianceL(fullSample);
                FloatL emitted[3];
                for (int c = 0; c < 3; ++c) emitted[c] = radiance.c[c] * opacityA;
                composite(a, emitted, opacityA, seen & (fullSample.c[3] > kEmpty));
            }
            // The real scene's light alone, by the scene's occupancy.
            const IntL sceneSeen = seen & (opacityB > 0.0f) & (sceneVisibility.c[0] > kEmpty);
            const FloatL inverse = 1.0f / select(sceneSeen, sceneVisibility.c[0], splat(1.0f));
            FloatL emitted[3];
            for (int c = 0; c < 3; ++c)
                emitted[c] = (fullSample.c[c] - deltaSample.c[c]) * inverse * opacityB;
            composite(b, emitted, opacityB, sceneSeen);
        }
        unsigned ended = march.advance((a.c[3] < settings.maxOcclusion) | (b.c[3] < settings.maxOcclusion));
        for (; ended; ended &= ended - 1) {
            const int lane = std::countr_zero(ended);
            out[march.cone[lane]] = {a.c[0][lane] - b.c[0][lane], a.c[1][lane] - b.c[1][lane],
                                     a.c[2][lane] - b.c[2][lane]};
            for (int c = 0; c < 4; ++c) a.c[c][lane] = b.c[c][lane] = 0.0f;
            march.start(lane, empty);
        }
    }
}

}  // namespace
}  // namespace deltagi
#endif  // DELTAGI_CONE_LANES

namespace deltagi {
namespace {

using cone_march::kMaxLevels;

// Whether the cones are traced in lanes here: the kernels are built, and the CPU has AVX2 and FMA.
bool lanesAvailable() {
#if DELTAGI_CONE_LANES
    static const bool available = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return available;
#else
    return false;
#endif
}

// Whether the lanes' kernels can read the volumes as they need: the volumes the lookup is shared by stored
// whole, over the reference's region and levels.
bool readableInLanes(const MipVolume& reference, std::initializer_list<const MipVolume*> shared) {
    if (!lanesAvailable() || reference.levelCount() > kMaxLevels) return false;
    for (const MipVolume* v : shared) {
        if (!v) continue;
        if (v->levelCount() != reference.levelCount() ||
            v->region().resolution != reference.region().resolution ||
            v->region().origin != reference.region().origin || v->region().size != reference.region().size)
            return false;
        for (int l = 0; l < v->levelCount(); ++l)
            if (!v->level(l).whole()) return false;
    }
    return true;
}

}  // namespace

void traceLightCones(std::span<const Cone> cones, const MipVolume& light, const VisibilityVolumes& visibility,
                     const ConeTraceSettings& settings, std::span<glm::vec3> out, int64_t* steps) {
    if (!readableInLanes(light, {&light, visibility.scene})) {
        for (size_t i = 0; i < cones.size(); ++i)
            out[i] = traceLightCone(cones[i], light, visibility, settings, steps);
        return;
    }
#if DELTAGI_CONE_LANES
    const bool objectWhole = visibility.object && readableInLanes(light, {visibility.object});
    traceLightConeLanes(cones, {light, visibility.scene, visibility.object, objectWhole}, visibility,
                        settings, out, steps);
#endif
}

void traceLightChangeCones(std::span<const Cone> cones, const MipVolume& fullLight,
                           const MipVolume& deltaLight, const VisibilityVolumes& visibility,
                           const ConeTraceSettings& settings, const MipVolume* objectLight,
                           std::span<glm::vec3> out) {
    if (!readableInLanes(fullLight, {&fullLight, &deltaLight, visibility.scene})) {
        for (size_t i = 0; i < cones.size(); ++i)
            out[i] = traceLightChangeCone(cones[i], fullLight, deltaLight, visibility, settings, objectLight);
        return;
    }
#if DELTAGI_CONE_LANES
    traceLightChangeConeLanes(cones,
                              {fullLight, deltaLight, visibility.scene, visibility.object, objectLight},
                              visibility, settings, out);
#endif
}

}  // namespace deltagi
