// The edge-aware filter eight pixels at a time in AVX2 lanes: the same bits as the one-pixel code of
// denoise.cpp, which includes this where DELTAGI_FILTER_LANES is set (GCC on x86-64). Internal to
// denoise.cpp.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include <immintrin.h>

#include "core/large_blocks.h"
#include "core/parallel.h"
#include "pipeline/denoise_pass.h"

namespace deltagi::denoise_pass {

// ---- The pixels between the samples eight at a time (filterRowWithoutPlan's interpolation, in lanes) ----
//
// Eight neighbouring pixels of a row in the lanes of 8-float vectors: each lane works its pixel's weights and
// value out with the same operations in the same order as cellNeighbourWeights, interpolationWeights and
// interpolatePixel (no fused multiply-adds: compiled for AVX2 alone), so that the result is the same bits.
// The cell samples a lane reads come from a copy of the pass's samples in planes (LaneSamples), moved into
// the lanes by one permutation per plane and corner. Pixels without a sample on their surface take the full
// filter, as there, one at a time.
#define DELTAGI_FILTER_KERNEL __attribute__((target("avx2")))
#define DELTAGI_FILTER_INLINE [[gnu::always_inline]] inline __attribute__((target("avx2")))

using FloatL = float __attribute__((vector_size(32)));
using IntL = int32_t __attribute__((vector_size(32)));
constexpr int kLanes = 8;

// The filter runs in lanes where at least 1 / kLaneWindowsShare of a pass's windows hold a value.
constexpr size_t kLaneWindowsShare = 4;

// Whether the CPU runs the lanes' kernel.
inline bool filterLanesAvailable() {
    static const bool available = __builtin_cpu_supports("avx2");
    return available;
}

// The pass's samples in planes of floats, with `pad` samples around the kept grid (kLanes + pad more on the
// right, pad + 1 below) that are not valid, as the samples past its edge are for the filter's window and
// cellSamples: their positions, normals, validity and values (the window filter's), and once the samples are
// filtered, their filtered values and whether those are non-zero (the interpolation's).
struct LaneSamples {
    template <typename T>
    using Plane = std::vector<T, UnsetAllocator<T>>;  // written in full where it is made
    int pad = 1, width = 0;
    size_t planeSize = 0;
    Plane<float> qx, qy, qz, nx, ny, nz;
    Plane<int32_t> valid;    // -1 or 0
    Plane<float> values;     // channel c's plane from c * planeSize
    Plane<float> filtered;   // likewise
    Plane<int32_t> nonZero;  // -1 or 0

