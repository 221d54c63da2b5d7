// Every tuning factor of the pipeline, with its default and unit. Read from the scene file's "options" object
// (the JSON key of each field is given in its comment) and written back by optionsToJson() (scene_io.h).
#pragma once

#include <algorithm>
#include <optional>

#include <glm/vec3.hpp>

namespace deltagi {

// The options that choose between methods. Their names in the scene file: src/scene/option_table.h.
enum class ShadowMethod { Rays, Cones };                          // options.shadow.method
enum class ConeAccumulation { Paper, FrontToBack };               // options.trace.accumulation
enum class RelightCones { Differential, DeltaVolume };            // options.render.relight_cones
enum class RelightObjectLight { Cones, Rays };                    // options.render.relight_object_light
enum class ExtractionMethod { MedianCut, VarianceMinimization };  // options.environment.extraction

// options.volume: the region covered by the four volumes (§3.4) and their resolution.
struct VolumeOptions {
    int resolution = 128;  // "resolution": voxels along each axis; a power of two in [4, 1024]
    // "extent_scale": when no region is given, the region is this multiple of the virtual objects' bounding
    // box (§3.4 uses twice the bounding box), made cubic around its centre.
    float extentScale = 2.0f;
    // "reach_scale": without an explicit region, the cube grows from extent_scale up to this multiple of the
    // objects' box to take in the real surfaces around them (the walls and floor that light the object and
    // that its shadows and light fall on), and is moved, keeping the objects inside, so that it holds as much
    // of the real scene as it can. 0 (or below extent_scale) keeps the paper's extent_scale cube.
    float reachScale = 4.0f;
    // "center" [x,y,z] and "size" (world units, edge length of the cube): an explicit region. Both or
    // neither.
    std::optional<glm::vec3> center;
    std::optional<float> size;
    // "viewpoint" [x,y,z]: the point that says which side of a real surface is the room's. Surfaces are
    // two-sided and a reconstruction's winding is not reliable: the reflective shadow maps keep a real
    // surface's texels where its lit side faces this point, and the further bounces gather on its side. Not
    // set (null): the camera's position. A sequence sets it to its transforms file's first camera, so that
    // every frame (and every chunk of frames) lights the volumes alike and the camera can move without the
    // real scene's volumes being redone.
    std::optional<glm::vec3> viewpoint;

    bool operator==(const VolumeOptions&) const = default;
};

// options.rsm: reflective shadow maps (Dachsbacher & Stamminger 2005), one per light.
struct RsmOptions {
    // "resolution": texels along each side of one RSM face, for every light; or "auto" (0 here, the default):
    // at most kAutoRsmTexelsPerVoxel texels per voxel along the volume's side (rsmResolutionCeiling: 512 at
    // 128^3 and above, 128 at 32^3), and less for a light that brings less light into the volume than the
    // brightest (rsmResolutions): many lights in a room cost little each.
    int resolution = 0;

    bool operator==(const RsmOptions&) const = default;
};

// options.diffuse: the diffuse cones of §3.1, covering the hemisphere, cosine weighted.
struct DiffuseConeOptions {
    int count = 9;  // "count": number of cones in [1, 64]
    // "aperture_deg": full apex angle of each cone in degrees; 0 derives it from the count so that the cones'
    // solid angles add up to the hemisphere (half-angle = acos(1 - 1/count)).
    float apertureDeg = 0.0f;
    // "object_aperture_deg": the same for the virtual objects' own diffuse cones (0: derived from the count).
    // Narrower than the 9 cones' 54 degrees that tile the hemisphere: a wide cone reads coarse voxels a few
    // steps from the surface and blurs the objects' self-occlusion and the colours of the walls they see. On
    // the quality suite, 54 -> 35 degrees: object_rel_rmse 0.258 -> 0.241 (Happy Buddha), 0.103 -> 0.085
    // (ball and ring), 0.106 -> 0.080 (field photo), the others within 0.001; narrower for the real surfaces'
    // relit cones too made the glossy box's delta worse (0.232 -> 0.241), so they keep aperture_deg.
    float objectApertureDeg = 35.0f;
    // "pixel_stride": the diffuse cones of rendered surfaces (the virtual objects, the real scene rendered
    // without a photo) are traced at every pixel_stride-th pixel of every pixel_stride-th row (1, 2, 4, 8, 16
    // or 32); the edge-aware filter fills the pixels between from traced neighbours on the same surface, and
    // pixels with none are traced too. "auto" (0 here, the default) scales kAutoDiffuseStride with the
    // image (pixelStrideFor). Diffuse light varies slowly: against the path-traced reference (`deltagi eval`,
    // Cornell box + Happy Buddha at 640x480) 8 is as close as 4 (object_rel_rmse 0.822 vs 0.827) and traces a
    // quarter of the cones.
    int pixelStride = 0;
    // "relight_pixel_stride": the same for the real surfaces' change (the relighting of §3.3), which is
    // smoother still: it is the light the objects add or take away, seen through wide cones. 16 against 4 at
    // 640x480: delta_rel_error 0.710 vs 0.713 on the same scene.
    int relightPixelStride = 0;
    // "object_rays": rays (0 to 256, rounded down to a square) that each coarse voxel of the virtual objects
    // casts to gather the light they reflect once more (options.render.light_bounces >= 2), and that each
    // relit real point casts towards the objects with options.render.relight_object_light "rays" (fewer where
    // the objects look small: object_bounce_rays.h's objectRaySide). Cones from a coarse voxel start half a
    // voxel and more off its surface, below the floor under an object standing on it, whose underside then
    // gets none of the floor's light (bounce_light.h). 0: cones.
    int objectRays = 16;

