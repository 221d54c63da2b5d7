// Every tuning factor of the pipeline, read from the scene file's "options" object and written back by
// optionsToJson() (scene_io.h). Each option is described once, in src/scene/option_table.cpp: its key
// (options.GROUP.KEY), type, range, unit and doc, from which the reader, the writer and the options tables of
// docs/scene-format.md follow; its default is the initializer here. The comments here say only what that
// table does not: how the code holds a value. Why each default is what it is: docs/design.md.
#pragma once

#include <algorithm>
#include <optional>

#include <glm/vec3.hpp>

#include "deltagi/export.h"

DELTAGI_API_BEGIN
namespace deltagi {

// The options that choose between methods. Their names in the scene file: src/scene/option_table.h.
enum class ShadowMethod { Rays, Cones };                          // options.shadow.method
enum class ConeAccumulation { Paper, FrontToBack };               // options.trace.accumulation
enum class RelightCones { Differential, DeltaVolume };            // options.render.relight_cones
enum class RelightObjectLight { Cones, Rays };                    // options.render.relight_object_light
enum class ExtractionMethod { MedianCut, VarianceMinimization };  // options.environment.extraction

// options.volume: the region covered by the four volumes (§3.4) and their resolution.
struct VolumeOptions {
    int resolution = 128;
    float extentScale = 2.0f;
    float reachScale = 4.0f;
    // An explicit region (both or neither); null in the scene file for "not set".
    std::optional<glm::vec3> center;
    std::optional<float> size;
    // Not set: the camera's position; a sequence sets it to its transforms file's first camera.
    std::optional<glm::vec3> viewpoint;

    bool operator==(const VolumeOptions&) const = default;
};

// options.rsm: reflective shadow maps (Dachsbacher & Stamminger 2005), one per light.
struct RsmOptions {
    int resolution = 0;  // 0: "auto" (rsmResolutionCeiling, and rsmResolutions for several lights)

    bool operator==(const RsmOptions&) const = default;
};

// options.diffuse: the diffuse cones of §3.1, covering the hemisphere, cosine weighted.
struct DiffuseConeOptions {
    int count = 9;
    float apertureDeg = 0.0f;         // 0: derived from the count
    float objectApertureDeg = 35.0f;  // 0: derived from the count
    int pixelStride = 0;              // 0: "auto" (pixelStrideFor with kAutoDiffuseStride)
    int relightPixelStride = 0;       // 0: "auto" (kAutoRelightDiffuseStride)
    int objectRays = 16;              // 0: cones (object_bounce_rays.h, bounce_light.h)
    int objectRayPixelStride = 0;     // 0: "auto" (kAutoObjectRayStride)
    // The objects' pixels' diffuse light by rays (diffuse_rays.h); 0: by cones; < 0: "auto"
    // (objectGatherRaysFor).
    int objectGatherRays = -1;

    bool operator==(const DiffuseConeOptions&) const = default;
};

// options.specular: the one specular cone along the reflected view ray.
struct SpecularConeOptions {
    float minApertureDeg = 2.0f;  // at most maxApertureDeg
    float maxApertureDeg = 90.0f;
    int relightPixelStride = 0;  // 0: "auto" (kAutoRelightSpecularStride)

    bool operator==(const SpecularConeOptions&) const = default;
};

// options.shadow: how the direct light of each light is shadowed: the shadow cone of §3.5, or shadow rays.
struct ShadowConeOptions {
    ShadowMethod method = ShadowMethod::Rays;
    int raySamples = 4;  // rounded down to a square
    int areaRaySamples = 16;
    float apertureDeg = 4.0f;    // of a light without a radius
    int pixelStride = 0;         // 0: "auto" (kAutoShadowStride, kAutoAreaLightStride)
    int relightPixelStride = 0;  // 0: "auto" (kAutoRelightShadowStride, kAutoRelightAreaLightStride)

    bool operator==(const ShadowConeOptions&) const = default;
};

// options.trace: the cone marcher shared by all cones (cone_trace.h).
struct TraceOptions {
    float stepScale = 0.5f;
    float startOffset = 1.5f;
    float maxOcclusion = 0.98f;
    float normalWeight = 1.0f;
    float backfaceWeight = 1.0f;
    float jitter = 1.0f;
    ConeAccumulation accumulation = ConeAccumulation::FrontToBack;

