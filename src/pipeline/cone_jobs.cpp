#include "pipeline/cone_jobs.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "core/parallel.h"
#include "pipeline/diffuse_rays.h"
#include "pipeline/object_bounce_rays.h"
#include "pipeline/sky_light.h"
#include "pipeline/sparse_pass.h"

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

// The 2 x 2 points of pixel i's area on the plane of its point (where the camera's rays through the
// quarters of the pixel meet it), for the surfaces that have no sub-samples of their own.
std::array<SurfacePoint, 4> pixelQuarters(const SurfacePoint& p, size_t i, const Camera& camera) {
    std::array<SurfacePoint, 4> out;
    const glm::vec3 eye = camera.position();
    const float x = static_cast<float>(i % static_cast<size_t>(camera.width)),
                y = static_cast<float>(i / static_cast<size_t>(camera.width));
    for (int k = 0; k < 4; ++k) {
        out[k] = p;
        const glm::vec3 dir = camera.rayDirection(x + 0.25f + 0.5f * (k & 1), y + 0.25f + 0.5f * (k >> 1));
        const float facing = glm::dot(dir, p.normal);
        const float t = glm::dot(p.position - eye, p.normal) / facing;
        if (!(std::abs(facing) > 1e-6f) || !(t > 0.0f) || !std::isfinite(t)) continue;
        out[k].position = eye + t * dir;
        out[k].toEye = glm::normalize(eye - out[k].position);
    }
    return out;
}

// An occlusion strictly between kPart and 1 - kPart is partial: a shadow's edge or penumbra.
constexpr float kPart = 1e-3f;

// A light without a size casts a shadow whose edge is a pixel wide, but the shadow's sparse samples and the
// filter (traceSparse) spread it over their stride and radius. The pixels they leave part-shadowed by such a
// light are traced again, each on its own over its area (its sub-samples where the job has them, else the
// quarters of the pixel on its point's plane: an edge smoothed over the pixel, as the path tracer's is), and
// keep that; elsewhere a hard light's occlusion is 0 or 1 already. Costs rays along the edges only.
void sharpenHardShadows(std::vector<ShadowOcclusion>& shadows, const ConeJob& job, const PixelRect& bounds,
                        std::span<const Light> lights, const Options& o, const Camera& camera) {
    const int width = camera.width;
    std::vector<int> hard;
    std::vector<Light> hardLights;
    for (int l = 0; l < static_cast<int>(lights.size()); ++l)
        if (shadowRayCount(lights[static_cast<size_t>(l)], o.shadow.raySamples) == 1) {
            hard.push_back(l);
            hardLights.push_back(lights[static_cast<size_t>(l)]);
        }
    if (hard.empty() || shadows.empty()) return;
    const auto part = [](float v) { return v > kPart && v < 1.0f - kPart; };
    const size_t n = lights.size();
    std::vector<uint32_t> edge;
    for (int y = bounds.y0; y < bounds.y1; ++y)
        for (int x = bounds.x0; x < bounds.x1; ++x) {
            const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
            if (!job.points[i].valid()) continue;
            for (int l : hard) {
                const ShadowOcclusion& s = shadows[i * n + static_cast<size_t>(l)];
                if (part(s.scene) || part(s.object) || part(s.combined)) {
                    edge.push_back(static_cast<uint32_t>(i));
                    break;
                }
            }
        }
    if (edge.empty()) return;
    if (job.pixelSamples) {
        const std::vector<ShadowOcclusion> exact =
            traceShadowRays(job.points, hardLights, job.rays, o, job.mode, edge, job.pixelSamples, width);
        for (uint32_t i : edge)
            for (size_t k = 0; k < hard.size(); ++k)
                shadows[i * n + static_cast<size_t>(hard[k])] = exact[i * hard.size() + k];
        return;
    }
    std::vector<SurfacePoint> quarters;
    quarters.reserve(4 * edge.size());
    for (uint32_t i : edge)
        for (const SurfacePoint& q : pixelQuarters(job.points[i], i, camera)) quarters.push_back(q);
    const std::vector<ShadowOcclusion> exact = traceShadowRays(quarters, hardLights, job.rays, o, job.mode);
    for (size_t e = 0; e < edge.size(); ++e)
        for (size_t k = 0; k < hard.size(); ++k) {
            ShadowOcclusion sum;
            for (size_t q = 0; q < 4; ++q) {
                const ShadowOcclusion& v = exact[(4 * e + q) * hard.size() + k];
                sum.scene += 0.25f * v.scene;
                sum.object += 0.25f * v.object;
                sum.combined += 0.25f * v.combined;
            }
            shadows[edge[e] * n + static_cast<size_t>(hard[k])] = sum;
        }
}