    bool operator==(const DiffuseConeOptions&) const = default;
};

// options.specular: the one specular cone along the reflected view ray.
struct SpecularConeOptions {
    // "min_aperture_deg" / "max_aperture_deg": the aperture derived from a material's roughness is clamped to
    // this range (degrees, full apex angle). A narrow cone costs many small steps (Table 1 of the paper).
    float minApertureDeg = 2.0f;
    float maxApertureDeg = 90.0f;
    // "relight_pixel_stride": the real surfaces' change through specular cones (the objects seen in a glossy
    // real surface, and their shadow in what it reflects) traced at every relight_pixel_stride-th pixel of
    // every such row and interpolated like the diffuse cones' ("auto", 0 here, the default:
    // kAutoRelightSpecularStride at 640x480). Rendered surfaces trace every pixel.
    int relightPixelStride = 0;

    bool operator==(const SpecularConeOptions&) const = default;
};

// options.shadow: how the direct light of each light is shadowed: the shadow cone of §3.5, or shadow rays.
struct ShadowConeOptions {
    // "method": "rays" (the default) casts `ray_samples` shadow rays per point and light towards points
    // spread over the light's area (a sphere light's disk, a directional light's cone of directions), against
    // the real scene's and the objects' triangles (Embree), and filters them like the cones; "cones" marches
    // the paper's shadow cone through the visibility volumes. Rays give the path tracer's shadows (width,
    // depth, penumbra, the objects' self-shadowing) at any volume size; cones blur every occluder to voxels
    // and are cut off at the volume's faces (docs/ground-truth.md has the figures of both).
    ShadowMethod method = ShadowMethod::Rays;
    // "ray_samples": shadow rays per point and light with a size (a radius or an angular radius), on a
    // jittered grid (rounded down to a square, 1 to 256). A light without a size takes one ray. The filter
    // averages 5 x 5 traced pixels, so 4 rays already give 100 per filtered pixel.
    int raySamples = 4;
    // "area_ray_samples": rays per point towards the emitting surfaces, and towards the environment map (each
    // set of rays samples many directions, so it needs more than a light's disk), on a jittered grid (rounded
    // down to a square, 1 to 256).
    int areaRaySamples = 16;
    // "aperture_deg": full apex angle in degrees of the shadow cone of a light without a "radius".
    // A light with a radius r at distance d uses 2*atan(r/d) instead.
    float apertureDeg = 4.0f;
    // "pixel_stride": shadows (rays or cones) of rendered surfaces at every pixel_stride-th pixel of every
    // pixel_stride-th row, interpolated like options.diffuse.pixel_stride ("auto", 0 here, the default:
    // kAutoShadowStride, kAutoAreaLightStride at 640x480; docs/scene-format.md has the figures).
    int pixelStride = 0;
    // "relight_pixel_stride": the same for the shadows the objects cast on real surfaces ("auto":
    // kAutoRelightShadowStride, kAutoRelightAreaLightStride at 640x480).
    int relightPixelStride = 0;

