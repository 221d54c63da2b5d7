// Sparse passes of stage 6 (cone_jobs.cpp): a pass's cones or rays traced at every stride-th pixel of every
// stride-th row, the pixels between filled by the edge-aware filter (denoise.h), its holes traced, and the
// cells where the samples change sharply traced again more finely (refineSparse).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "core/parallel.h"
#include "pipeline/denoise.h"
#include "pipeline/gbuffer.h"

namespace deltagi {

// Where a sparse pass is traced again more finely (refineSparse): its cells whose corners' filtered values
// differ by more than kRefineThreshold of the pass's largest value, at the stride divided by kRefineDivisor,
// the sharpest first, as many cells as `budget` times the image's pixels holds fine samples (0: never); the
// margin the fine filter reads around them adds up to three times as many again for a lone cell.
//
// On the quality suite (options.render.refine_budget 0.01 against 0, the relit passes of the environment's
// and the objects' light): the field photo's delta_rel_error 0.347 -> 0.239 (the bunny's contact shadow from
// the sky and its glow on the grass: the shadow part 0.245 -> 0.172, the indirect part 0.281 -> 0.191), the
// bare bulb's 0.155 -> 0.143 and its camera path's 0.133-0.166 -> 0.132-0.149, the concave head's 0.191 ->
// 0.187; the glossy box's 0.156 -> 0.163 (the fine samples' noise), the others within 0.001. Half the stride
// gave the field 0.264, a quarter of the stride with a quarter of the rays 0.293 (their noise), the fine
// samples filtered over 3 x 3 instead of 5 x 5 0.245; the raw samples instead of the filtered ones as the
// test: the big boxes 0.001-0.002 better, the camera path 0.004-0.013 worse. Without the feathering the fine
// result's edge showed as steps of cells in the field's contact shadow (at 16 times the change), for 0.002
// of its figure.
struct SparseRefinement {
    float budget = 0.0f;
};
inline constexpr int kRefineDivisor = 4;
inline constexpr float kRefineThreshold = 0.1f;
// The fine samples' filter: 5 x 5 of them (their stride is a quarter of the pass's, their noise the same).
inline constexpr int kRefineFilterRadius = 2;

// A sparse pass's cells (the squares between four samples of its stride) where its filtered values change
// sharply, traced again at a finer stride and filtered at it: what the interpolation between the stride's
// samples blurs (a contact shadow's core, the objects' glow at their feet). A cell counts when its corners'
// values (each channel's) differ by more than kRefineThreshold of the pass's largest, or when some of its
// corners hold no surface (an object's silhouette) and the others such a value. The fine samples around the
// marked cells that the fine filter's window reaches are traced too; the marked cells' pixels take the fine
// result, feathered into the coarse one over half a cell inside the marked region's edge (the fine filter's
// holes keep the coarse one).
template <typename T, typename Trace>
void refineSparse(std::vector<T>& values, std::span<const SurfacePoint> points, const PixelRect& bounds,
                  const Camera& camera, int stride, int perPixel, const DenoiseSettings& fill,
                  const SparseRefinement& refine, Trace&& trace) {
    if (!(refine.budget > 0.0f) || stride <= 1) return;
    const int fine = std::max(stride / kRefineDivisor, 1);
    const int channels = perPixel * static_cast<int>(sizeof(T) / sizeof(float));
    const int width = camera.width, height = camera.height;
    const float* v = reinterpret_cast<const float*>(values.data());
    // Samples (sx, sy) at pixel (sx * stride, sy * stride); cells (cx, cy) between samples cx..cx+1,
    // cy..cy+1.
    const int sw = (width + stride - 1) / stride, sh = (height + stride - 1) / stride;
    const int cx0 = bounds.x0 / stride, cy0 = bounds.y0 / stride;
    const int cx1 = std::min((bounds.x1 + stride - 1) / stride, sw),
              cy1 = std::min((bounds.y1 + stride - 1) / stride, sh);
    auto sampleIndex = [&](int sx, int sy) {
        return static_cast<size_t>(sy) * stride * width + static_cast<size_t>(sx) * stride;
    };
    std::vector<float> scale(static_cast<size_t>(channels), 0.0f);
    for (int sy = cy0; sy < cy1; ++sy)
        for (int sx = cx0; sx < cx1; ++sx) {
            const size_t i = sampleIndex(sx, sy);
            if (!points[i].valid()) continue;
            for (int c = 0; c < channels; ++c) scale[c] = std::max(scale[c], std::abs(v[i * channels + c]));
        }
    const int cw = cx1 - cx0, chh = cy1 - cy0;
    if (cw <= 0 || chh <= 0) return;
    // Each cell's sharpness: its corners' largest difference (or, at a silhouette, value) relative to the
    // pass's largest value, over the channels; a cell is refined above the threshold.
    std::vector<float> sharpness(static_cast<size_t>(cw) * chh, 0.0f);
    parallelFor(0, chh, 8, [&](int64_t row) {
        const int cy = cy0 + static_cast<int>(row);
        for (int cx = cx0; cx < cx1; ++cx) {
            size_t corners[4];
            int count = 0, present = 0;
            for (int k = 0; k < 4; ++k) {
                const int sx = cx + (k & 1), sy = cy + (k >> 1);
                if (sx >= sw || sy >= sh) continue;
                ++present;
                const size_t i = sampleIndex(sx, sy);
                if (points[i].valid()) corners[count++] = i;
            }
            if (count == 0) continue;
            float sharpest = 0.0f;
            for (int c = 0; c < channels; ++c) {
                if (!(scale[c] > 0.0f)) continue;
                float lo = v[corners[0] * channels + c], hi = lo, largest = std::abs(lo);
                for (int k = 1; k < count; ++k) {
                    const float x = v[corners[k] * channels + c];
                    lo = std::min(lo, x), hi = std::max(hi, x), largest = std::max(largest, std::abs(x));
                }
                sharpest =
                    std::max(sharpest, (count < present ? std::max(hi - lo, largest) : hi - lo) / scale[c]);
            }
            sharpness[static_cast<size_t>(row) * cw + (cx - cx0)] = sharpest;
        }
    });
    // The sharpest cells first, within the budget of fine samples.
    std::vector<uint32_t> order;
    for (uint32_t k = 0; k < sharpness.size(); ++k)
        if (sharpness[k] > kRefineThreshold) order.push_back(k);
    if (order.empty()) return;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return sharpness[a] != sharpness[b] ? sharpness[a] > sharpness[b] : a < b;
    });
    const size_t perCell = static_cast<size_t>(stride / fine) * static_cast<size_t>(stride / fine);
    const size_t cells = std::max<size_t>(
        1, static_cast<size_t>(refine.budget * static_cast<float>(width) * static_cast<float>(height)) /
               perCell);
    order.resize(std::min(order.size(), cells));
    std::vector<uint8_t> marked(sharpness.size(), 0);
    for (uint32_t k : order) marked[k] = 1;
    // The fine samples in the marked cells, and those around them that the fine filter's window reaches.
    const int margin = kRefineFilterRadius * fine;
    auto markedAt = [&](int x, int y) {
        const int cx = std::clamp(x, bounds.x0, bounds.x1 - 1) / stride - cx0,
                  cy = std::clamp(y, bounds.y0, bounds.y1 - 1) / stride - cy0;
        return cx >= 0 && cy >= 0 && cx < cw && cy < chh && marked[static_cast<size_t>(cy) * cw + cx] != 0;
    };
    PixelRect rect{width, height, 0, 0};
    for (int cy = 0; cy < chh; ++cy)
        for (int cx = 0; cx < cw; ++cx) {
            if (!marked[static_cast<size_t>(cy) * cw + cx]) continue;
            const int px = (cx0 + cx) * stride, py = (cy0 + cy) * stride;
            rect.x0 = std::min(rect.x0, px - margin), rect.y0 = std::min(rect.y0, py - margin);
            rect.x1 = std::max(rect.x1, px + stride + margin + 1);
            rect.y1 = std::max(rect.y1, py + stride + margin + 1);
        }
    rect.x0 = std::max(rect.x0, bounds.x0), rect.y0 = std::max(rect.y0, bounds.y0);
    rect.x1 = std::min(rect.x1, bounds.x1), rect.y1 = std::min(rect.y1, bounds.y1);
    std::vector<uint8_t> traced(static_cast<size_t>(width) * height, 0);
    std::vector<uint32_t> pixels;
    for (int y = (rect.y0 + fine - 1) / fine * fine; y < rect.y1; y += fine)
        for (int x = (rect.x0 + fine - 1) / fine * fine; x < rect.x1; x += fine) {
            const size_t i = static_cast<size_t>(y) * width + x;
            if (!points[i].valid()) continue;
            if (!(markedAt(x, y) || markedAt(x - margin, y - margin) || markedAt(x + margin, y - margin) ||
                  markedAt(x - margin, y + margin) || markedAt(x + margin, y + margin)))
                continue;
            pixels.push_back(static_cast<uint32_t>(i));
            traced[i] = 1;
        }
    if (pixels.empty()) return;
    std::vector<T> fineValues = trace(std::span<const uint32_t>(pixels));
    // The marked cells' pixels, which take the fine result.
    std::vector<uint8_t> wanted(traced.size(), 0);
    parallelFor(rect.y0, rect.y1, 4, [&](int64_t y) {
        for (int x = rect.x0; x < rect.x1; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            wanted[i] = points[i].valid() && markedAt(x, static_cast<int>(y));
        }
    });
    DenoiseSettings fineFill = fill;
    fineFill.stride = fine;
    fineFill.radius = kRefineFilterRadius;
    fineFill.plan = nullptr;
    fineFill.traced = traced;
    fineFill.filtered = wanted;
    std::vector<size_t> holes;
    denoiseInPlace(fineValues, perPixel, points, camera, fineFill, &holes, &rect);
    for (size_t i : holes) traced[i] = 2;  // not filled: keeps the coarse value
    // The fine result feathered into the coarse one over half a cell inside the marked cells' edge (where an
    // unmarked cell begins), so that no seam shows where the coarse interpolation takes over.
    const float feather = 0.5f * static_cast<float>(stride);
    auto shareOfFine = [&](int x, int y) {
        const int cx = x / stride, cy = y / stride;
        float nearest = feather;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int nx = cx + dx, ny = cy + dy;
                if ((dx == 0 && dy == 0) || nx < cx0 || ny < cy0 || nx >= cx1 || ny >= cy1 ||
                    marked[static_cast<size_t>(ny - cy0) * cw + (nx - cx0)])
                    continue;
                // Pixels from the unmarked cell's nearest pixel, along each axis.
                const int gapX = dx < 0 ? x - cx * stride + 1 : dx > 0 ? (cx + 1) * stride - x : 0;
                const int gapY = dy < 0 ? y - cy * stride + 1 : dy > 0 ? (cy + 1) * stride - y : 0;
                nearest = std::min(nearest, static_cast<float>(std::max(gapX, gapY)) - 0.5f);
            }
        return std::clamp(nearest / feather, 0.0f, 1.0f);
    };
    const int floatsPerPixel = channels;
    parallelFor(rect.y0, rect.y1, 4, [&](int64_t y) {
        for (int x = rect.x0; x < rect.x1; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            if (!wanted[i] || traced[i] == 2) continue;
            const float share = shareOfFine(x, static_cast<int>(y));
            float* to = reinterpret_cast<float*>(values.data()) + i * floatsPerPixel;
            const float* from = reinterpret_cast<const float*>(fineValues.data()) + i * floatsPerPixel;
            for (int c = 0; c < floatsPerPixel; ++c) to[c] += share * (from[c] - to[c]);
        }
    });
}

