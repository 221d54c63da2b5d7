#include "pipeline/denoise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <optional>
#include <utility>

#include "core/large_blocks.h"
#include "core/parallel.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DELTAGI_FILTER_LANES 1
#include <immintrin.h>
// The 8-float helpers are always inlined into the kernel: the note that 32-byte vectors are passed
// differently with AVX than without does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace deltagi {

namespace {

// x^n for a float or, lane by lane, a vector of them (interpolationWeights, the filter in lanes: always
// inlined, so that it is compiled for their instruction set).
template <typename T>
[[gnu::always_inline]] inline T powInt(T x, int n) {
    if (n == 16) {  // the filter's normal power: the loop's own squarings, unrolled (the same bits)
        x *= x;
        x *= x;
        x *= x;
        return x * x;
    }
    T r = T{} + 1.0f;
    for (; n > 0; n >>= 1, x *= x)
        if (n & 1) r *= x;
    return r;
}

// The filter's sample at a point (invalid where the pass holds no value there: `traced` false).
FilterSample filterSampleOf(const SurfacePoint& q, bool traced = true) {
    return {q.position, q.normal, q.valid() && traced};
}

// Everything one filter pass reads, shared by its rows.
struct FilterPass {
    std::span<float> values;
    int channels;
    std::span<const SurfacePoint> points;
    int width, height;
    glm::vec3 eye;
    float pixelAngle;
    const DenoiseSettings& s;
    int r, stride, reach, side;
    // The grid of samples the pass keeps: (ox, oy) its first, sw x sh of them. The whole image's without a
    // rectangle or with a plan (built over the whole image); else the rectangle's samples and one more on
    // each side, which hold every window centre of its pixels (the samples outside the rectangle are never
    // valid, so that leaving them out changes no weight).
    int ox, oy, sw, sh;
    std::vector<float> spatial{};       // (2r+1)^2 window weights
    std::vector<float> offsetLength{};  // sqrt(px^2 + py^2 + 1) for every pixel offset a window can have
    std::vector<float> fraction{};      // d / stride for d in [0, stride): a pixel's place between samples
    std::vector<FilterSample> samples{};
    std::vector<float> sampleValues{};
    // Per window centre ((sw + 1) x (sh + 1): a centre may lie one past the last sample): whether any sample
    // of its window holds a non-zero value. A window of zeros filters to zero, whatever its weights.
    std::vector<uint8_t> windowHasValue{};