    bool operator==(const ShadowConeOptions&) const = default;
};

// options.trace: the cone marcher shared by all cones.
struct TraceOptions {
    // "step_scale": distance between samples as a fraction of the cone diameter there (dimensionless).
    float stepScale = 0.5f;
    // "start_offset": the cone starts this many voxels (level-0 voxel edges) away from the surface, along the
    // normal and the cone axis, so that a surface does not occlude itself.
    float startOffset = 1.5f;
    // "max_occlusion": a cone stops once its accumulated occlusion reaches this value (in [0.5, 1]).
    float maxOcclusion = 0.98f;
    // "normal_weight": how strongly the stored average normal adapts the occlusion (§3.1): 0 = isotropic
    // occlusion, 1 = a voxel whose normals all agree occludes a grazing cone in proportion to |cos|.
    float normalWeight = 1.0f;
    // "backface_weight": how much less a voxel occludes a cone that leaves it through the back of its surface
    // (mean normal along the cone): 0 = two-sided, 1 = a coherent back face does not occlude. This is what
    // keeps a convex surface from shadowing itself at grazing angles (the shadow terminator).
    float backfaceWeight = 1.0f;
    // "jitter": offsets each cone's first step by a fraction of a step that is random per pixel (seeded by
    // the pixel index), turning the banding of regular steps into fine noise. 0 disables it.
    float jitter = 1.0f;
    // "accumulation": "paper" uses the accumulator formulas of §3.1 as printed
    //   light = light*occ + light_local*occ_local*(1-occ); occ = occ + occ_local*(1-occ),
    // "front_to_back" uses the usual emission-absorption compositing light += light_local*occ_local*(1-occ).
    ConeAccumulation accumulation = ConeAccumulation::FrontToBack;

    bool operator==(const TraceOptions&) const = default;
};

// options.render: the camera pass.
struct RenderOptions {
    // "samples_per_pixel": sub-pixel samples for the G-buffer; the object mask is their coverage, which
    // anti-aliases the silhouette, and the objects' direct light is shaded over them
    // (GBuffer::objectSamples). 1, 4, 9 or 16 (a square grid).
    int samplesPerPixel = 4;
    // "indirect": trace the diffuse and specular cones (false: direct light and shadow cones only).
    bool indirect = true;
    // "double_shadow_fix": relight real surfaces with the object's shadow only where the real scene does not
    // already shadow them (§3.2). false reproduces the double shadow of a single shared visibility volume.
    bool doubleShadowFix = true;
    // "relight_indirect": add the indirect change (delta volume cones) to real surfaces. false keeps only the
    // object's shadow on them (the "shadow only" baseline of the evaluation); the object is shaded in full.
    bool relightIndirect = true;
    // "temporal_frames": frames of a sequence (FrameRenderer) each pixel's lighting is averaged over, this
    // one and those before it, reprojected and clamped to this frame's neighbourhood
    // (pipeline/temporal_reuse.h); 1 turns it off. A single render() has no frames before it.
    int temporalFrames = 4;
    // "relight_cones": how the real surfaces' indirect change is traced. "differential" (the default): each
    // cone is the full light volume seen through both visibility volumes (the scene's surfaces and the
    // objects' each shining with their own radiance) minus the real scene's own light (full - delta) seen
    // through the scene's visibility alone, which includes the light the objects block between two real
    // surfaces. "delta_volume": the paper's delta volume seen through both visibility volumes (§3.3), which
    // misses that blocked light. Quality suite (with the objects' own further bounce): delta_rel_error 0.255
    // -> 0.161 (ball and ring), 0.227 -> 0.204 (Buddha), 0.268 -> 0.258 (glossy), 0.297 -> 0.216 (area
    // light), 0.758 -> 0.630 (field photo).
    RelightCones relightCones = RelightCones::Differential;
    // "relight_object_light": how the objects' own light, and the real light they hide, reach the real
    // surfaces with "differential" relit cones. "cones" (the default): all of it through the cones, where a
    // coarse voxel that holds an object and the floor under it hides the object from afar and spreads it wide
    // nearby. "rays": options.diffuse.object_rays rays per relit point (at the area lights' relit stride)
    // towards the objects (object_bounce_rays.h); where one meets an object it brings the objects' voxel
    // radiance there and takes away the real scene's light it met before; the cones carry only the change of
    // the real surfaces' own light, through the scene's visibility. Quality suite, cones -> rays:
    // delta_rel_error 0.154 -> 0.144 (ball and ring), 0.210 -> 0.188 (Buddha), 0.232 -> 0.188 (glossy),
    // 0.160 -> 0.154 (area light), 0.237 -> 0.188 (textured vase); the field photo, which sets "rays", 0.261.
    // Not the default for its cost: the benchmark frame's diffuse stage 14 -> 90 ms (76,800 relit points, up
    // to 16 rays each), and its error per millisecond is no better than the cones' at any stride tried
    // (README, departures from the paper).
    RelightObjectLight relightObjectLight = RelightObjectLight::Cones;
    // "layers": also make the compositing layers of RenderOutput (object, shadow, indirect, depth); `deltagi
    // render --layers` sets it. Off by default: four more images a frame.
    bool layers = false;
    // "light_bounces": bounces of indirect light the light volumes carry (1 to 8). 1 is the paper: the
    // reflective shadow maps inject the directly lit surfaces, and the cones gather one bounce. Each more
    // gathers the volume at every surface voxel of the real scene and adds what it reflects (bounceLight,
    // once while the real side stays the same).
    int lightBounces = 2;
    // "denoise_radius": pixels of the edge-aware filter over the shadow and diffuse cone results, which
    // averages the noise of the jittered cone starts (0 disables it).
    int denoiseRadius = 2;

