#include "pipeline/denoise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <optional>
#include <utility>

#include "core/parallel.h"

// The filter in AVX2 lanes (denoise_lanes.h), built with GCC for x86-64. Its 8-float helpers, and powInt for
// them, are always inlined into its kernels: the note that 32-byte vectors are passed differently with AVX
// than without does not apply.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DELTAGI_FILTER_LANES 1
#pragma GCC diagnostic ignored "-Wpsabi"
#include "pipeline/denoise_lanes.h"
#endif
#include "pipeline/denoise_pass.h"

namespace deltagi {

namespace {

using namespace denoise_pass;

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