    // Sample (sx, sy) of the image's stride grid in the kept grid, and window centre (cx, cy).
    size_t sampleIndex(int sx, int sy) const { return static_cast<size_t>(sy - oy) * sw + (sx - ox); }
    size_t centreIndex(int cx, int cy) const { return static_cast<size_t>(cy - oy) * (sw + 1) + (cx - ox); }
    // How far a neighbour may lie off the tangent plane of the surface at `position`, per unit of
    // offsetLength: settings.planeDistance pixel sizes there.
    float planeAllowance(glm::vec3 position) const {
        return s.planeDistance * pixelAngle * glm::length(position - eye);
    }
    // Whether the pixels between the samples are interpolated from them (settings.interpolate at a stride).
    bool interpolates() const { return stride > 1 && s.interpolate; }
    // offsetLength's entry for sample (sx, sy) seen from pixel (x, y).
    size_t offsetIndex(int sx, int sy, int x, int y) const {
        return static_cast<size_t>(sy * stride - y + reach) * side + sx * stride - x + reach;
    }
};

// Whether sample k is a usable neighbour of pixel p: on the same side, near p's tangent plane. Returns its
// weight (0: not usable) without the spatial factor.
// The test of both (surfaceWeight too): a point at `position` with `normal` against p.
inline float sameSurfaceWeight(const SurfacePoint& p, glm::vec3 position, glm::vec3 normal, float allowance,
                               int normalPower) {
    const float cosN = glm::dot(p.normal, normal);
    if (cosN <= 0.0f) return 0.0f;
    // Off the tangent plane by more than the allowance: another surface (a depth edge).
    if (std::abs(glm::dot(p.normal, position - p.position)) > allowance) return 0.0f;
    return powInt(cosN, normalPower);
}
inline float neighbourWeight(const FilterPass& f, const SurfacePoint& p, const FilterSample& q,
                             float allowance) {
    return q.valid ? sameSurfaceWeight(p, q.position, q.normal, allowance, f.s.normalPower) : 0.0f;
}

// The edge-aware filter at pixel (x, y), whose surface is p, from the samples of its window, into `dst`.
// Returns false, leaving `dst` alone, when no sample is usable (a hole). C is the channel count when known at
// compile time (0: f.channels).
template <int C>
bool filterPixel(const FilterPass& f, int x, int y, const SurfacePoint& p, float* dst) {
    const int channels = C > 0 ? C : f.channels;
    std::array<float, (C > 0 ? C : 1)> fixedSum{};
    std::vector<float> dynamicSum(C > 0 ? 0 : channels);
    float* sum = C > 0 ? fixedSum.data() : dynamicSum.data();
    const int r = f.r, stride = f.stride;
    // The samples nearest to the pixel (below and right of it when between two): the window's centre.
    const int xCentre = (x + stride / 2) / stride, yCentre = (y + stride / 2) / stride;
    const int sxBegin = std::max(xCentre - r, f.ox), sxEnd = std::min(xCentre + r, f.ox + f.sw - 1);
    const int syBegin = std::max(yCentre - r, f.oy), syEnd = std::min(yCentre + r, f.oy + f.sh - 1);
    const float planeAllowance = f.planeAllowance(p.position);
    auto allowance = [&](int sx, int sy) {
        return planeAllowance * f.offsetLength[f.offsetIndex(sx, sy, x, y)];
    };
    if (!f.windowHasValue[f.centreIndex(xCentre, yCentre)]) {
        // All zeros: the result is zero if any sample is usable, else the pixel is a hole.
        for (int sy = syBegin; sy <= syEnd; ++sy)
            for (int sx = sxBegin; sx <= sxEnd; ++sx)
                if (neighbourWeight(f, p, f.samples[f.sampleIndex(sx, sy)], allowance(sx, sy)) > 0.0f) {
                    std::fill_n(dst, channels, 0.0f);
                    return true;
                }
        return false;
    }
    std::fill_n(sum, channels, 0.0f);
    float weightSum = 0.0f;
    for (int sy = syBegin; sy <= syEnd; ++sy) {
        const float* spatialRow = &f.spatial[static_cast<size_t>(sy - yCentre + r) * (2 * r + 1)];
        for (int sx = sxBegin; sx <= sxEnd; ++sx) {
            const size_t k = f.sampleIndex(sx, sy);
            float w = neighbourWeight(f, p, f.samples[k], allowance(sx, sy));
            if (w == 0.0f) continue;
            w *= spatialRow[sx - xCentre + r];
            const float* v = &f.sampleValues[k * channels];
            for (int c = 0; c < channels; ++c) sum[c] += v[c] * w;
            weightSum += w;
        }
    }
    if (!(weightSum > 0.0f)) return false;
    for (int c = 0; c < channels; ++c) dst[c] = sum[c] / weightSum;
    return true;
}

using Float4 = float __attribute__((vector_size(16)));
using Int4 = int32_t __attribute__((vector_size(16)));

// Stride > 1, the (up to) 4 samples around the pixels of cell (sx0, sy0) of the stride's grid, those whose
// first sample it is: (sx0, sy0), (sx0 + 1, sy0), (sx0, sy0 + 1), (sx0 + 1, sy0 + 1), in the lanes of 4-float
// vectors (one past the last row or column is none: not valid). The same for every pixel of the cell, so
// that a pass loads them once a cell and row instead of once a pixel.
struct CellSamples {
    int sx0, sy0;
    Float4 qx{}, qy{}, qz{}, nx{}, ny{}, nz{};
    Int4 valid{};
};
CellSamples cellSamples(const FilterPass& f, std::span<const FilterSample> samples, int sx0, int sy0) {
    CellSamples c{sx0, sy0};
    for (int n = 0; n < 4; ++n) {
        const int sx = sx0 + (n & 1), sy = sy0 + (n >> 1);
        if (sx >= f.ox + f.sw || sy >= f.oy + f.sh) continue;
        const FilterSample& q = samples[f.sampleIndex(sx, sy)];
        if (!q.valid) continue;
        c.valid[n] = -1;
        c.qx[n] = q.position.x, c.qy[n] = q.position.y, c.qz[n] = q.position.z;
        c.nx[n] = q.normal.x, c.ny[n] = q.normal.y, c.nz[n] = q.normal.z;
    }
    return c;
}

// Pixel (x, y) of cell c, whose surface is p: the filter's weight of each of the cell's samples as its
// neighbour (neighbourWeight, without the spatial factor; 0 where not usable), worked out side by side in
// the lanes, each lane as neighbourWeight and powInt work one out (the same operations in the same order:
// the same weights).
Float4 cellNeighbourWeights(const FilterPass& f, const CellSamples& c, int x, int y, const SurfacePoint& p) {
    const int stride = f.stride;
    // The sample (sx, sy)'s allowance is planeAllowance times offsetLength at its offset from the pixel.
    const size_t first = f.offsetIndex(c.sx0, c.sy0, x, y), below = static_cast<size_t>(stride) * f.side;
    const Float4 allowance = Float4{f.offsetLength[first], f.offsetLength[first + stride],
                                    f.offsetLength[first + below], f.offsetLength[first + below + stride]} *
                             f.planeAllowance(p.position);
    // sameSurfaceWeight in each lane: facing the same side, near p's tangent plane, cos^normalPower.
    const Float4 cosN = (p.normal.x * c.nx + p.normal.y * c.ny) + p.normal.z * c.nz;
    const Float4 offPlane = (p.normal.x * (c.qx - p.position.x) + p.normal.y * (c.qy - p.position.y)) +
                            p.normal.z * (c.qz - p.position.z);
    const Float4 distance = offPlane < 0.0f ? -offPlane : offPlane;
    const Int4 usable = c.valid & ~(cosN <= 0.0f) & ~(distance > allowance);
    return usable ? powInt(cosN, f.s.normalPower) : Float4{};
}

// Stride > 1: the filter's weight of cell (sx, sy)'s first sample, k00, as a neighbour of its pixel (x, y),
// whose surface is p (lane 0 of cellNeighbourWeights, the same bits).
float firstSampleWeight(const FilterPass& f, const SurfacePoint& p, int x, int y, int sx, int sy,
                        size_t k00) {
    return neighbourWeight(f, p, f.samples[k00],
                           f.planeAllowance(p.position) * f.offsetLength[f.offsetIndex(sx, sy, x, y)]);
}

// Stride > 1, the interpolation weights of pixel (x, y) of cell c from its samples' neighbour weights
// (cellNeighbourWeights): bilinear, and like the filter's only for the samples on the pixel's surface;
// normalized, in InterpolationPlan's order. All zero when none of them is on its surface.
std::array<float, 4> interpolationWeights(const FilterPass& f, const CellSamples& c, int x, int y, Float4 w) {
    const float fx = f.fraction[x - c.sx0 * f.stride], fy = f.fraction[y - c.sy0 * f.stride];
    // A small floor under the bilinear weight: a pixel on a sample's row still reads the row below when the
    // sample is on another surface.
    constexpr float kMinBilinear = 1e-3f;
    const Float4 bilinear = Float4{1.0f - fx, fx, 1.0f - fx, fx} * Float4{1.0f - fy, 1.0f - fy, fy, fy};
    w *= bilinear < kMinBilinear ? Float4{} + kMinBilinear : bilinear;
    // The sum in the neighbours' order (a zero adds nothing).
    const float weightSum = ((w[0] + w[1]) + w[2]) + w[3];
    std::array<float, 4> weights{};
    if (weightSum > 0.0f) w /= weightSum;  // the four divisions as one
    if (weightSum > 0.0f || weightSum != weightSum) std::memcpy(weights.data(), &w, sizeof(w));
    return weights;
}

// Stride > 1: whether any of the (up to) 4 filtered samples around cell (sx, sy) (its first, right, below and
// below right) is not zero.
bool cellHasValue(const FilterPass& f, std::span<const uint8_t> filteredNonZero, int sx, int sy) {
    const size_t k00 = f.sampleIndex(sx, sy);
    const bool right = sx + 1 < f.ox + f.sw, below = sy + 1 < f.oy + f.sh;
    return filteredNonZero[k00] || (right && filteredNonZero[k00 + 1]) ||
           (below && filteredNonZero[k00 + f.sw]) || (right && below && filteredNonZero[k00 + f.sw + 1]);
}

// Stride > 1, the pixels between the samples: the filtered values of the (up to) 4 samples around the pixel
// with `weights` (interpolationWeights); k00 is the first of them, (x / stride, y / stride). A pixel with
// none of them on its surface (an edge between samples) takes the full filter over its window. Returns false
// for a hole.
template <int C>
[[gnu::always_inline]] inline bool interpolatePixel(const FilterPass& f, std::span<const float> filtered,
                                                    std::span<const uint8_t> filteredNonZero, int x, int y,
                                                    size_t k00, const SurfacePoint* p,
                                                    const std::array<float, 4>& weights, float* dst) {
    const int channels = C > 0 ? C : f.channels;
    const size_t keys[4] = {k00, k00 + 1, k00 + f.sw, k00 + f.sw + 1};
    bool any = false, anyNonZero = false;
    for (int n = 0; n < 4; ++n)
        if (weights[n] > 0.0f) {
            any = true;
            anyNonZero = anyNonZero || filteredNonZero[keys[n]];
        }
    if (!any) return filterPixel<C>(f, x, y, p ? *p : f.points[static_cast<size_t>(y) * f.width + x], dst);
    if (!anyNonZero) {  // zeros all around (most of a shadow's change)
        std::fill_n(dst, channels, 0.0f);
        return true;
    }
    if constexpr (C > 0) {  // summed in registers, stored once
        std::array<float, C> sum{};
        for (int n = 0; n < 4; ++n) {
            if (weights[n] == 0.0f) continue;
            const float* v = &filtered[keys[n] * C];
            for (int c = 0; c < C; ++c) sum[c] += v[c] * weights[n];
        }
        std::copy_n(sum.data(), C, dst);
    } else {
        std::fill_n(dst, channels, 0.0f);
        for (int n = 0; n < 4; ++n) {
            if (weights[n] == 0.0f) continue;
            const float* v = &filtered[keys[n] * channels];
            for (int c = 0; c < channels; ++c) dst[c] += v[c] * weights[n];
        }
    }
    return true;
}

// The plan's weights for f's stride and settings, from its surfaces (built when it has none for them).
void buildPlan(const FilterPass& f, InterpolationPlan& plan) {
    const size_t pixels = static_cast<size_t>(f.width) * f.height;
    if (plan.stride == f.stride && plan.weights.size() == pixels) return;
    std::vector<FilterSample>& samples = plan.samples;
    samples.resize(static_cast<size_t>(f.sw) * f.sh);
    parallelFor(0, f.sh, 16, [&](int64_t sy) {
        for (int sx = 0; sx < f.sw; ++sx) {
            const SurfacePoint& q = plan.surfaces[static_cast<size_t>(sy) * f.stride * f.width +
                                                  static_cast<size_t>(sx) * f.stride];
            samples[static_cast<size_t>(sy) * f.sw + sx] = filterSampleOf(q);
        }
    });
    plan.stride = f.stride;
    plan.weights.resize(pixels);
    plan.weighted.assign(samples.size(), 1);
    // By row of cells: a cell's pixels' weights and then its flag, in one pass.
    parallelFor(0, f.sh, 1, [&](int64_t sy) {
        uint8_t* weighted = &plan.weighted[static_cast<size_t>(sy) * f.sw];
        for (int y = static_cast<int>(sy) * f.stride; y < std::min((sy + 1) * f.stride, int64_t{f.height});
             ++y)
            for (int sx = 0; sx < f.sw; ++sx) {
                const CellSamples cell = cellSamples(f, samples, sx, static_cast<int>(sy));
                for (int x = sx * f.stride; x < std::min((sx + 1) * f.stride, f.width); ++x) {
                    const size_t i = static_cast<size_t>(y) * f.width + x;
                    const SurfacePoint& p = plan.surfaces[i];
                    // {-1, 0, 0, 0}: no surface.
                    const std::array<float, 4> w =
                        p.valid()
                            ? interpolationWeights(f, cell, x, y, cellNeighbourWeights(f, cell, x, y, p))
                            : std::array<float, 4>{-1.0f, 0.0f, 0.0f, 0.0f};
                    plan.weights[i] = w;
                    if (!(w[0] > 0.0f || w[1] > 0.0f || w[2] > 0.0f || w[3] > 0.0f)) weighted[sx] = 0;
                }
            }
    });
}

// The pass's plan, if it has one it can use (built by then: denoiseInto).
InterpolationPlan* usablePlan(const FilterPass& f) {
    const bool interpolate = f.interpolates();
    return interpolate && f.s.plan && f.s.plan->surfaces.size() == f.points.size() ? f.s.plan : nullptr;
}

// The pixels [x0, x1) of row y without a plan: each filtered over its window, or (settings.interpolate)
// interpolated from the filtered samples around them, cell by cell. The holes are appended to `holes`.
template <int C>
[[gnu::noinline]] void filterRowWithoutPlan(const FilterPass& f, std::span<const float> filtered,
                                            std::span<const uint8_t> filteredNonZero, int y, int x0, int x1,
                                            std::span<float> out, std::vector<size_t>& holes) {
    const int channels = C > 0 ? C : f.channels;
    const bool interpolate = f.interpolates();
    const int sy = y / f.stride;
    int sx = 0, cellEnd = x0;  // the cell column of the pixels before cellEnd
    size_t k00 = 0;
    // Whether the filtered values around the cell are all zero, and its samples, loaded once for its pixels
    // that need their weights (where its values are all zero, only those off its first sample's surface).
    bool cellNonZero = false;
    std::optional<CellSamples> cell;
    for (int x = x0; x < x1; ++x) {
        if (interpolate && x >= cellEnd) {  // a new cell
            sx = x / f.stride;
            cellEnd = (sx + 1) * f.stride;
            k00 = f.sampleIndex(sx, sy);
            cellNonZero = cellHasValue(f, filteredNonZero, sx, sy);
            cell.reset();
        }
        const size_t i = static_cast<size_t>(y) * f.width + x;
        if (!f.s.filtered.empty() && !f.s.filtered[i]) continue;
        const SurfacePoint& p = f.points[i];
        if (!p.valid()) continue;
        bool ok;
        if (interpolate) {
            // The filtered samples around it all zero and the first on its surface: zero, as interpolatePixel
            // would give it (most of a shadow's change), without its weights.
            if (!cellNonZero && firstSampleWeight(f, p, x, y, sx, sy, k00) > 0.0f) {
                std::fill_n(&out[i * channels], channels, 0.0f);
                continue;
            }
            if (!cell) cell = cellSamples(f, f.samples, sx, sy);
            ok = interpolatePixel<C>(
                f, filtered, filteredNonZero, x, y, k00, &p,
                interpolationWeights(f, *cell, x, y, cellNeighbourWeights(f, *cell, x, y, p)),
                &out[i * channels]);
        } else {
            ok = filterPixel<C>(f, x, y, p, &out[i * channels]);
        }
        if (!ok) holes.push_back(i);
    }
}

#if DELTAGI_FILTER_LANES
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
bool filterLanesAvailable() {
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
LaneSamples laneSamples(const FilterPass& f, int channels) {
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
void addFiltered(LaneSamples& s, const FilterPass& f, std::span<const float> filtered,
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
        alignas(32) int32_t active[kLanes];
        std::memcpy(active, &on, sizeof(on));
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
                if (active[l]) std::fill_n(&out[(static_cast<size_t>(y) * f.width + x + l) * C], C, 0.0f);
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
        alignas(32) int32_t zero[kLanes], fallback[kLanes];
        const IntL zeroL = zeroCell, fallbackL = ~zeroCell & ~any;
        std::memcpy(zero, &zeroL, sizeof(zeroL));
        std::memcpy(fallback, &fallbackL, sizeof(fallbackL));
        for (int l = 0; l < kLanes; ++l) {
            if (!active[l]) continue;
            const size_t i = static_cast<size_t>(y) * f.width + x + l;
            float* dst = &out[i * C];
            if (zero[l]) {
                std::fill_n(dst, C, 0.0f);
            } else if (fallback[l]) {
                if (!filterPixel<C>(f, x + l, y, f.points[i], dst)) holes.push_back(i);
            } else {
                for (int c = 0; c < C; ++c) dst[c] = sums[c][l];
            }
        }
    }
}
#endif

// The whole pass for C channels: every pixel filtered, or (settings.interpolate) the samples filtered and the
// pixels between interpolated from them.
template <int C>
void filterImage(const FilterPass& f, const PixelRect& rect, std::span<float> out,
                 std::vector<std::vector<size_t>>& rowHoles) {
    const int channels = C > 0 ? C : f.channels;
    std::vector<float> filtered;
    std::vector<uint8_t> filteredNonZero;
    const bool interpolate = f.interpolates();
    // The samples in planes for the filter in lanes, where the CPU has them and enough windows hold values:
    // where nearly all are zeros (a relit shadow's change) the one-pixel code's early outs cost less than the
    // planes.
#if DELTAGI_FILTER_LANES
    std::optional<LaneSamples> lanes;
    if constexpr (C > 0)
        if (f.s.lanes && filterLanesAvailable() &&
            static_cast<size_t>(std::count(f.windowHasValue.begin(), f.windowHasValue.end(), 1)) *
                    kLaneWindowsShare >=
                f.windowHasValue.size())
            lanes.emplace(laneSamples(f, channels));
#endif
    if (interpolate) {
        filtered.assign(f.samples.size() * channels, 0.0f);
        filteredNonZero.assign(f.samples.size(), 0);
        // Samples at valid points, which lie inside the rectangle.
        const int sx0 = (rect.x0 + f.stride - 1) / f.stride, sx1 = (rect.x1 + f.stride - 1) / f.stride;
        const int sy0 = (rect.y0 + f.stride - 1) / f.stride, sy1 = (rect.y1 + f.stride - 1) / f.stride;
        parallelFor(sy0, sy1, 4, [&](int64_t sy) {
#if DELTAGI_FILTER_LANES
            if constexpr (C > 0)
                if (lanes) {
                    filterSamplesInLanes<C>(f, *lanes, static_cast<int>(sy), sx0, sx1, filtered);
                    for (int sx = sx0; sx < sx1; ++sx) {
                        const size_t k = f.sampleIndex(sx, static_cast<int>(sy));
                        const float* v = &filtered[k * channels];
                        filteredNonZero[k] = std::any_of(v, v + channels, [](float c) { return c != 0.0f; });
                    }
                    return;
                }
#endif
            for (int sx = sx0; sx < sx1; ++sx) {
                const size_t k = f.sampleIndex(sx, static_cast<int>(sy));
                if (!f.samples[k].valid) continue;
                const size_t i =
                    static_cast<size_t>(sy) * f.stride * f.width + static_cast<size_t>(sx) * f.stride;
                float* v = &filtered[k * channels];
                filterPixel<C>(f, sx * f.stride, static_cast<int>(sy) * f.stride, f.points[i], v);
                filteredNonZero[k] = std::any_of(v, v + channels, [](float c) { return c != 0.0f; });
            }
        });
    }
    InterpolationPlan* plan = usablePlan(f);
    // The pixels without a plan in lanes, where the CPU has them.
    auto rowWithoutPlan = [&](int y, int x0, int x1) {
        filterRowWithoutPlan<C>(f, filtered, filteredNonZero, y, x0, x1, out, rowHoles[y]);
    };
#if DELTAGI_FILTER_LANES
    if (lanes && interpolate) addFiltered(*lanes, f, filtered, filteredNonZero, channels);
    auto rowInLanes = [&](int y, int x0, int x1) {
        if constexpr (C > 0) {
            if (lanes && interpolate) return interpolateRowInLanes<C>(f, *lanes, y, x0, x1, out, rowHoles[y]);
            if (lanes) return filterRowInLanes<C>(f, *lanes, y, x0, x1, out, rowHoles[y]);
        }
        rowWithoutPlan(y, x0, x1);
    };
#else
    auto rowInLanes = rowWithoutPlan;
#endif
    // With a plan: the pixels whose points, or the samples around them, may differ from the plan's surfaces.
    const PixelRect changed = f.s.planChanged;
    const int stride = f.stride;
    const bool zeroCells = plan && f.s.filtered.empty() && plan->weighted.size() == f.samples.size();
    parallelFor(rect.y0, rect.y1, 4, [&](int64_t y64) {
        const int y = static_cast<int>(y64);
        // The pixels from planStart to a given one (of whole cells) interpolated with the plan's weights.
        int planStart = -1;
        auto planPixels = [&](int y, int end) {
            if (planStart < 0) return;
            const int x0 = std::exchange(planStart, -1);
#if DELTAGI_FILTER_LANES
            if constexpr (C > 0)
                if (lanes) return planRowInLanes<C>(f, *lanes, *plan, y, x0, end, out, rowHoles[y]);
#endif
            for (int x = x0; x < end; ++x) {
                const size_t i = static_cast<size_t>(y) * f.width + x;
                if (!f.s.filtered.empty() && !f.s.filtered[i]) continue;
                const std::array<float, 4>& w = plan->weights[i];
                if (w[0] < 0.0f) continue;  // no surface
                if (!interpolatePixel<C>(f, filtered, filteredNonZero, x, y,
                                         f.sampleIndex(x / stride, y / stride), nullptr, w,
                                         &out[i * channels]))
                    rowHoles[y].push_back(i);
            }
        };
        // Pixels by cell of samples, [cx, cx + stride] x [cy, cy + stride]: with a plan, those whose cell
        // misses `changed` read it.
        const int sy = y / stride, cy = sy * stride;
        const bool rowMisses = changed.empty() || cy + stride < changed.y0 || cy >= changed.y1;
        if (!plan) {
            rowInLanes(y, rect.x0, rect.x1);
            return;
        }
        for (int x = rect.x0; x < rect.x1;) {
            const int sx = x / stride, cx = sx * stride, cellEnd = std::min(cx + stride, rect.x1);
            const bool cellPlan = rowMisses || cx + stride < changed.x0 || cx >= changed.x1;
            const size_t k00 = f.sampleIndex(sx, sy);
            if (!cellPlan) {  // its points may differ from the plan's surfaces
                planPixels(y, x);
                rowInLanes(y, x, cellEnd);
                x = cellEnd;
                continue;
            }
            if (zeroCells && plan->weighted[k00]) {
                // Every pixel of the cell weighs some of its samples: where all of them are zero, so is every
                // pixel (as interpolatePixel would give it), without reading their weights.
                if (!cellHasValue(f, filteredNonZero, sx, sy)) {
                    planPixels(y, x);
                    std::fill(out.begin() + (static_cast<ptrdiff_t>(y) * f.width + x) * channels,
                              out.begin() + (static_cast<ptrdiff_t>(y) * f.width + cellEnd) * channels, 0.0f);
                    x = cellEnd;
                    continue;
                }
            }
            if (planStart < 0) planStart = x;  // interpolated with the plan's weights with the cells after it
            x = cellEnd;
        }
        planPixels(y, rect.x1);
    });
}

}  // namespace

bool denoiseLanesAvailable() {
#if DELTAGI_FILTER_LANES
    return filterLanesAvailable();
#else
    return false;
#endif
}

float surfaceWeight(const SurfacePoint& p, const SurfacePoint& q, glm::vec2 offset, glm::vec3 eye,
                    float pixelAngle, const DenoiseSettings& settings) {
    if (!p.valid() || !q.valid()) return 0.0f;
    // The filter's allowance (its planeAllowance times offsetLength).
    const float allowance = settings.planeDistance * pixelAngle * glm::length(p.position - eye) *
                            std::sqrt(offset.x * offset.x + offset.y * offset.y + 1.0f);
    return sameSurfaceWeight(p, q.position, q.normal, allowance, settings.normalPower);
}

std::vector<uint32_t> blendHolesFromGrid(std::span<float> values, int channels,
                                         std::span<const SurfacePoint> points, int width, int height,
                                         glm::vec3 eye, float pixelAngle, const DenoiseSettings& settings,
                                         int step, std::span<const size_t> holes,
                                         std::span<const uint8_t> traced) {
    // Each hole writes only its own values and reads only traced ones: in parallel.
    std::vector<uint8_t> blended(holes.size(), 0);
    parallelFor(0, static_cast<int64_t>(holes.size()), 256, [&](int64_t h) {
        const size_t i = holes[h];
        if (traced[i]) return;
        const int x = static_cast<int>(i % width), y = static_cast<int>(i / width);
        const int cx = x / step * step, cy = y / step * step;
        const float fx = static_cast<float>(x - cx) / static_cast<float>(step);
        const float fy = static_cast<float>(y - cy) / static_cast<float>(step);
        std::array<float, 4> weights{};
        std::array<size_t, 4> corners{};
        float sum = 0.0f;
        for (int n = 0; n < 4; ++n) {
            const int qx = cx + (n & 1) * step, qy = cy + (n >> 1) * step;
            if (qx >= width || qy >= height) continue;
            const size_t q = static_cast<size_t>(qy) * width + qx;
            if (!traced[q]) continue;
            weights[n] =
                surfaceWeight(points[i], points[q], glm::vec2(qx - x, qy - y), eye, pixelAngle, settings) *
                ((n & 1) ? fx : 1.0f - fx) * ((n >> 1) ? fy : 1.0f - fy);
            corners[n] = q;
            sum += weights[n];
        }
        if (!(sum > 0.0f)) return;
        float* out = &values[i * channels];
        std::fill_n(out, channels, 0.0f);
        for (int n = 0; n < 4; ++n) {
            if (weights[n] == 0.0f) continue;
            const float* v = &values[corners[n] * channels];
            for (int c = 0; c < channels; ++c) out[c] += v[c] * (weights[n] / sum);
        }
        blended[h] = 1;
    });
    std::vector<uint32_t> rest;
    for (size_t h = 0; h < holes.size(); ++h)
        if (!traced[holes[h]] && !blended[h]) rest.push_back(static_cast<uint32_t>(holes[h]));
    return rest;
}

std::vector<float> denoise(std::span<const float> values, int channels, std::span<const SurfacePoint> points,
                           int width, int height, glm::vec3 eye, float pixelAngle, const DenoiseSettings& s,
                           std::vector<size_t>* holes) {
    std::vector<float> out(values.begin(), values.end());
    denoiseInto(out, channels, points, width, height, eye, pixelAngle, s, holes);
    return out;
}

void denoiseInto(std::span<float> values, int channels, std::span<const SurfacePoint> points, int width,
                 int height, glm::vec3 eye, float pixelAngle, const DenoiseSettings& s,
                 std::vector<size_t>* holes, const PixelRect* bounds) {
    if (s.radius <= 0 || channels <= 0) return;
    const PixelRect rect = bounds ? *bounds : PixelRect{0, 0, width, height};
    if (rect.empty()) return;
    const int r = s.radius, stride = std::max(s.stride, 1);
    const int reach = (r + 1) * stride;
    // Only samples inside the rectangle can be valid.
    const int sx0 = (rect.x0 + stride - 1) / stride, sx1 = (rect.x1 + stride - 1) / stride;
    const int sy0 = (rect.y0 + stride - 1) / stride, sy1 = (rect.y1 + stride - 1) / stride;
    const int fullSw = (width + stride - 1) / stride, fullSh = (height + stride - 1) / stride;
    const bool wholeGrid = s.plan != nullptr;
    const int ox = wholeGrid ? 0 : std::max(sx0 - 1, 0), oy = wholeGrid ? 0 : std::max(sy0 - 1, 0);
    const int ex = wholeGrid ? fullSw : std::min(sx1 + 1, fullSw),
              ey = wholeGrid ? fullSh : std::min(sy1 + 1, fullSh);
    FilterPass f{values, channels, points, width,         height, eye, pixelAngle, s,
                 r,      stride,   reach,  2 * reach + 1, ox,     oy,  ex - ox,    ey - oy};
    const int window = 2 * r + 1;
    std::vector<float> spatial1d(window);
    for (int d = -r; d <= r; ++d)
        spatial1d[d + r] = std::exp(-0.5f * d * d / (s.spatialSigma * s.spatialSigma));
    f.spatial.resize(static_cast<size_t>(window) * window);
    for (int dy = 0; dy < window; ++dy)
        for (int dx = 0; dx < window; ++dx) f.spatial[dy * window + dx] = spatial1d[dy] * spatial1d[dx];
    f.offsetLength.resize(static_cast<size_t>(f.side) * f.side);
    for (int py = -reach; py <= reach; ++py)
        for (int px = -reach; px <= reach; ++px)
            f.offsetLength[static_cast<size_t>(py + reach) * f.side + px + reach] =
                std::sqrt(static_cast<float>(px * px + py * py + 1));
    f.fraction.resize(stride);
    for (int d = 0; d < stride; ++d) f.fraction[d] = static_cast<float>(d) / static_cast<float>(stride);

    const int sw = f.sw, sh = f.sh;
    // With a plan over the whole image the samples are the plan's (its surfaces' at every stride-th pixel),
    // but in planChanged, the only pixels whose points may differ from its surfaces.
    InterpolationPlan* plan = usablePlan(f);
    if (plan) buildPlan(f, *plan);
    const bool planSamples = plan && s.traced.empty() && rect.x0 == 0 && rect.y0 == 0 && rect.x1 == width &&
                             rect.y1 == height && plan->samples.size() == static_cast<size_t>(sw) * sh;
    const PixelRect& changed = s.planChanged;
    auto sampleOfPoint = [&](int sx, int sy) {
        const size_t j = static_cast<size_t>(sy) * stride * width + static_cast<size_t>(sx) * stride;
        return filterSampleOf(points[j], s.traced.empty() || s.traced[j] != 0);
    };
    if (planSamples) {
        f.samples = plan->samples;
        if (!changed.empty())
            parallelFor(std::max((changed.y0 + stride - 1) / stride, 0),
                        std::min((changed.y1 + stride - 1) / stride, sh), 16, [&](int64_t sy) {
                            for (int sx = std::max((changed.x0 + stride - 1) / stride, 0);
                                 sx < std::min((changed.x1 + stride - 1) / stride, sw); ++sx)
                                f.samples[f.sampleIndex(sx, static_cast<int>(sy))] =
                                    sampleOfPoint(sx, static_cast<int>(sy));
                        });
    } else {
        f.samples.resize(static_cast<size_t>(sw) * sh);
    }
    f.sampleValues.resize(f.samples.size() * channels);
    std::vector<uint8_t> nonZero(f.samples.size());
    // The samples outside the rectangle stay invalid.
    parallelFor(sy0, sy1, 16, [&](int64_t sy) {
        for (int sx = sx0; sx < sx1; ++sx) {
            const size_t j = static_cast<size_t>(sy) * stride * width + static_cast<size_t>(sx) * stride;
            const size_t k = f.sampleIndex(sx, static_cast<int>(sy));
            if (!planSamples) f.samples[k] = sampleOfPoint(sx, static_cast<int>(sy));
            const float* v = &values[j * channels];
            std::copy_n(v, channels, &f.sampleValues[k * channels]);
            nonZero[k] =
                f.samples[k].valid && std::any_of(v, v + channels, [](float c) { return c != 0.0f; });
        }
    });
    // Dilate the non-zero samples by the window (rows, then columns) onto the window centres, with running
    // counts: a centre's window holds a value when the count over its span is not zero.
    std::vector<uint8_t> rows(static_cast<size_t>(sw + 1) * sh);
    parallelFor(0, sh, 16, [&](int64_t sy) {
        std::vector<uint32_t> prefix(sw + 1, 0);
        const uint8_t* row = &nonZero[static_cast<size_t>(sy) * sw];
        for (int sx = 0; sx < sw; ++sx) prefix[sx + 1] = prefix[sx] + row[sx];
        for (int cx = 0; cx <= sw; ++cx)
            rows[static_cast<size_t>(sy) * (sw + 1) + cx] =
                prefix[std::min(cx + r, sw - 1) + 1] != prefix[std::max(cx - r, 0)];
    });
    f.windowHasValue.assign(static_cast<size_t>(sw + 1) * (sh + 1), 0);
    parallelFor(0, sw + 1, 16, [&](int64_t cx) {
        std::vector<uint32_t> prefix(sh + 1, 0);
        for (int sy = 0; sy < sh; ++sy)
            prefix[sy + 1] = prefix[sy] + rows[static_cast<size_t>(sy) * (sw + 1) + cx];
        for (int cy = 0; cy <= sh; ++cy)
            f.windowHasValue[static_cast<size_t>(cy) * (sw + 1) + cx] =
                prefix[std::min(cy + r, sh - 1) + 1] != prefix[std::max(cy - r, 0)];
    });

    std::vector<std::vector<size_t>> rowHoles(height);
    switch (channels) {
        case 1:
            filterImage<1>(f, rect, values, rowHoles);
            break;
        case 3:
            filterImage<3>(f, rect, values, rowHoles);
            break;
        case 6:
            filterImage<6>(f, rect, values, rowHoles);
            break;
        default:
            filterImage<0>(f, rect, values, rowHoles);
            break;
    }
    if (holes)
        for (const std::vector<size_t>& row : rowHoles) holes->insert(holes->end(), row.begin(), row.end());
}

}  // namespace deltagi