    size_t index(const FilterPass& f, int sx, int sy) const {
        return static_cast<size_t>(sy - f.oy + pad) * width + (sx - f.ox + pad);
    }
    // A window's centre may lie one past the grid's last row (filterPixel).
    int rows(const FilterPass& f) const { return f.sh + 2 * pad + 1; }
    // Calls each(j, k) for every entry j of a plane, k the sample there in the pass's grid (none: kNone).
    static constexpr size_t kNone = ~size_t{0};
    template <typename Each>
    void forEachEntry(const FilterPass& f, Each&& each) const {
        parallelFor(0, rows(f), 16, [&](int64_t row) {
            const int sy = static_cast<int>(row) - pad;
            for (int col = 0; col < width; ++col) {
                const int sx = col - pad;
                const bool inGrid = sy >= 0 && sy < f.sh && sx >= 0 && sx < f.sw;
                each(static_cast<size_t>(row) * width + col,
                     inGrid ? static_cast<size_t>(sy) * f.sw + sx : kNone);
            }
        });
    }
};

// The samples' positions, normals, validity and values in planes, around the window's radius.
inline LaneSamples laneSamples(const FilterPass& f, int channels) {
    LaneSamples s;
    s.pad = std::max(f.r, 1);
    s.width = f.sw + 2 * s.pad + kLanes;
    s.planeSize = static_cast<size_t>(s.width) * s.rows(f);
    for (LaneSamples::Plane<float>* plane : {&s.qx, &s.qy, &s.qz, &s.nx, &s.ny, &s.nz})
        plane->resize(s.planeSize);
    s.valid.resize(s.planeSize);
    s.values.resize(s.planeSize * channels);
    s.forEachEntry(f, [&](size_t j, size_t k) {
        const bool valid = k != LaneSamples::kNone && f.samples[k].valid;
        const FilterSample q = valid ? f.samples[k] : FilterSample{glm::vec3(0.0f), glm::vec3(0.0f), false};
        s.valid[j] = valid ? -1 : 0;
        s.qx[j] = q.position.x, s.qy[j] = q.position.y, s.qz[j] = q.position.z;
        s.nx[j] = q.normal.x, s.ny[j] = q.normal.y, s.nz[j] = q.normal.z;
        for (int c = 0; c < channels; ++c)
            s.values[c * s.planeSize + j] = valid ? f.sampleValues[k * channels + c] : 0.0f;
    });
    return s;
}

// The samples' filtered values in planes.
inline void addFiltered(LaneSamples& s, const FilterPass& f, std::span<const float> filtered,
                        std::span<const uint8_t> filteredNonZero, int channels) {
    s.filtered.resize(s.planeSize * channels);
    s.nonZero.resize(s.planeSize);
    s.forEachEntry(f, [&](size_t j, size_t k) {
        const bool valid = k != LaneSamples::kNone && f.samples[k].valid;
        s.nonZero[j] = valid && filteredNonZero[k] ? -1 : 0;
        for (int c = 0; c < channels; ++c)
            s.filtered[c * s.planeSize + j] = valid ? filtered[k * channels + c] : 0.0f;
    });
}

DELTAGI_FILTER_INLINE FloatL sqrtL(FloatL x) {
    return reinterpret_cast<FloatL>(_mm256_sqrt_ps(reinterpret_cast<__m256>(x)));
}
DELTAGI_FILTER_INLINE FloatL toFloatL(IntL x) {
    return reinterpret_cast<FloatL>(_mm256_cvtepi32_ps(reinterpret_cast<__m256i>(x)));
}
DELTAGI_FILTER_INLINE IntL splatInt(int32_t x) {
    return IntL{} + x;
}
DELTAGI_FILTER_INLINE bool anyOf(IntL mask) {
    return !_mm256_testz_si256(reinterpret_cast<__m256i>(mask), reinterpret_cast<__m256i>(mask));
}
DELTAGI_FILTER_INLINE bool allOf(IntL mask) {
    return _mm256_testc_si256(reinterpret_cast<__m256i>(mask), reinterpret_cast<__m256i>(splatInt(-1)));
}
DELTAGI_FILTER_INLINE FloatL splat(float x) {
    return FloatL{} + x;
}
DELTAGI_FILTER_INLINE FloatL loadL(const float* p) {
    FloatL v;
    std::memcpy(&v, p, sizeof(v));
    return v;
}
DELTAGI_FILTER_INLINE IntL loadL(const int32_t* p) {
    IntL v;
    std::memcpy(&v, p, sizeof(v));
    return v;
}
// Lane l of the result is p[offset[l]] (offsets 0..7).
DELTAGI_FILTER_INLINE FloatL permuted(const float* p, IntL offset) {
    return reinterpret_cast<FloatL>(
        _mm256_permutevar8x32_ps(reinterpret_cast<__m256>(loadL(p)), reinterpret_cast<__m256i>(offset)));
}
DELTAGI_FILTER_INLINE IntL permuted(const int32_t* p, IntL offset) {
    return reinterpret_cast<IntL>(
        _mm256_permutevar8x32_epi32(reinterpret_cast<__m256i>(loadL(p)), reinterpret_cast<__m256i>(offset)));
}

// The surfaces of eight pixels in lanes: lane l's is points[offset[l]] (lanes off `inRow` read nothing),
// gathered a float at a time; `valid` where the lane is in the row and its point has a surface.
struct PointLanes {
    FloatL x, y, z, nx, ny, nz;
    IntL valid;
};
DELTAGI_FILTER_INLINE PointLanes pointLanes(const SurfacePoint* points, IntL offset, IntL inRow) {
    constexpr int kPointFloats = sizeof(SurfacePoint) / sizeof(float);
    static_assert(sizeof(SurfacePoint) % sizeof(float) == 0 && offsetof(SurfacePoint, material) % 8 == 0);
    constexpr int kMaterial =
        offsetof(SurfacePoint, material) / sizeof(float);  // a pointer: two floats' bits
    const float* first = reinterpret_cast<const float*>(points);
    const IntL index = offset * kPointFloats;
    auto gather = [&](int at) __attribute__((always_inline, target("avx2"))) {
        return reinterpret_cast<FloatL>(
            _mm256_mask_i32gather_ps(_mm256_setzero_ps(), first + at, reinterpret_cast<__m256i>(index),
                                     reinterpret_cast<__m256>(inRow), sizeof(float)));
    };
    const IntL material =
        reinterpret_cast<IntL>(gather(kMaterial)) | reinterpret_cast<IntL>(gather(kMaterial + 1));
    return {gather(0), gather(1), gather(2), gather(3), gather(4), gather(5), inRow & (material != 0)};
}

// Lane by lane, whether pixels [i0, i0 + 8) are to be filtered (settings.filtered; all when it is empty), the
// first `count` of them.
DELTAGI_FILTER_INLINE IntL filteredLanes(const FilterPass& f, size_t i0, int count) {
    if (f.s.filtered.empty()) return splatInt(-1);
    uint64_t bytes = 0;
    std::memcpy(&bytes, &f.s.filtered[i0], static_cast<size_t>(std::min(count, kLanes)));
    return reinterpret_cast<IntL>(_mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<int64_t>(bytes)))) != 0;
}

