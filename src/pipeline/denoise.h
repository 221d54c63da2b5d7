// An edge-aware (joint bilateral) filter over per-pixel cone results.
//
// Cones start their march at a random fraction of a step (options.trace.jitter) so that regular steps do not
// alias into bands; this filter averages that noise over a few neighbouring pixels of the same surface. It is
// guided by the G-buffer: a neighbour counts only if it lies near the pixel's tangent plane and shares its
// normal, so shadow and object edges stay sharp. It filters occlusion and gathered radiance, never the BRDF
// or the photo, so textures and highlights are untouched.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "deltagi/scene.h"
#include "pipeline/gbuffer.h"

namespace deltagi {

struct InterpolationPlan;

// A sample of the filter: the surface at one of the pixels that hold values (every stride-th pixel of every
// stride-th row).
struct FilterSample {
    glm::vec3 position, normal;
    bool valid;
};

struct DenoiseSettings {
    int radius = 2;             // samples: a (2r+1)^2 window of them; 0 disables the filter
    float spatialSigma = 1.5f;  // samples
    // Only the pixels with x and y multiples of `stride` hold values (1: all of them): the filter then
    // interpolates every valid pixel from its (2r+1)^2 nearest such samples, spaced `stride` pixels apart.
    int stride = 1;
    // With stride > 1: filter only the samples, and give each pixel between them the bilinear blend of the
    // (up to 4) filtered samples around it that lie on its surface (the full filter where none does). About
    // 6 times cheaper for a 5x5 window; smoother, so for slowly varying values (the real surfaces' change).
    bool interpolate = false;
    int normalPower = 16;        // weight dot(n_i, n_j)^power
    float planeDistance = 1.0f;  // how far a neighbour may lie off the tangent plane, in its pixel distances
    // With interpolate: the weights of each pixel between the samples, kept for surfaces that stay the same
    // from pass to pass (see InterpolationPlan); null: computed every time.
    InterpolationPlan* plan = nullptr;
    // The pixels whose points may differ from the plan's surfaces (made invalid): they, and the pixels whose
    // samples lie in it, are computed without the plan. Empty: none.
    PixelRect planChanged;
    // Per pixel of the image, whether it holds a value (a sparse pass that traced only some of the stride's
    // samples); the samples at the others are not used. Empty: every valid point's.
    std::span<const uint8_t> traced;
    // Per pixel of the image, whether to filter it (the others are left as they are). Empty: every one.
    std::span<const uint8_t> filtered;
    // With interpolate: the pixels between the samples eight at a time in vector lanes where the CPU has
    // AVX2 (the same bits); false: one at a time, the definition (tests compare the two).
    bool lanes = true;
};

// The interpolation weights (DenoiseSettings::interpolate) of every pixel of a fixed set of surfaces, such as
// the real scene's G-buffer, which does not change while only the objects move: a pass reads them instead of
// testing the samples around each pixel again. A pass whose points are these surfaces with some made invalid
// (the real surfaces the objects hide) uses a pixel's weights when the samples they weight are all still
// valid, and computes the pixel as without a plan otherwise: the result is the same bits either way.
struct InterpolationPlan {
    std::span<const SurfacePoint> surfaces;  // the fixed surfaces (must outlive the plan)
    // Built by the first pass that uses the plan, for its stride and settings:
    int stride = 0;
    // Per pixel, the normalized weights of the samples (sx, sy), (sx + 1, sy), (sx, sy + 1), (sx + 1, sy + 1)
    // with sx = x / stride, sy = y / stride; all zero: none of them lies on the pixel's surface.
    std::vector<std::array<float, 4>> weights;
    // The samples of `surfaces` at the stride, which a pass over the whole image copies instead of reading
    // them from its points again (but where its points may differ: DenoiseSettings::planChanged).
    std::vector<FilterSample> samples;
    // Per cell of samples (the pixels whose first sample is (sx, sy)): whether every one of its pixels has a
    // surface and weighs some sample.
    std::vector<uint8_t> weighted;
};

// Filters `values`, `channels` floats per pixel of `points` (width x height, row-major), returning the
// result. Invalid points keep their values and are never used as neighbours. `eye` is the camera position and
// `pixelAngle` the angle one pixel subtends (1 / fy), which together give a pixel's size on a surface.
// With settings.stride > 1, valid pixels without any usable sample in their window keep their value and are
// listed in `holes` (if given), in pixel order.
std::vector<float> denoise(std::span<const float> values, int channels, std::span<const SurfacePoint> points,
                           int width, int height, glm::vec3 eye, float pixelAngle,
                           const DenoiseSettings& settings, std::vector<size_t>* holes = nullptr);
// The same in place, where the valid points all lie inside `bounds` (nullptr: anywhere).
void denoiseInto(std::span<float> values, int channels, std::span<const SurfacePoint> points, int width,
                 int height, glm::vec3 eye, float pixelAngle, const DenoiseSettings& settings,
                 std::vector<size_t>* holes = nullptr, const PixelRect* bounds = nullptr);

// Whether DenoiseSettings::lanes runs in vector lanes on this CPU (it has AVX2 and the build has the kernel).
bool denoiseLanesAvailable();

// The filter's weight of q as a neighbour of p, q `offset` pixels away in the image (without the window's
// spatial factor): dot(normals)^settings.normalPower where q lies on p's side and within
// settings.planeDistance pixel sizes per pixel of offset of p's tangent plane; 0 on another surface.
float surfaceWeight(const SurfacePoint& p, const SurfacePoint& q, glm::vec2 offset, glm::vec3 eye,
                    float pixelAngle, const DenoiseSettings& settings);

// Sparse passes whose filter left holes (valid pixels without a usable sample, denoise's `holes`) trace
// them: at strides of 2 x kHoleStepDivisor and more only the holes on a finer grid, every step-th pixel of
// every step-th row (step = stride / kHoleStepDivisor), and the others take the blend of those at their
// step x step cell's corners that lie on their surface (bilinear weights times surfaceWeight, as the
// filter's interpolation between samples); a hole with none is traced itself. Holes gather on surfaces
// narrower than the stride (a box's side seen nearly edge on, a strip of floor under an object), where the
// light the finer grid misses varies no faster than it does between the stride's samples elsewhere.
inline constexpr int kHoleStepDivisor = 4;

// The blending of fillHoles: each of `holes` (indices of valid points, width x height) that is not
// `traced` blends the traced pixels at its cell's corners in `values` (`channels` floats per pixel). The
// holes it could not blend are returned, in the order given.
std::vector<uint32_t> blendHolesFromGrid(std::span<float> values, int channels,
                                         std::span<const SurfacePoint> points, int width, int height,
                                         glm::vec3 eye, float pixelAngle, const DenoiseSettings& settings,
                                         int step, std::span<const size_t> holes,
                                         std::span<const uint8_t> traced);

// fillHoles for the cone passes' results (as denoiseInPlace): `trace(pixels)` gives `perPixel` values of T
// per pixel of the image for the listed pixels; settings.stride is the pass's.
template <typename T, typename Trace>
void fillHoles(std::vector<T>& values, int perPixel, std::span<const SurfacePoint> points,
               const Camera& camera, const DenoiseSettings& settings, std::span<const size_t> holes,
               Trace&& trace) {
    if (holes.empty()) return;
    auto traceInto = [&](const std::vector<uint32_t>& pixels) {
        if (pixels.empty()) return;
        const std::vector<T> traced = trace(std::span<const uint32_t>(pixels));
        for (uint32_t i : pixels)
            std::copy_n(traced.begin() + static_cast<size_t>(i) * perPixel, perPixel,
                        values.begin() + static_cast<size_t>(i) * perPixel);
    };
    const int step = settings.stride / kHoleStepDivisor;
    if (step < 2) {
        traceInto(std::vector<uint32_t>(holes.begin(), holes.end()));
        return;
    }
    std::vector<uint32_t> coarse;
    std::vector<uint8_t> traced(points.size(), 0);
    for (size_t i : holes)
        if (static_cast<int>(i % camera.width) % step == 0 &&
            static_cast<int>(i / camera.width) % step == 0) {
            coarse.push_back(static_cast<uint32_t>(i));
            traced[i] = 1;
        }
    traceInto(coarse);
    const int channels = perPixel * static_cast<int>(sizeof(T) / sizeof(float));
    const std::span<float> flat(reinterpret_cast<float*>(values.data()),
                                values.size() * sizeof(T) / sizeof(float));
    traceInto(blendHolesFromGrid(flat, channels, points, camera.width, camera.height, camera.position(),
                                 1.0f / camera.fy, settings, step, holes, traced));
}

// In place, for the cone passes' per-pixel results: `perPixel` values of T (made of floats: glm::vec3,
// ShadowOcclusion) per pixel of the camera's image. Empty vectors are left alone.
template <typename T>
void denoiseInPlace(std::vector<T>& values, int perPixel, std::span<const SurfacePoint> points,
                    const Camera& camera, const DenoiseSettings& settings,
                    std::vector<size_t>* holes = nullptr, const PixelRect* bounds = nullptr) {
    static_assert(sizeof(T) % sizeof(float) == 0 && std::is_trivially_copyable_v<T> &&
                  std::is_standard_layout_v<T>);
    if (values.empty() || settings.radius <= 0) return;
    const int channels = perPixel * static_cast<int>(sizeof(T) / sizeof(float));
    const std::span<float> flat(reinterpret_cast<float*>(values.data()),
                                values.size() * sizeof(T) / sizeof(float));
    denoiseInto(flat, channels, points, camera.width, camera.height, camera.position(), 1.0f / camera.fy,
                settings, holes, bounds);
}

}  // namespace deltagi