// The valid points' pixels at every stride-th pixel of every stride-th row of `bounds` (which holds all valid
// points), for a trace. An empty list would mean every pixel: where there is none, pixel 0 alone, a place
// that is then invalid (inside `bounds` it would be listed, outside it no point is valid).
inline std::vector<uint32_t> validPixels(std::span<const SurfacePoint> points, const PixelRect& bounds,
                                         int width, int stride) {
    std::vector<uint32_t> pixels;
    for (int y = (bounds.y0 + stride - 1) / stride * stride; y < bounds.y1; y += stride)
        for (int x = (bounds.x0 + stride - 1) / stride * stride; x < bounds.x1; x += stride) {
            const size_t i = static_cast<size_t>(y) * width + x;
            if (points[i].valid()) pixels.push_back(static_cast<uint32_t>(i));
        }
    if (pixels.empty()) pixels.push_back(0);
    return pixels;
}

// How far around the pixels that may hold values other than zero a sparse pass (traceSparse) at `stride`
// with `filter` must run to give them, and every other pixel, the same result as over the whole image: twice
// what the filter reads around a pixel (its window of samples and the cell between them), and a stride. The
// pixels between that margin's inner part and the image's edge read only samples of zero and take zero, or
// are holes whose trace gives zero, with or without the pixels beyond.
inline int sparsePassMargin(int stride, const DenoiseSettings& filter) {
    const int reach = (std::max(filter.radius, 1) + 1) * stride;
    return 2 * reach + stride;
}