// The pixels a job's pass of shadow rays towards `lights` traces and filters (`stride`, `filter`: the
// pass's): the job's, or for the real surfaces relit (whose change is zero wherever their rays cannot meet
// the objects) the rectangle of the objects' shadow volumes with the pass's margin (sparsePassMargin): the
// same result as over the job's bounds, for a fraction of the pixels where the shadow is small.
PixelRect shadowRayBounds(const ConeJob& job, std::span<const Light> lights, const Camera& camera, int stride,
                          const DenoiseSettings& filter) {
    if (job.mode != ShadowMode::DeltaShadow) return job.bounds;
    return relitShadowRect(camera, lights, job.rays, job.bounds, sparsePassMargin(stride, filter));
}

// The same for the emitting surfaces' rays (relitEmitterRect).
PixelRect emitterRayBounds(const ConeJob& job, const Camera& camera, int stride,
                           const DenoiseSettings& filter) {
    if (job.mode != ShadowMode::DeltaShadow) return job.bounds;
    return relitEmitterRect(camera, *job.emitters, job.rays, job.bounds, sparsePassMargin(stride, filter));
}

// A sphere light's soft shadow on the objects' glossy pixels in a still (glossyShadowOcclusion): the pixels
// whose occlusion by a sized light is partial take the visible share of their direct light's quadrature over
// the light's disk, from at most kGlossyShadowRays rays each. Quality suite's cornell-textured,
// object_rel_rmse: 0.190 without (with the finer grids of the G-buffer's kFineLobeTurns), 0.149, 0.134,
// 0.125, 0.121 with 16, 64, 128, 256 rays over all of a finer pixel's 64 sub-samples; 0.123 with 64 over 16
// of them (kGlossyShadowSamples). Its still's shadow stage 60 ms without, 119 with.
constexpr int kGlossyShadowRays = 64;