    bool operator==(const RenderOptions&) const = default;
};

// options.environment: how the scene's environment map lights the pipeline (ignored without one).
struct EnvironmentOptions {
    // "light_count": directional lights extracted from the map (in [0, 256]); they drive the reflective
    // shadow maps and the shadow cones. 0 leaves all of the map's light to the sky term.
    int lightCount = 16;
    // "extraction": "median_cut" (Debevec 2005: regions of equal energy) or "variance_minimization"
    // (Viriyothai & Debevec 2009: each split minimizes the regions' energy-weighted angular variance).
    ExtractionMethod extraction = ExtractionMethod::MedianCut;
    // "sky": diffuse and specular cones that leave the volumes pick up the map minus the extracted lights,
    // prefiltered to their aperture (sky light, reflections, and the object's ambient occlusion on real
    // surfaces).
    bool sky = true;
    // "max_light_aperture_deg": an extracted light's shadow cone is as wide as the region of sky it stands
    // for (full apex angle, degrees), at most this.
    float maxLightApertureDeg = 30.0f;

    bool operator==(const EnvironmentOptions&) const = default;
};

// The "auto" pixel strides: these at a 640x480 image, scaled with its smaller side (so that an image samples
// its surfaces alike at any size) and rounded down to a power of two, at least 1.
inline constexpr int kAutoDiffuseStride = 8, kAutoRelightDiffuseStride = 16;
// Shadows of point, spot and directional lights; the area lights' direct light by rays on rendered surfaces
// (noisier: many directions, few rays each) at twice their stride, so that the filter averages more samples.
// Relit, the environment's rays sample the objects' cone of directions too (traceEnvironmentRays), and the
// contact shadow under an object is sharper than the filter's reach at 4: 2 like the shadows.
inline constexpr int kAutoShadowStride = 1, kAutoRelightShadowStride = 2;
inline constexpr int kAutoAreaLightStride = 2, kAutoRelightAreaLightStride = 2;
inline constexpr int kAutoRelightSpecularStride = 4;
// The stride an option (0: "auto", with `autoStride` at 640x480) gives for a width x height image.
// The "auto" RSM resolution. A point or spot light's map: kAutoRsmTexelsPerVoxel texels per voxel along the
// volume's side, a power of two in [kAutoRsmMinResolution, kAutoRsmMaxResolution] (512 at 128^3 and above,
// 128 at 32^3). A directional light's map is orthographic over the whole region, with fewer texels per voxel,
// and the injection is short of light with fewer still (field photo at 32^3: delta_rel_error 0.250 at 512,
// 0.363 at 128): kAutoRsmMaxResolution. Among several lights, each takes its ceiling times the square root of
// its share of the brightest light's irradiance in the volume (the split of a texel budget that minimizes
// the sum of the lights' injection noise), rounded to the nearest power of two, at least the ceiling /
// kAutoRsmMinShare.
inline constexpr int kAutoRsmTexelsPerVoxel = 4, kAutoRsmMinResolution = 64, kAutoRsmMaxResolution = 512;
inline constexpr int kAutoRsmMinShare = 4;

// The largest RSM face resolution options.rsm.resolution gives a light (the given one, or "auto"'s ceiling
// for options.volume.resolution `volumeResolution`, point and spot lights or directional ones).
inline int rsmResolutionCeiling(int option, int volumeResolution, bool directional) {
    if (option > 0) return option;
    if (directional) return kAutoRsmMaxResolution;
    int resolution = kAutoRsmMinResolution;
    while (resolution * 2 <= std::min(kAutoRsmTexelsPerVoxel * volumeResolution, kAutoRsmMaxResolution))
        resolution *= 2;
    return resolution;
}

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