// Cone results `trace(pixels)` (perPixel values of T per pixel of `points`, for the listed pixels) at every
// stride-th pixel of every stride-th row, then filtered: the edge-aware filter interpolates the pixels
// between from traced neighbours on the same surface (averaging the noise of the jittered cone starts too),
// and the pixels that have none are traced as well, or blended from a finer grid of them (fillHoles). With
// stride 1 every pixel is traced and filtered.
// `bounds` holds all valid points.
template <typename T, typename Trace>
std::vector<T> traceSparse(std::span<const SurfacePoint> points, const PixelRect& bounds,
                           const Camera& camera, int stride, int perPixel, const DenoiseSettings& filter,
                           Trace&& trace, const SparseRefinement& refine = {}) {
    if (stride <= 1) {
        // Where `bounds` is less than the image (the objects' pixels), its pixels are listed, so that the
        // pass does not visit every point of the image to find the valid ones; else the empty list: all.
        const std::vector<uint32_t> listed =
            static_cast<size_t>(bounds.x1 - bounds.x0) * (bounds.y1 - bounds.y0) < points.size()
                ? validPixels(points, bounds, camera.width, 1)
                : std::vector<uint32_t>{};
        std::vector<T> values = trace(std::span<const uint32_t>(listed));
        denoiseInPlace(values, perPixel, points, camera, filter, nullptr, &bounds);
        return values;
    }
    const std::vector<uint32_t> samples = validPixels(points, bounds, camera.width, stride);
    std::vector<T> values = trace(std::span<const uint32_t>(samples));
    // The same number of samples as the filter at stride 1 (at least the 3x3 around each pixel), spaced out.
    DenoiseSettings fill = filter;
    fill.radius = std::max(filter.radius, 1);
    fill.stride = stride;
    std::vector<size_t> holes;
    denoiseInPlace(values, perPixel, points, camera, fill, &holes, &bounds);
    fillHoles(values, perPixel, points, camera, fill, holes, trace);
    refineSparse(values, points, bounds, camera, stride, perPixel, fill, refine, trace);
    return values;
}

}  // namespace deltagi