// planeAllowance(p.position), lane by lane.
DELTAGI_FILTER_INLINE FloatL planeAllowanceL(const FilterPass& f, const PointLanes& p) {
    const FloatL ex = p.x - f.eye.x, ey = p.y - f.eye.y, ez = p.z - f.eye.z;
    return f.s.planeDistance * f.pixelAngle * sqrtL((ex * ex + ey * ey) + ez * ez);
}

// sameSurfaceWeight (and neighbourWeight) of the samples q (positions, normals, validity) at pixel offsets
// (ox, oy) from the pixels p, lane by lane.
DELTAGI_FILTER_INLINE FloatL sameSurfaceWeightL(const FilterPass& f, const PointLanes& p,
                                                FloatL planeAllowance, FloatL qx, FloatL qy, FloatL qz,
                                                FloatL nx, FloatL ny, FloatL nz, IntL valid, IntL ox,
                                                IntL oy) {
    // offsetLength: sqrt(px^2 + py^2 + 1) at the sample's offset from the pixel.
    const FloatL allowance = sqrtL(toFloatL(ox * ox + oy * oy + 1)) * planeAllowance;
    const FloatL cosN = (p.nx * nx + p.ny * ny) + p.nz * nz;
    const FloatL offPlane = (p.nx * (qx - p.x) + p.ny * (qy - p.y)) + p.nz * (qz - p.z);
    const FloatL distance = offPlane < 0.0f ? -offPlane : offPlane;
    const IntL usable = valid & ~(cosN <= 0.0f) & ~(distance > allowance);
    return usable ? powInt(cosN, f.s.normalPower) : FloatL{};
}

// Eight pixels of row y through the edge-aware filter (filterPixel<C>), lane l's at x[l] with surface p: its
// value into result[c][l]. Returns the lanes that had a usable sample (the others are holes; their result is
// not written).
template <int C>
DELTAGI_FILTER_INLINE IntL windowInLanes(const FilterPass& f, const LaneSamples& s, int y, IntL x,
                                         const PointLanes& p, float (&result)[C][kLanes]) {
    const int r = f.r, stride = f.stride, window = 2 * r + 1;
    // The samples nearest to the pixels: the windows' centres.
    const int yCentre = (y + stride / 2) / stride;
    const IntL xCentre = reinterpret_cast<IntL>(
        _mm256_cvttps_epi32(reinterpret_cast<__m256>(toFloatL(x + stride / 2) / static_cast<float>(stride))));
    const int first = xCentre[0];
    const IntL lane = xCentre - first;
    alignas(32) int32_t hasValue[kLanes];
    for (int l = 0; l < kLanes; ++l)
        hasValue[l] = p.valid[l] && f.windowHasValue[f.centreIndex(xCentre[l], yCentre)] ? -1 : 0;
    const IntL windowHasValue = loadL(hasValue);
    const FloatL planeAllowance = planeAllowanceL(f, p);
    FloatL sum[C] = {}, weightSum{};
    IntL anyUsable{};
    // Windows of zeros alone: done once each has a usable sample.
    const bool zerosAlone = !anyOf(windowHasValue);
    for (int dy = -r; dy <= r && !(zerosAlone && allOf(anyUsable | ~p.valid)); ++dy) {
        const size_t row = s.index(f, first, yCentre + dy);
        const IntL oy = splatInt((yCentre + dy) * stride - y);
        for (int dx = -r; dx <= r; ++dx) {
            const size_t at = row + dx;
            const FloatL w = sameSurfaceWeightL(
                f, p, planeAllowance, permuted(&s.qx[at], lane), permuted(&s.qy[at], lane),
                permuted(&s.qz[at], lane), permuted(&s.nx[at], lane), permuted(&s.ny[at], lane),
                permuted(&s.nz[at], lane), permuted(&s.valid[at], lane), (xCentre + dx) * stride - x, oy);
            anyUsable |= w > 0.0f;
            if (zerosAlone) continue;  // only whether some sample is usable matters
            const IntL weighs = w != 0.0f;
            const FloatL spatial = w * f.spatial[static_cast<size_t>(dy + r) * window + dx + r];
            for (int c = 0; c < C; ++c)
                sum[c] = weighs ? sum[c] + permuted(&s.values[c * s.planeSize + at], lane) * spatial : sum[c];
            weightSum = weighs ? weightSum + spatial : weightSum;
        }
    }
    // A window of zeros: zero where some sample is usable.
    for (int c = 0; c < C; ++c) {
        const FloatL value = windowHasValue ? sum[c] / weightSum : FloatL{};
        std::memcpy(result[c], &value, sizeof(value));
    }
    return windowHasValue ? (weightSum > 0.0f) : anyUsable;
}