    bool operator==(const TraceOptions&) const = default;
};

// options.render: the camera pass.
struct RenderOptions {
    int samplesPerPixel = 4;  // GBuffer::objectSamples
    bool indirect = true;
    bool doubleShadowFix = true;
    bool relightIndirect = true;
    int temporalFrames = 4;  // pipeline/temporal_reuse.h; FrameRenderer only
    RelightCones relightCones = RelightCones::Differential;
    RelightObjectLight relightObjectLight = RelightObjectLight::Rays;
    bool layers = false;     // RenderOutput's compositing layers
    int lightBounces = 3;    // bounce_light.h
    bool bounceTail = true;  // the bounces beyond lightBounces, estimated (bounce_light.h)
    int bounceCones = 5;     // the diffuse cones of each further bounce's gather (bounce_light.h)
    int bounceRays = 16;     // its rays instead (bounce_light.h); 0: the cones
    int denoiseRadius = 2;
    int relightDenoiseRadius = 1;  // the same for the real surfaces' change (the relit passes)
    // The share of the image's pixels that the relit passes of the environment's and the objects' light by
    // rays may trace again where their sparse samples change sharply (cone_jobs.cpp, refineSparse); < 0:
    // "auto" (kAutoRefineBudget for a single render, 0 for the frames of a session).
    float refineBudget = -1.0f;

    bool operator==(const RenderOptions&) const = default;
};

// options.environment: how the scene's environment map lights the pipeline (ignored without one).
struct EnvironmentOptions {
    int lightCount = 16;  // light_extraction.h
    ExtractionMethod extraction = ExtractionMethod::MedianCut;
    bool sky = true;  // sky_light.h
    float maxLightApertureDeg = 30.0f;

