// Stage 6 of a frame (§3.3) for its sets of surfaces: the shadow, diffuse and specular cones (or rays) of
// the objects' pixels and of the real surfaces they relight, traced sparsely where a job asks and filtered
// (denoise.h), the jobs run at once. renderer.cpp makes the jobs; this unit runs their passes.
#pragma once

#include <array>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "core/environment_sampling.h"
#include "core/ray_scene.h"
#include "deltagi/scene.h"
#include "pipeline/area_light_rays.h"
#include "pipeline/cone_trace.h"
#include "pipeline/denoise.h"
#include "pipeline/gbuffer.h"
#include "pipeline/mipmap.h"
#include "pipeline/shadow_rays.h"
#include "pipeline/stage_timer.h"

namespace deltagi {

// One set of surfaces to trace cones from, against a light volume and visibility volumes.
struct ConeJob {
    std::span<const SurfacePoint> points;
    const MipVolume* light = nullptr;
    VisibilityVolumes visibility;
    bool indirect = true;  // trace diffuse and specular cones too
    // How shadows and the sky through the cones count (shaded, relit, or the real scene alone).
    ShadowMode mode = ShadowMode::Shaded;
    PixelRect bounds;                             // holds every valid point
    SceneOcclusionCache* sceneShadows = nullptr;  // relit with DeltaShadow: the scene's share, kept
    // Relit real surfaces: the filter's interpolation weights of the shadow, diffuse and specular passes,
    // kept (their surfaces are the real G-buffer's), and the pixels whose points differ from it (covered).
    std::array<InterpolationPlan, 5>* plans = nullptr;  // one per stride (filter())
    PixelRect changed{};
    ShadowRayScenes rays;  // options.shadow.method "rays": what shadow rays are cast against
    // Relit with options.render.relight_cones "differential": the full light volume (`light` is the delta).
    const MipVolume* fullLight = nullptr;
    const MipVolume* objectLight = nullptr;  // with fullLight: the objects' share of it
    // The objects' change of the real surfaces' light around them (ObjectVolumes::roomChange), which the
    // objects' diffuse rays (diffuseRays) read with `light`; may be null or empty.
    const MipVolume* lightChange = nullptr;
    // Emitting surfaces lighting the points through shadow rays (options.shadow.method "rays"), or none.
    const AreaLights* emitters = nullptr;
    // The environment map lighting the points through shadow rays (options.shadow.method "rays"), or none.
    const EnvironmentSampler* environment = nullptr;
    // Rendered objects: the sub-samples of their pixels, whose area the shadow rays sample; or none.
    const PixelSamples* pixelSamples = nullptr;
    // Relit: the share of the image's pixels its environment and objects' light passes may trace again where
    // they change sharply (options.render.refine_budget, resolved); 0: none.
    float refineBudget = 0.0f;
    // Rendered objects: a still (a single render), whose "auto" gather rays are finer than a session
    // frame's (objectGatherRaysFor; with them, where options.diffuse.pixel_stride is "auto" too, every pixel
    // traced: kAutoStillDiffuseRayStride), and whose glossy pixels in a sphere light's penumbra take the
    // shadow of the part of the disk their lobe sees (glossyShadowOcclusion).
    bool still = false;
    bool relit() const {
        return mode == ShadowMode::DeltaShadow || mode == ShadowMode::DeltaSingleVisibility;
    }
    // The pixel strides of its shadow, specular (relit only) and diffuse cones, "auto" resolved for the
    // camera's image.
    // Shadows, emitters' and the environment map's direct light by rays: options.shadow.pixel_stride (or
    // relight_pixel_stride) when given, else each its own "auto" (`shadedAuto` on rendered surfaces,
    // `relitAuto` on relit ones).
    int shadowOptionStride(const Options& o, const Camera& c, int shadedAuto, int relitAuto) const {
        return relit() ? pixelStrideFor(o.shadow.relightPixelStride, relitAuto, c.width, c.height)
                       : pixelStrideFor(o.shadow.pixelStride, shadedAuto, c.width, c.height);
    }
    int areaLightStride(const Options& o, const Camera& c) const {
        return shadowOptionStride(o, c, kAutoAreaLightStride, kAutoRelightAreaLightStride);
    }
    int environmentStride(const Options& o, const Camera& c) const {
        return shadowOptionStride(o, c, kAutoAreaLightStride, kAutoRelightEnvironmentStride);
    }
    int shadowStride(const Options& o, const Camera& c) const {
        return shadowOptionStride(o, c, kAutoShadowStride, kAutoRelightShadowStride);
    }
    // The edge-aware filter of its sparse cones; the real surfaces' change varies slowly, so its pixels
    // between samples are interpolated.
    // The passes of one stride share their plan: their weights are the same.
    DenoiseSettings filter(const Options& o, int stride) const {
        DenoiseSettings s;
        s.radius = relit() ? o.render.relightDenoiseRadius : o.render.denoiseRadius;
        s.interpolate = relit();
        if (plans) {
            auto plan = std::find_if(plans->begin(), plans->end(),
                                     [&](const InterpolationPlan& p) { return p.stride == stride; });
            if (plan == plans->end())  // one not built yet
                plan = std::find_if(plans->begin(), plans->end(),
                                    [](const InterpolationPlan& p) { return p.stride == 0; });
            if (plan != plans->end()) s.plan = &*plan;
        }
        s.planChanged = changed;
        return s;
    }
    // The objects' light on relit real surfaces by rays (traceObjectBounceRays): only when the differential
    // relit cones can leave it out.
    bool objectBounceByRays(const Options& o) const {
        return relit() && indirect && fullLight && objectLight && rays.scene && rays.objects &&
               o.render.relightObjectLight == RelightObjectLight::Rays;
    }
    // The virtual objects' diffuse cones have their own aperture; the others options.diffuse.aperture_deg.
    std::optional<float> diffuseAperture(const Options& o) const {
        if (mode == ShadowMode::Shaded) return o.diffuse.objectApertureDeg;
        return std::nullopt;
    }
    int objectRayStride(const Options& o, const Camera& c) const {
        return pixelStrideFor(o.diffuse.objectRayPixelStride, kAutoObjectRayStride, c.width, c.height);
    }
    int specularStride(const Options& o, const Camera& c) const {
        return pixelStrideFor(o.specular.relightPixelStride, kAutoRelightSpecularStride, c.width, c.height);
    }
    int diffuseStride(const Options& o, const Camera& c) const {
        if (relit())
            return pixelStrideFor(o.diffuse.relightPixelStride, kAutoRelightDiffuseStride, c.width, c.height);
        const int rayStride =
            still && o.diffuse.objectGatherRays < 0 ? kAutoStillDiffuseRayStride : kAutoDiffuseRayStride;
        return pixelStrideFor(o.diffuse.pixelStride, diffuseRays(o) ? rayStride : kAutoDiffuseStride, c.width,
                              c.height);
    }
    // The rendered objects' diffuse light by rays (traceDiffuseRays, gatherRays of them) rather than cones,
    // cast against this.
    const RayScene* diffuseRays(const Options& o) const {
        if (mode != ShadowMode::Shaded || gatherRays(o) <= 0) return nullptr;
        return rays.objects ? rays.objects : rays.scene;
    }
    int gatherRays(const Options& o) const { return objectGatherRaysFor(o.diffuse, still); }
};

// What traceCones gives a job, per point of its surfaces (pixels of the image).
struct ConeResults {
    std::vector<ShadowOcclusion> shadows;      // points x lights
    std::vector<glm::vec3> diffuse, specular;  // empty without indirect light
    std::vector<glm::vec3> areaLight;          // direct light of emitting surfaces; empty without
};

// a += b, where an empty vector is zero.
void addInto(std::vector<glm::vec3>& a, std::vector<glm::vec3>&& b);

// The cone passes of every job, each pass timed as one stage over all jobs ("shadow", "diffuse", "specular",
// then "sky" with a sky light), with options `o` (the scene's, or the background's), the direct light of
// `directLights`.
std::vector<ConeResults> traceCones(std::span<const ConeJob> jobs, const Scene& scene, const Options& o,
                                    std::span<const Light> directLights, StageTimer& timer);

}  // namespace deltagi