// The pixels [x0, x1) of row y as filterRowWithoutPlan<C> without settings.interpolate gives them.
template <int C>
DELTAGI_FILTER_KERNEL void filterRowInLanes(const FilterPass& f, const LaneSamples& s, int y, int x0, int x1,
                                            std::span<float> out, std::vector<size_t>& holes) {
    const IntL laneIndex = {0, 1, 2, 3, 4, 5, 6, 7};
    for (int x = x0; x < x1; x += kLanes) {
        const size_t i0 = static_cast<size_t>(y) * f.width + x;
        const IntL inRow = (laneIndex < x1 - x) & filteredLanes(f, i0, x1 - x);
        const PointLanes p = pointLanes(&f.points[i0], laneIndex, inRow);
        if (!anyOf(p.valid)) continue;
        float result[C][kLanes];
        const IntL ok = windowInLanes<C>(f, s, y, x + laneIndex, p, result);
        for (int l = 0; l < kLanes; ++l) {
            if (!p.valid[l]) continue;
            if (!ok[l]) {
                holes.push_back(i0 + l);
                continue;
            }
            for (int c = 0; c < C; ++c) out[(i0 + l) * C + c] = result[c][l];
        }
    }
}

// The samples [sx0, sx1) of row sy through the filter, as filterImage<C> filters them one at a time into
// `filtered` (a hole's left as it is).
template <int C>
DELTAGI_FILTER_KERNEL void filterSamplesInLanes(const FilterPass& f, const LaneSamples& s, int sy, int sx0,
                                                int sx1, std::span<float> filtered) {
    const IntL laneIndex = {0, 1, 2, 3, 4, 5, 6, 7};
    const int stride = f.stride, y = sy * stride;
    for (int sx = sx0; sx < sx1; sx += kLanes) {
        const IntL inRow =
            (laneIndex < sx1 - sx) & (loadL(&s.valid[s.index(f, sx, sy)]) != 0);  // the valid samples
        const PointLanes p =
            pointLanes(&f.points[static_cast<size_t>(y) * f.width + sx * stride], laneIndex * stride, inRow);
        if (!anyOf(p.valid)) continue;
        float result[C][kLanes];
        const IntL ok = windowInLanes<C>(f, s, y, (sx + laneIndex) * stride, p, result);
        for (int l = 0; l < kLanes; ++l)
            if (p.valid[l] && ok[l])
                for (int c = 0; c < C; ++c) filtered[f.sampleIndex(sx + l, sy) * C + c] = result[c][l];
    }
}