void sharpenGlossyShadows(std::vector<ShadowOcclusion>& shadows, const ConeJob& job,
                          std::span<const Light> lights, const Options& o, const Camera& camera) {
    if (job.mode != ShadowMode::Shaded || !job.still || !job.rays.scene || shadows.empty()) return;
    std::vector<size_t> sized;
    for (size_t l = 0; l < lights.size(); ++l)
        if (shadowRayCount(lights[l], o.shadow.raySamples) > 1) sized.push_back(l);
    if (sized.empty()) return;
    const size_t n = lights.size();
    const int width = camera.width;
    parallelFor(job.bounds.y0, job.bounds.y1, 4, [&](int64_t y) {
        for (int x = job.bounds.x0; x < job.bounds.x1; ++x) {
            const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
            const SurfacePoint& p = job.points[i];
            if (!p.valid() || !p.surface.glossy()) continue;
            const std::span<const SurfacePoint> area =
                job.pixelSamples ? job.pixelSamples->of(i, width) : std::span<const SurfacePoint>{};
            for (const size_t l : sized) {
                float& combined = shadows[i * n + l].combined;
                if (combined > kPart && combined < 1.0f - kPart)
                    combined =
                        glossyShadowOcclusion(p, area, lights[l], job.rays, combined, kGlossyShadowRays);
            }
        }
    });
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
        const int stride = job.shadowStride(o, scene.camera);
        const DenoiseSettings filter = job.filter(o, stride);
        const PixelRect bounds = o.shadow.method == ShadowMethod::Rays
                                     ? shadowRayBounds(job, directLights, scene.camera, stride, filter)
                                     : job.bounds;
        if (bounds.empty()) {  // the objects change no point's shadow
            results[j].shadows.assign(job.points.size() * directLights.size(), ShadowOcclusion{});
            return;
        }
        results[j].shadows = traceSparse<ShadowOcclusion>(
            job.points, bounds, scene.camera, stride, lights, filter, [&](std::span<const uint32_t> pixels) {
                if (o.shadow.method == ShadowMethod::Rays)
                    return traceShadowRays(job.points, directLights, job.rays, o, job.mode, pixels,
                                           job.pixelSamples, scene.camera.width);
                return traceShadowCones(job.points, directLights, job.visibility, o,
                                        job.mode == ShadowMode::DeltaShadow, pixels, job.sceneShadows);
            });
        if (o.shadow.method == ShadowMethod::Rays) {
            sharpenHardShadows(results[j].shadows, job, bounds, directLights, o, scene.camera);
            sharpenGlossyShadows(results[j].shadows, job, directLights, o, scene.camera);
        }
    });
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        if (!job.emitters || job.emitters->empty()) return;
        const int stride = job.areaLightStride(o, scene.camera);
        const DenoiseSettings filter = job.filter(o, stride);
        const PixelRect bounds = emitterRayBounds(job, scene.camera, stride, filter);
        if (bounds.empty()) {  // the objects change no point's light from the emitters
            results[j].areaLight.assign(job.points.size(), glm::vec3(0.0f));
            return;
        }
        results[j].areaLight = traceSparse<glm::vec3>(
            job.points, bounds, scene.camera, stride, 1, filter, [&](std::span<const uint32_t> pixels) {
                return traceAreaLightRays(job.points, *job.emitters, job.rays, o, job.mode, pixels);
            });
    });
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        if (!job.environment) return;
        addInto(results[j].areaLight,
                traceSparse<glm::vec3>(
                    job.points, job.bounds, scene.camera, job.environmentStride(o, scene.camera), 1,
                    job.filter(o, job.environmentStride(o, scene.camera)),
                    [&](std::span<const uint32_t> pixels) {
                        return traceEnvironmentRays(job.points, *job.environment, job.rays, o, job.mode,
                                                    pixels);
                    },
                    SparseRefinement{job.refineBudget}));
    });
    timer.lap("shadow");
    forEachJob(jobs.size(), [&](size_t j) {
        const ConeJob& job = jobs[j];
        if (!job.indirect) return;
        results[j].diffuse = traceSparse<glm::vec3>(
            job.points, job.bounds, scene.camera, job.diffuseStride(o, scene.camera), 1,
            job.filter(o, job.diffuseStride(o, scene.camera)), [&](std::span<const uint32_t> pixels) {
                if (const RayScene* scene = job.diffuseRays(o))
                    return traceDiffuseRays(job.points, *job.light, *scene, job.gatherRays(o), pixels,
                                            job.lightChange);
                return traceDiffuseCones(job.points, *job.light, job.visibility, o, pixels, job.fullLight,
                                         job.objectLight, job.objectBounceByRays(o), job.diffuseAperture(o));
            });
        if (job.objectBounceByRays(o))
            addInto(results[j].diffuse,
                    traceSparse<glm::vec3>(
                        job.points, job.bounds, scene.camera, job.objectRayStride(o, scene.camera), 1,
                        job.filter(o, job.objectRayStride(o, scene.camera)),
                        [&](std::span<const uint32_t> pixels) {
                            return traceObjectBounceRays(job.points, *job.objectLight, job.rays, o, pixels,
                                                         {job.fullLight, job.light});
                        },
                        SparseRefinement{job.refineBudget}));
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
