#include "pipeline/cone_jobs.h"

#include <algorithm>
#include <utility>

#include "core/parallel.h"
#include "pipeline/object_bounce_rays.h"
#include "pipeline/sky_light.h"

namespace deltagi {

// a += b, where an empty vector is zero.
void addInto(std::vector<glm::vec3>& a, std::vector<glm::vec3>&& b) {
    if (b.empty()) return;
    if (a.empty()) {
        a = std::move(b);
        return;
    }
    for (size_t i = 0; i < a.size(); ++i) a[i] += b[i];
}

namespace {

// Cone results `trace(pixels)` (perPixel values of T per pixel of `points`, for the listed pixels) at every
// stride-th pixel of every stride-th row, then filtered: the edge-aware filter interpolates the pixels
// between from traced neighbours on the same surface (averaging the noise of the jittered cone starts too),
// and the pixels that have none are traced as well. With stride 1 every pixel is traced and filtered.
// `bounds` holds all valid points.
template <typename T, typename Trace>
std::vector<T> traceSparse(std::span<const SurfacePoint> points, const PixelRect& bounds,
                           const Camera& camera, int stride, int perPixel, const DenoiseSettings& filter,
                           Trace&& trace) {
    if (stride <= 1) {
        std::vector<T> values = trace(std::span<const uint32_t>{});
        denoiseInPlace(values, perPixel, points, camera, filter, nullptr, &bounds);
        return values;
    }
    std::vector<uint32_t> samples;
    for (int y = (bounds.y0 + stride - 1) / stride * stride; y < bounds.y1; y += stride)
        for (int x = (bounds.x0 + stride - 1) / stride * stride; x < bounds.x1; x += stride) {
            const size_t i = static_cast<size_t>(y) * camera.width + x;
            if (points[i].valid()) samples.push_back(static_cast<uint32_t>(i));
        }
    // An empty list would mean every pixel. Pixel 0 is a sample position, so here it is invalid: nothing.
    if (samples.empty()) samples.push_back(0);
    std::vector<T> values = trace(std::span<const uint32_t>(samples));
    // The same number of samples as the filter at stride 1 (at least the 3x3 around each pixel), spaced out.
    DenoiseSettings fill = filter;
    fill.radius = std::max(filter.radius, 1);
    fill.stride = stride;
    std::vector<size_t> holes;
    denoiseInPlace(values, perPixel, points, camera, fill, &holes, &bounds);
    if (holes.empty()) return values;
    const std::vector<uint32_t> holePixels(holes.begin(), holes.end());
    const std::vector<T> filled = trace(std::span<const uint32_t>(holePixels));
    for (size_t i : holes)
        std::copy_n(filled.begin() + i * perPixel, perPixel, values.begin() + i * perPixel);
    return values;
}

// Runs body(j) for the jobs at once (the real surfaces' and the objects'): each job's own passes are
// parallel, but they end in small tails of work that leave a core idle; the other job fills them. The
// results do not depend on the order (each job writes only its own).
template <typename Body>
void forEachJob(size_t jobs, Body&& body) {
    parallelFor(0, static_cast<int64_t>(jobs), 1, [&](int64_t j) { body(static_cast<size_t>(j)); });
}

}  // namespace

// Stage 6 for every job: shadow, diffuse and specular cones, each timed as one stage over all jobs, then the
// sky light through the cones, with options `o` (the scene's, or the background's). Shadow and diffuse cones
// are traced at options.shadow/diffuse.pixel_stride (relight_pixel_stride for real surfaces relit) and
// filtered (traceSparse).
std::vector<ConeResults> traceCones(std::span<const ConeJob> jobs, const Scene& scene, const Options& o,
                                    std::span<const Light> directLights, StageTimer& timer) {
    const int lights = static_cast<int>(directLights.size());
    std::vector<ConeResults> results(jobs.size());
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        results[j].shadows = traceSparse<ShadowOcclusion>(
            job.points, job.bounds, scene.camera, job.shadowStride(o, scene.camera), lights,
            job.filter(o, job.shadowStride(o, scene.camera)), [&](std::span<const uint32_t> pixels) {
                if (o.shadow.method == ShadowMethod::Rays)
                    return traceShadowRays(job.points, directLights, job.rays, o, job.mode, pixels,
                                           job.pixelSamples, scene.camera.width);
                return traceShadowCones(job.points, directLights, job.visibility, o,
                                        job.mode == ShadowMode::DeltaShadow, pixels, job.sceneShadows);
            });
    });
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        if (!job.emitters || job.emitters->empty()) return;
        results[j].areaLight = traceSparse<glm::vec3>(
            job.points, job.bounds, scene.camera, job.areaLightStride(o, scene.camera), 1,
            job.filter(o, job.areaLightStride(o, scene.camera)), [&](std::span<const uint32_t> pixels) {
                return traceAreaLightRays(job.points, *job.emitters, job.rays, o, job.mode, pixels);
            });
    });
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        if (!job.environment) return;
        addInto(
            results[j].areaLight,
            traceSparse<glm::vec3>(
                job.points, job.bounds, scene.camera, job.areaLightStride(o, scene.camera), 1,
                job.filter(o, job.areaLightStride(o, scene.camera)), [&](std::span<const uint32_t> pixels) {
                    return traceEnvironmentRays(job.points, *job.environment, job.rays, o, job.mode, pixels);
                }));
    });
    timer.lap("shadow");
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        if (!job.indirect) return;
        results[j].diffuse = traceSparse<glm::vec3>(
            job.points, job.bounds, scene.camera, job.diffuseStride(o, scene.camera), 1,
            job.filter(o, job.diffuseStride(o, scene.camera)), [&](std::span<const uint32_t> pixels) {
                return traceDiffuseCones(job.points, *job.light, job.visibility, o, pixels, job.fullLight,
                                         job.objectLight, job.objectBounceByRays(o), job.diffuseAperture(o));
            });
        if (job.objectBounceByRays(o))
            addInto(results[j].diffuse,
                    traceSparse<glm::vec3>(
                        job.points, job.bounds, scene.camera, job.areaLightStride(o, scene.camera), 1,
                        job.filter(o, job.areaLightStride(o, scene.camera)),
                        [&](std::span<const uint32_t> pixels) {
                            return traceObjectBounceRays(job.points, *job.objectLight, job.rays, o, pixels,
                                                         {job.fullLight, job.light});
                        }));
    });
    timer.lap("diffuse");
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        if (!job.indirect) return;
        auto trace = [&](std::span<const uint32_t> pixels) {
            return traceSpecularCones(job.points, *job.light, job.visibility, o, pixels, job.fullLight,
                                      job.objectLight);
        };
        // Rendered surfaces keep every pixel's reflection unfiltered; the real surfaces' change is sparse.
        results[j].specular =
            job.relit() ? traceSparse<glm::vec3>(job.points, job.bounds, scene.camera,
                                                 job.specularStride(o, scene.camera), 1,
                                                 job.filter(o, job.specularStride(o, scene.camera)), trace)
                        : trace({});
    });
    timer.lap("specular");
    // Sky light through the cones, added to their indirect light; its diffuse part traced sparsely and
    // filtered like the diffuse cones (it has the same jitter noise).
    // (With the environment's light by rays, its direct light, sky included, is already in `areaLight`.)
    if (scene.environment && !scene.environment->sky.empty() && o.shadow.method != ShadowMethod::Rays) {
        const Environment& environment = *scene.environment;
        forEachJob(jobs.size(), [&](size_t j) {
            const ConeJob& job = jobs[j];
            addInto(results[j].diffuse,
                    traceSparse<glm::vec3>(job.points, job.bounds, scene.camera,
                                           job.diffuseStride(o, scene.camera), 1,
                                           job.filter(o, job.diffuseStride(o, scene.camera)),
                                           [&](std::span<const uint32_t> pixels) {
                                               return traceSkyCones(job.points, environment, job.visibility,
                                                                    job.mode, o, SkyParts::Diffuse, pixels)
                                                   .diffuse;
                                           }));
            addInto(results[j].specular,
                    traceSkyCones(job.points, environment, job.visibility, job.mode, o, SkyParts::Specular)
                        .specular);
        });
        timer.lap("sky");
    }
    return results;
}

}  // namespace deltagi