// interpolatePixel in lanes: the pixels' values from the filtered values of their cells' corners (at
// corner(n) in the planes, moved into the lanes by `lane`) and their nonZero flags, with their interpolation
// weights, into sums[c] (zero where every weighed corner is zero). Returns the lanes with a positive weight;
// the others take the full filter.
template <int C, typename Corner>
DELTAGI_FILTER_INLINE IntL interpolateInLanes(const LaneSamples& s, const FloatL (&weight)[4],
                                              const IntL (&nonZero)[4], Corner&& corner, IntL lane,
                                              float (&sums)[C][kLanes]) {
    IntL any{}, anyNonZero{};
    for (int n = 0; n < 4; ++n) {
        any |= weight[n] > 0.0f;
        anyNonZero |= (weight[n] > 0.0f) & nonZero[n];
    }
    for (int c = 0; c < C; ++c) {
        FloatL sum{};
        for (int n = 0; n < 4; ++n) {
            const FloatL v = permuted(&s.filtered[c * s.planeSize + corner(n)], lane);
            sum = weight[n] != 0.0f ? sum + v * weight[n] : sum;
        }
        sum = anyNonZero ? sum : FloatL{};
        std::memcpy(sums[c], &sum, sizeof(sum));
    }
    return any;
}

// The pixels [x0, x1) of row y interpolated with the plan's weights, as filterImage<C> does it one pixel at a
// time (interpolatePixel with the pixel's weights from the plan).
template <int C>
DELTAGI_FILTER_KERNEL void planRowInLanes(const FilterPass& f, const LaneSamples& s,
                                          const InterpolationPlan& plan, int y, int x0, int x1,
                                          std::span<float> out, std::vector<size_t>& holes) {
    const int stride = f.stride, sy = y / stride;
    const size_t rowAbove = s.index(f, f.ox, sy), rowBelow = rowAbove + s.width;
    const IntL laneIndex = {0, 1, 2, 3, 4, 5, 6, 7};
    const float strideF = static_cast<float>(stride);
    for (int x = x0; x < x1; x += kLanes) {
        const size_t i0 = static_cast<size_t>(y) * f.width + x;
        const IntL inRow = (laneIndex < x1 - x) & filteredLanes(f, i0, x1 - x);
        // The pixels' four weights (-1 first: no surface).
        const float* weights = plan.weights[i0].data();
        FloatL weight[4];
        for (int n = 0; n < 4; ++n)
            weight[n] = reinterpret_cast<FloatL>(_mm256_mask_i32gather_ps(
                _mm256_setzero_ps(), weights + n, reinterpret_cast<__m256i>(laneIndex * 4),
                reinterpret_cast<__m256>(inRow), sizeof(float)));
        const IntL on = inRow & ~(weight[0] < 0.0f);
        if (!anyOf(on)) continue;
        const IntL sx = reinterpret_cast<IntL>(
            _mm256_cvttps_epi32(reinterpret_cast<__m256>(toFloatL(x + laneIndex) / strideF)));
        const int first = sx[0];
        const IntL lane = sx - first;
        const size_t base = static_cast<size_t>(first - f.ox);
        auto corner = [&](int n) { return (n >> 1 ? rowBelow : rowAbove) + base + (n & 1); };
        IntL nonZero[4];
        for (int n = 0; n < 4; ++n) nonZero[n] = permuted(&s.nonZero[corner(n)], lane);
        float sums[C][kLanes];
        const IntL any = interpolateInLanes<C>(s, weight, nonZero, corner, lane, sums);
        for (int l = 0; l < kLanes; ++l) {
            if (!on[l]) continue;
            const size_t i = i0 + l;
            float* dst = &out[i * C];
            if (!any[l]) {
                if (!filterPixel<C>(f, x + l, y, f.points[i], dst)) holes.push_back(i);
            } else {
                for (int c = 0; c < C; ++c) dst[c] = sums[c][l];
            }
        }
    }
}