    bool operator==(const EnvironmentOptions&) const = default;
};

// The "auto" pixel strides: these at a 640x480 image, scaled with its smaller side (so that an image samples
// its surfaces alike at any size) and rounded down to a power of two, at least 1.
inline constexpr int kAutoDiffuseStride = 8, kAutoRelightDiffuseStride = 16;
// The objects' pixels' diffuse light by rays (options.diffuse.object_gather_rays): a detailed statue's light
// changes from pixel to pixel more than the filter interpolates over 8. A still (a single render, a live
// session's idle still) traces every pixel with kAutoStillObjectGatherRays rays, a session's frame every 4th
// of every 4th row with kAutoObjectGatherRays. On the quality suite (docs/quality-notes.md) every pixel with
// 36 rays takes the Buddha's object_rel_rmse 0.185 -> 0.147, the bunny's 0.087 -> 0.063, the dragon's 0.123
// -> 0.110, the bare bulb's 0.061 -> 0.045, for 75 ms more a 640x480 Buddha (its diffuse stage 72 -> 147 ms)
// and 15 ms more a 320x240 Cornell box; every 2nd pixel with 36 rays gave the Buddha 0.157, every pixel with
// 25 rays 0.150, with 49 0.144 (100 ms more), with 64 0.142 (135 ms more).
inline constexpr int kAutoDiffuseRayStride = 4, kAutoStillDiffuseRayStride = 1;
inline constexpr int kAutoObjectGatherRays = 32, kAutoStillObjectGatherRays = 36;
// The objects' gather rays a render uses: the option's, or for "auto" kAutoStillObjectGatherRays for a still
// and kAutoObjectGatherRays for a session's frame; 0: the objects gather by cones.
inline int objectGatherRaysFor(const DiffuseConeOptions& diffuse, bool still) {
    return diffuse.objectGatherRays >= 0 ? diffuse.objectGatherRays
           : still                       ? kAutoStillObjectGatherRays
                                         : kAutoObjectGatherRays;
}
// Shadows of point, spot and directional lights; the area lights' direct light by rays on rendered surfaces
// (noisier: many directions, few rays each) at twice their stride, so that the filter averages more samples.
// Relit, an emitter's contact shadow under an object is sharper than the filter's reach at 4 (the area-lit
// Cornell box's delta_rel_error 0.153 at 4 against 0.119 at 2): 2 like the shadows. The environment's rays
// sample the objects' cone of directions too (traceEnvironmentRays), and a sky's shadow is soft: at 4 the
// bunny in the field keeps its quality-suite figures for a third of the rays' time (docs/design.md).
inline constexpr int kAutoShadowStride = 1, kAutoRelightShadowStride = 2;
inline constexpr int kAutoAreaLightStride = 2, kAutoRelightAreaLightStride = 2;
inline constexpr int kAutoRelightEnvironmentStride = 4;
inline constexpr int kAutoRelightSpecularStride = 4;
// The relit points' rays towards the objects (options.render.relight_object_light "rays"): the light the
// objects add and hide varies slowly, but more sharply than the relit cones' change near the objects. At
// 320x240 over the quality suite and its independent scenes, 4 (8 at 640x480) gives delta_rel_error within
// 0.03 of every pixel's rays, at an eighth of their time (docs/design.md).
inline constexpr int kAutoObjectRayStride = 8;
// The "auto" refine budget of a single render: 1 % of the image's pixels traced again. A session's frames
// keep their time (temporal reuse averages them instead): the field photo's delta_rel_error 0.347 -> 0.239
// for 15-35 ms more a live frame there, 13 ms more a benchmark frame (docs/design.md).
inline constexpr float kAutoRefineBudget = 0.01f;
// The refine budget a render uses: the option's, or for "auto" kAutoRefineBudget for a still (a single
// render, a live session's idle still) and 0 for a session's frame.
inline float refineBudgetFor(const RenderOptions& render, bool still) {
    return render.refineBudget >= 0.0f ? render.refineBudget : still ? kAutoRefineBudget : 0.0f;
}

// The "auto" RSM resolution. A point or spot light's map: kAutoRsmTexelsPerVoxel texels per voxel along the
// volume's side, in [kAutoRsmMinResolution, kAutoRsmMaxResolution]. At 128^3, 3 (384) against 4 (512): every
// quality-suite delta_rel_error within 0.006 (0.003-0.006 higher on the 640x480 boxes, under 0.001 on the
// bare bulb and the bunny) for a live frame's shadow maps and injection in 60 % of the time (docs/design.md).
// A directional light's map is orthographic over the region's bounding sphere:
// kAutoRsmDirectionalTexelsPerVoxel per voxel along the volume's side (about 1.2 across a voxel facing the
// light), in [kAutoRsmDirectionalMinResolution, kAutoRsmMaxResolution]. The field photo's 16 lights at 128^3:
// 256 against 512 gives delta_rel_error 0.347 against 0.340 for a live frame's shadow maps and injection in a
// third of the time; at 32^3 and 64^3 the floor keeps 2.3 texels and more across a voxel (docs/design.md,
// "Sparse tracing"). Among several lights, each takes its ceiling times the square root of its share of the
// brightest light's irradiance in the volume (the split of a texel budget that minimizes the sum of the
// lights' injection noise), rounded to the nearest power of two, at least the ceiling / kAutoRsmMinShare.
inline constexpr int kAutoRsmTexelsPerVoxel = 3, kAutoRsmMinResolution = 64, kAutoRsmMaxResolution = 512;
inline constexpr int kAutoRsmMinShare = 4;
inline constexpr int kAutoRsmDirectionalTexelsPerVoxel = 2, kAutoRsmDirectionalMinResolution = 256;

// The largest RSM face resolution options.rsm.resolution gives a light (the given one, or "auto"'s ceiling
// for options.volume.resolution `volumeResolution`, point and spot lights or directional ones).
inline int rsmResolutionCeiling(int option, int volumeResolution, bool directional) {
    if (option > 0) return option;
    if (directional)
        return std::clamp(kAutoRsmDirectionalTexelsPerVoxel * volumeResolution,
                          kAutoRsmDirectionalMinResolution, kAutoRsmMaxResolution);
    return std::clamp(kAutoRsmTexelsPerVoxel * volumeResolution, kAutoRsmMinResolution,
                      kAutoRsmMaxResolution);
}

// The stride an option (0: "auto", with `autoStride` at 640x480) gives for a width x height image.
inline int pixelStrideFor(int option, int autoStride, int width, int height) {
    if (option > 0) return option;
    const int scaled = autoStride * std::min(width, height) / 480;
    int stride = 1;
    while (stride * 2 <= std::min(scaled, 32)) stride *= 2;
    return stride;
}

struct Options {
    VolumeOptions volume;
    RsmOptions rsm;
    DiffuseConeOptions diffuse;
    SpecularConeOptions specular;
    ShadowConeOptions shadow;
    TraceOptions trace;
    RenderOptions render;
    EnvironmentOptions environment;

    bool operator==(const Options&) const = default;
};

}  // namespace deltagi
DELTAGI_API_END