// The pixels [x0, x1) of row y as filterRowWithoutPlan<C> with settings.interpolate gives them.
template <int C>
DELTAGI_FILTER_KERNEL void interpolateRowInLanes(const FilterPass& f, const LaneSamples& s, int y, int x0,
                                                 int x1, std::span<float> out, std::vector<size_t>& holes) {
    const int stride = f.stride, sy = y / stride;
    const float fy = static_cast<float>(y - sy * stride) / static_cast<float>(stride);
    const size_t rowAbove = s.index(f, f.ox, sy), rowBelow = rowAbove + s.width;
    // The vertical offsets (in pixels) of the cell's rows of samples from the row.
    const IntL pyAbove = splatInt(sy * stride - y), pyBelow = splatInt((sy + 1) * stride - y);
    const IntL laneIndex = {0, 1, 2, 3, 4, 5, 6, 7};
    const float strideF = static_cast<float>(stride);
    for (int x = x0; x < x1; x += kLanes) {
        // The lanes' pixels: those past x1 are not read.
        const size_t i0 = static_cast<size_t>(y) * f.width + x;
        const IntL inRow = (laneIndex < x1 - x) & filteredLanes(f, i0, x1 - x);
        const PointLanes p = pointLanes(&f.points[i0], laneIndex, inRow);
        const IntL on = p.valid;
        if (!anyOf(on)) continue;
        // Each pixel's cell (first sample sx), by a division of floats that is exact for such integers.
        const IntL xs = x + laneIndex;
        const IntL sx =
            reinterpret_cast<IntL>(_mm256_cvttps_epi32(reinterpret_cast<__m256>(toFloatL(xs) / strideF)));
        const int first = sx[0];
        const IntL lane = sx - first;
        const IntL toSample = sx * stride - xs;  // the cell's first sample's x offset from the pixel
        const FloatL planeAllowance = planeAllowanceL(f, p);
        const size_t base = static_cast<size_t>(first - f.ox);
        auto corner = [&](int n) { return (n >> 1 ? rowBelow : rowAbove) + base + (n & 1); };
        IntL nonZero[4];
        for (int n = 0; n < 4; ++n) nonZero[n] = permuted(&s.nonZero[corner(n)], lane);
        // Corner n's weight as a neighbour (cellNeighbourWeights' lane n).
        auto neighbourWeight = [&](int n) __attribute__((always_inline, target("avx2"))) {
            const size_t at = corner(n);
            return sameSurfaceWeightL(f, p, planeAllowance, permuted(&s.qx[at], lane),
                                      permuted(&s.qy[at], lane), permuted(&s.qz[at], lane),
                                      permuted(&s.nx[at], lane), permuted(&s.ny[at], lane),
                                      permuted(&s.nz[at], lane), permuted(&s.valid[at], lane),
                                      toSample + (n & 1) * stride, n >> 1 ? pyBelow : pyAbove);
        };
        FloatL weight[4];
        weight[0] = neighbourWeight(0);
        // The cell's samples all zero and the first on the pixel's surface: zero (filterRowWithoutPlan's
        // shortcut); when so for every pixel, the other corners are not needed.
        const IntL zeroCell = ~(nonZero[0] | nonZero[1] | nonZero[2] | nonZero[3]) & (weight[0] > 0.0f);
        if (allOf(zeroCell | ~on)) {
            for (int l = 0; l < kLanes; ++l)
                if (on[l]) std::fill_n(&out[(static_cast<size_t>(y) * f.width + x + l) * C], C, 0.0f);
            continue;
        }
        for (int n = 1; n < 4; ++n) weight[n] = neighbourWeight(n);
        // interpolationWeights.
        const FloatL fx = toFloatL(-toSample) / static_cast<float>(stride);
        constexpr float kMinBilinear = 1e-3f;
        const FloatL bilinear[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy, fx * fy};
        for (int n = 0; n < 4; ++n)
            weight[n] *= bilinear[n] < kMinBilinear ? splat(kMinBilinear) : bilinear[n];
        const FloatL weightSum = ((weight[0] + weight[1]) + weight[2]) + weight[3];
        const IntL positive = weightSum > 0.0f, keep = positive | (weightSum != weightSum);
        for (int n = 0; n < 4; ++n) {
            weight[n] = positive ? weight[n] / weightSum : weight[n];
            weight[n] = keep ? weight[n] : FloatL{};
        }
        float sums[C][kLanes];
        const IntL any = interpolateInLanes<C>(s, weight, nonZero, corner, lane, sums);
        const IntL fallback = ~zeroCell & ~any;
        for (int l = 0; l < kLanes; ++l) {
            if (!on[l]) continue;
            const size_t i = static_cast<size_t>(y) * f.width + x + l;
            float* dst = &out[i * C];
            if (zeroCell[l]) {
                std::fill_n(dst, C, 0.0f);
            } else if (fallback[l]) {
                if (!filterPixel<C>(f, x + l, y, f.points[i], dst)) holes.push_back(i);
            } else {
                for (int c = 0; c < C; ++c) dst[c] = sums[c][l];
            }
        }
    }
}

}  // namespace deltagi::denoise_pass
