// The pipeline of §3 / Fig. 2, stage by stage. Each stage is a function of explicit inputs to outputs, in its
// own file pair; this file only wires them up and times them.
#include "deltagi/renderer.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <optional>

#include "core/environment_sampling.h"
#include "core/parallel.h"
#include "core/ray_scene.h"
#include "deltagi/scene_io.h"
#include "pipeline/area_light_rays.h"
#include "pipeline/bounce_light.h"
#include "pipeline/composite.h"
#include "pipeline/cone_jobs.h"
#include "pipeline/denoise.h"
#include "pipeline/gbuffer.h"
#include "pipeline/inject.h"
#include "pipeline/mipmap.h"
#include "pipeline/object_bounce_rays.h"
#include "pipeline/object_volumes.h"
#include "pipeline/reflective_shadow_map.h"
#include "pipeline/shading.h"
#include "pipeline/shadow_rays.h"
#include "pipeline/sky_light.h"
#include "pipeline/stage_timer.h"
#include "pipeline/temporal_reuse.h"
#include "pipeline/voxelize.h"

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace deltagi {

namespace {

Bounds3f boundsOf(std::span<const TriangleMesh> meshes) {
    Bounds3f b;
    for (const TriangleMesh& m : meshes) b.extend(m.bounds());
    return b;
}

VolumeRegion cubeAround(const Bounds3f& b, float scale, int resolution) {
    VolumeRegion r;
    r.size = std::max(b.maxExtent() * scale, 1e-6f);
    r.origin = b.center() - glm::vec3(0.5f * r.size);
    r.resolution = resolution;
    return r;
}

Image toImage(std::span<const glm::vec3> pixels, int width, int height) {
    Image image(width, height, 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) image.setRgb(x, y, pixels[static_cast<size_t>(y) * width + x]);
    sanitize(image);
    return image;
}

// One map per light, each at its resolution (rsmResolutions).
std::vector<ReflectiveShadowMap> renderRsms(const RayScene& rays, std::span<const Light> lights,
                                            const VolumeRegion& region, const Options& options,
                                            glm::vec3 viewpoint) {
    const std::vector<int> resolutions = rsmResolutions(options, lights, region);
    std::vector<ReflectiveShadowMap> rsms;
    for (size_t l = 0; l < lights.size(); ++l)
        rsms.push_back(renderReflectiveShadowMap(rays, lights[l], region, resolutions[l], viewpoint));
    return rsms;
}

// The z depth (along the camera's axis) of the surface at each pixel's centre: the object's where it covers
// the pixel, else the real one's; infinity where there is none.
Image depthImage(const Camera& camera, const GBuffer& gbuffer, std::span<const SurfacePoint> real) {
    Image depth(camera.width, camera.height, 1, std::numeric_limits<float>::infinity());
    const glm::vec3 eye = camera.position();
    const glm::vec3 axis = glm::normalize(camera.rayDirection(camera.cx, camera.cy));
    parallelFor(0, camera.height, 8, [&](int64_t y) {
        for (int x = 0; x < camera.width; ++x) {
            const size_t i = static_cast<size_t>(y) * camera.width + x;
            const bool object =
                i < gbuffer.coverage.size() && gbuffer.coverage[i] > 0.0f && gbuffer.object[i].valid();
            const SurfacePoint& p = object ? gbuffer.object[i] : real[i];
            if (p.valid()) depth.at(x, static_cast<int>(y), 0) = glm::dot(p.position - eye, axis);
        }
    });
    return depth;
}

// Whether the environment map lights the scene through shadow rays (then its extracted lights only drive the
// reflective shadow maps, and its sky is not gathered through the cones).
bool environmentByRays(const Scene& scene) {
    return scene.environment && scene.options.shadow.method == "rays";
}

// The lights whose direct light is shaded with their shadows: the scene's, without the environment's lights
// when the map is sampled by rays.
std::vector<Light> directLights(const Scene& scene) {
    std::vector<Light> lights = scene.lights;
    if (environmentByRays(scene)) std::erase_if(lights, [](const Light& l) { return l.fromEnvironment; });
    return lights;
}

// The lights whose reflective shadow maps light the volumes: the scene's, and with area lights by rays the
// stand-ins of its emitting surfaces (their direct light comes from traceAreaLightRays, not the volumes).
std::vector<Light> rsmLights(const Scene& scene, const RayScene& realOnly) {
    std::vector<Light> lights = scene.lights;
    if (scene.options.shadow.method == "rays") {
        const std::vector<Light> standIns = emitterStandInLights(scene, realOnly);
        lights.insert(lights.end(), standIns.begin(), standIns.end());
    }
    return lights;
}

// The static half of a frame: what depends only on the real scene, its lights, the camera, the options and
// the volume region. Built lazily, kept by FrameRenderer while its signature and region are unchanged. Of it,
// the camera-space work (the G-buffer, the background, the per-pixel caches) is redone when the camera
// changes; the world-space work (BVHs, voxels, RSMs, injected and bounced light, the objects' volumes) is
// kept while the camera stays on the same side of every real surface (keepWorldWork).
struct StaticWork {
    uint64_t signature = 0;        // of the world: everything but the camera (worldSignature)
    uint64_t cameraSignature = 0;  // of the camera
    // The camera is the last frame's: the filter's weights over the real surfaces are worth keeping (a
    // camera that moves every frame would build them for one use; its passes compute only those they need).
    bool cameraSteady = false;
    std::unique_ptr<RayScene> realOnly;
    std::unique_ptr<RayScene> objects;       // the virtual objects' layer over realOnly, refit as they move
    std::vector<SurfacePoint> realSurfaces;  // the G-buffer's real half, when realSurfacesMade
    bool realSurfacesMade = false;
    std::optional<Image> background;  // the real scene rendered alone (no photo)
    // Over `region`:
    std::optional<VolumeRegion> region;
    std::optional<VoxelGeometry> sceneGeometry;
    std::optional<MipVolume> sceneVisibility;
    SceneOcclusionCache relitShadows;             // the scene's share of the real surfaces' shadow cones
    std::array<InterpolationPlan, 5> relitPlans;  // the relit passes' filter weights over realSurfaces
    GBuffer gbuffer;                              // the objects' half, redone where they were and are
    // realSurfaces without the pixels the objects cover (the last frame's `hidden`).
    std::vector<SurfacePoint> relitSurfaces;
    std::vector<uint32_t> hidden;
    std::optional<std::vector<ReflectiveShadowMap>> sceneRsms;  // of the scene alone, one per light
    std::optional<Grid3> sceneLight;                            // injected from sceneRsms, plus sceneBounce
    // The further bounces of the scene's light (options.render.light_bounces).
    std::optional<Grid3> sceneBounce;
    // The environment map's sampler (its CDFs), when its light is traced by rays.
    std::unique_ptr<EnvironmentSampler> environmentSampler;
    // The objects' volumes of the last frame, updated where the objects changed them.
    std::optional<ObjectVolumes> objectVolumes;
    // The viewpoint the world-space work holds for, and the sides of the real surfaces it is on there: the
    // RSMs' (rsmViewSides) and the further bounces' (bounceViewSides).
    std::optional<glm::vec3> viewpoint;
    std::vector<int8_t> rsmSides;
    std::vector<bool> bounceSides;
};

// The point whose side of the real surfaces the volumes light (options.volume.viewpoint; the camera's).
glm::vec3 viewpointOf(const Scene& scene) {
    return scene.options.volume.viewpoint.value_or(scene.camera.position());
}

// Forgets what depends on the camera: the real G-buffer and what is made over its pixels.
// The large buffers keep their memory for the next camera's (14 MiB each at 640 x 480: allocated afresh,
// their pages would be faulted in every frame).
void forgetCameraWork(StaticWork& kept) {
    kept.realSurfacesMade = false;
    kept.background.reset();
    kept.relitShadows = {};
    for (InterpolationPlan& plan : kept.relitPlans) {
        plan.stride = 0;
        plan.weights.clear();
    }
    kept.gbuffer.object.clear();  // renderObjectSurfaces starts afresh
    kept.gbuffer.coverage.clear();
    kept.relitSurfaces.clear();
    kept.hidden.clear();
}

// Keeps the world-space work for the camera at `viewpoint` where it is the same as made afresh: the RSMs keep
// a real surface's texels on the camera's side only, and the further bounces gather on the camera's side of
// each voxel. Where the camera crossed a surface's plane, they are redone (and what is made from them).
void keepWorldWork(const Scene& scene, glm::vec3 viewpoint, StaticWork& kept) {
    if (kept.viewpoint == viewpoint) return;
    kept.viewpoint = viewpoint;
    if (kept.sceneRsms) {
        const std::vector<int8_t> sides = rsmViewSides(scene.real, viewpoint);
        if (sides != kept.rsmSides || std::find(sides.begin(), sides.end(), 0) != sides.end()) {
            kept.sceneRsms.reset();
            kept.sceneLight.reset();
            kept.sceneBounce.reset();
            kept.objectVolumes.reset();
            return;
        }
    }
    if (kept.sceneBounce && bounceViewSides(*kept.sceneVisibility, viewpoint) != kept.bounceSides) {
        kept.sceneLight.reset();
        kept.sceneBounce.reset();
        kept.objectVolumes.reset();
    }
}

bool sameRegion(const VolumeRegion& a, const VolumeRegion& b) {
    return a.origin == b.origin && a.size == b.size && a.resolution == b.resolution;
}

// XXH3 (xxHash, Debian's libxxhash-dev, inlined) over bytes: the world signature reads every byte of the real
// meshes each frame, and a byte-wise FNV-1a took about 4 cycles a byte (40 ms a frame for a reconstruction
// of a million triangles).
class Hasher {
  public:
    Hasher() { XXH3_64bits_reset(&state_); }
    Hasher(const Hasher&) = delete;
    Hasher& operator=(const Hasher&) = delete;
    void bytes(const void* data, size_t size) { XXH3_64bits_update(&state_, data, size); }
    uint64_t value() const { return XXH3_64bits_digest(&state_); }

  private:
    XXH3_state_t state_;
};

uint64_t cameraSignature(const Camera& camera) {
    Hasher h;
    h.bytes(&camera, sizeof(camera));
    return h.value();
}

// A hash of everything the static half depends on but the camera. The scene's and its real meshes' addresses
// are part of it: the kept BVH and surfaces point into them.
uint64_t worldSignature(const Scene& scene) {
    Hasher h;
    auto bytes = [&](const void* data, size_t size) { h.bytes(data, size); };
    auto value = [&](const auto& v) { bytes(&v, sizeof(v)); };
    value(&scene);
    value(scene.real.data());
    value(scene.real.size());
    for (const TriangleMesh& m : scene.real) {
        value(m.positions.data());
        bytes(m.positions.data(), m.positions.size() * sizeof(glm::vec3));
        bytes(m.normals.data(), m.normals.size() * sizeof(glm::vec3));
        bytes(m.triangles.data(), m.triangles.size() * sizeof(glm::uvec3));
        bytes(m.uvs.data(), m.uvs.size() * sizeof(glm::vec2));
        bytes(m.uvs1.data(), m.uvs1.size() * sizeof(glm::vec2));
        bytes(m.tangents.data(), m.tangents.size() * sizeof(glm::vec4));
        bytes(m.colors.data(), m.colors.size() * sizeof(glm::vec3));
        visitMaterialFields(m.material, value);
    }
    for (const Light& l : scene.lights) {  // field by field: Light has padding after its bool
        value(l.type);
        value(l.color);
        value(l.intensity);
        value(l.position);
        value(l.direction);
        value(l.innerAngleDeg);
        value(l.outerAngleDeg);
        value(l.radius);
        value(l.fromEnvironment);
        value(l.angularRadius);
    }
    // The environment lights the background rendered without a photo (its sky term).
    value(scene.environment ? scene.environment->radiance.data().data() : nullptr);
    if (scene.environment) value(scene.environment->worldFromEnvironment);
    value(scene.background.has_value());
    const std::string options = optionsToJson(scene.options).dump();
    bytes(options.data(), options.size());
    return h.value();
}

// Makes the pixels the objects cover fully invalid in `points`, listing them in `hidden`.
void hideCovered(const GBuffer& gbuffer, std::vector<SurfacePoint>& points, std::vector<uint32_t>& hidden) {
    const PixelRect& w = gbuffer.written;
    // The records cleared in parallel (96 bytes each), the list made in pixel order.
    parallelFor(w.y0, w.y1, 8, [&](int64_t y) {
        for (int x = w.x0; x < w.x1; ++x) {
            const size_t i = static_cast<size_t>(y) * gbuffer.width + x;
            if (gbuffer.coverage[i] >= 1.0f) points[i] = {};
        }
    });
    for (int y = w.y0; y < w.y1; ++y)
        for (int x = w.x0; x < w.x1; ++x) {
            const size_t i = static_cast<size_t>(y) * gbuffer.width + x;
            if (gbuffer.coverage[i] >= 1.0f) hidden.push_back(static_cast<uint32_t>(i));
        }
}

// The real surfaces that show through (coverage < 1), to be relit: `real` without the pixels the objects
// cover, kept in `kept` and changed only where the covered pixels were or are.
const std::vector<SurfacePoint>& hideCoveredSurfaces(const std::vector<SurfacePoint>& real,
                                                     const GBuffer& gbuffer, StaticWork& kept) {
    std::vector<SurfacePoint>& points = kept.relitSurfaces;
    if (points.size() != real.size()) {  // a new camera: 14 MiB at 640 x 480, copied in parallel
        points.resize(real.size());
        constexpr int64_t kChunk = 1 << 14;
        parallelFor(0, (static_cast<int64_t>(real.size()) + kChunk - 1) / kChunk, 1, [&](int64_t c) {
            const size_t begin = static_cast<size_t>(c * kChunk);
            const size_t end = std::min(real.size(), begin + static_cast<size_t>(kChunk));
            std::copy(real.begin() + begin, real.begin() + end, points.begin() + begin);
        });
        kept.hidden.clear();
    }
    for (uint32_t i : kept.hidden) points[i] = real[i];
    kept.hidden.clear();
    hideCovered(gbuffer, points, kept.hidden);
    return points;
}

// hideCoveredSurfaces for a camera that moved: the real surfaces rendered straight into the relit ones (the
// whole real G-buffer is needed only by a steady camera's kept filter weights, the depth layer and a rendered
// background; a camera that stays computes it next frame, and the relit surfaces stay valid).
const std::vector<SurfacePoint>& renderRelitSurfaces(const Camera& camera, const RayScene& realOnly,
                                                     const GBuffer& gbuffer, StaticWork& kept) {
    std::vector<SurfacePoint>& points = kept.relitSurfaces;
    renderRealSurfaces(camera, realOnly, points);
    kept.hidden.clear();
    hideCovered(gbuffer, points, kept.hidden);
    return points;
}

// Stages 1-4 (§3.2): the two visibility volumes, the full light volume and the delta volume, mip-mapped. The
// scene's share comes from `kept` when it is there; the objects' volumes are kept there too and updated
// where the objects changed them since the last frame (ObjectVolumes).
struct DgiVolumes {
    const MipVolume *sceneVisibility, *objectVisibility, *fullLight, *deltaLight, *objectLight;
};

DgiVolumes buildVolumes(const Scene& scene, std::span<const Light> lights, const VolumeRegion& region,
                        const RayScene& realOnly, const RayScene& all, StaticWork& kept, StageTimer& timer) {
    // With area lights by rays, emitting surfaces light the volumes through their stand-ins' RSMs instead.
    const bool withEmission = scene.options.shadow.method != "rays";
    ObjectVolumes& objects = kept.objectVolumes ? *kept.objectVolumes : kept.objectVolumes.emplace();
    // 1. Voxelization: one visibility volume for the reconstruction, one for the virtual objects.
    const int bounces = scene.options.render.lightBounces - 1;
    if (!kept.sceneGeometry) kept.sceneGeometry = voxelize(scene.real, region, withEmission, bounces > 0);
    objects.voxelize(scene.virtuals, region, withEmission, bounces > 0);
    timer.lap("voxelize");
    // 2. Reflective shadow maps: scene alone, and scene + objects (the texels that can see the objects traced
    // again).
    if (!kept.sceneRsms) {
        kept.sceneRsms = renderRsms(realOnly, lights, region, scene.options, viewpointOf(scene));
        kept.rsmSides = rsmViewSides(scene.real, viewpointOf(scene));
    }
    std::vector<RsmUpdate> updates;
    const Bounds3f objectBounds = boundsOf(scene.virtuals);
    for (size_t l = 0; l < lights.size(); ++l)
        updates.push_back(
            traceRsmUpdate((*kept.sceneRsms)[l], all, lights[l], region, objectBounds, viewpointOf(scene)));
    timer.lap("rsm");
    // 3. Light injection: the full light volume and the delta volume = full - scene alone.
    const VoxelGeometry* sceneAlone[] = {&*kept.sceneGeometry};
    if (!kept.sceneLight) {
        kept.sceneLight = injectLight(*kept.sceneRsms, region, sceneAlone);
        if (bounces > 0) {
            if (!kept.sceneVisibility)
                kept.sceneVisibility = buildMipChain(region, kept.sceneGeometry->visibility.clone());
            kept.sceneBounce = bounceLight(*kept.sceneLight, *kept.sceneGeometry, *kept.sceneVisibility,
                                           scene.options, bounces, viewpointOf(scene));
            kept.bounceSides = bounceViewSides(*kept.sceneVisibility, viewpointOf(scene));
            for (size_t i = 0; i < kept.sceneLight->size(); ++i)
                (*kept.sceneLight)[i] += (*kept.sceneBounce)[i];
        }
    }
    objects.inject({*kept.sceneGeometry, *kept.sceneRsms, *kept.sceneLight,
                    kept.sceneBounce ? &*kept.sceneBounce : nullptr},
                   updates);
    timer.lap("inject");
    // 4. Mipmaps of all four volumes.
    if (!kept.sceneVisibility)
        kept.sceneVisibility = buildMipChain(region, kept.sceneGeometry->visibility.clone());
    // With further bounces the objects reflect the room's light they receive too.
    objects.mipmap(bounces > 0 ? &*kept.sceneVisibility : nullptr, &scene.options, &all);
    timer.lap("mipmap");
    return {&*kept.sceneVisibility, &objects.objectVisibility(), &objects.fullLight(), &objects.deltaLight(),
            &objects.objectLight()};
}

// The background without a photo takes this many times the shadow rays of options.shadow.ray_samples and
// area_ray_samples (at most 256).
constexpr int kBackgroundRayFactor = 16;
// ... and traces its diffuse cones at options.diffuse.pixel_stride divided by this (at least 1).
constexpr int kBackgroundStrideDivisor = 4;

// The real scene alone, rendered with regular voxel cone tracing over its own bounds: the background when the
// scene has no photo (the "already lit virtual scene" of the paper's Fig. 3). Its stages are timed together.
Image renderRealScene(const Scene& scene, const RayScene& realOnly, std::span<const SurfacePoint> points) {
    const Options& o = scene.options;
    // One voxel of margin on each side so that surfaces on the bounds are inside.
    const float margin = 1.0f + 2.0f / static_cast<float>(o.volume.resolution);
    const VolumeRegion region = cubeAround(boundsOf(scene.real), margin, o.volume.resolution);
    const bool areaRays = o.shadow.method == "rays";
    const int bounces = o.render.lightBounces - 1;
    VoxelGeometry geometry = voxelize(scene.real, region, !areaRays, bounces > 0);
    const std::vector<ReflectiveShadowMap> rsms =
        renderRsms(realOnly, rsmLights(scene, realOnly), region, o, viewpointOf(scene));
    const AreaLights emitters(scene, SceneContent::RealOnly);
    std::optional<EnvironmentSampler> environment;
    if (environmentByRays(scene)) environment.emplace(*scene.environment);
    const std::vector<Light> shaded = directLights(scene);
    const VoxelGeometry* geometries[] = {&geometry};
    const MipVolume visibility = buildMipChain(region, geometry.visibility.clone());
    Grid3 direct = injectLight(rsms, region, geometries);
    if (bounces > 0) {
        const Grid3 bounced = bounceLight(direct, geometry, visibility, o, bounces, viewpointOf(scene));
        for (size_t i = 0; i < direct.size(); ++i) direct[i] += bounced[i];
    }
    const MipVolume light = buildMipChain(region, std::move(direct));
    const ConeJob job{points,
                      &light,
                      {&visibility, nullptr, VisibilityVolumes::Self::Scene},
                      o.render.indirect,
                      ShadowMode::SceneOnly,
                      {0, 0, scene.camera.width, scene.camera.height},
                      nullptr,
                      nullptr,
                      {},
                      {&realOnly, nullptr, {}},
                      nullptr,
                      nullptr,
                      areaRays ? &emitters : nullptr,
                      environment ? &*environment : nullptr};
    std::vector<StageTiming> ignored;
    StageTimer quiet(ignored, {});
    // Rendered once per real scene: 16 times the shadow rays (the penumbrae of 4 were blotchy where the
    // filter spreads them over the whole image, with no photo to hide them).
    Options backgroundOptions = o;
    backgroundOptions.shadow.raySamples = std::min(kBackgroundRayFactor * o.shadow.raySamples, 256);
    backgroundOptions.shadow.areaRaySamples = std::min(kBackgroundRayFactor * o.shadow.areaRaySamples, 256);
    backgroundOptions.diffuse.pixelStride = std::max(
        1,
        pixelStrideFor(o.diffuse.pixelStride, kAutoDiffuseStride, scene.camera.width, scene.camera.height) /
            kBackgroundStrideDivisor);
    ConeResults cones = std::move(traceCones({&job, 1}, scene, backgroundOptions, shaded, quiet)[0]);
    std::vector<glm::vec3> radiance =
        combineLighting(points, shaded, cones.shadows, ShadowMode::SceneOnly, cones.diffuse, cones.specular);
    addInto(radiance, std::move(cones.areaLight));
    return toImage(radiance, scene.camera.width, scene.camera.height);
}

// One frame; `kept` holds the static half from an earlier frame of the same scene, or nothing.
RenderOutput renderFrame(const Scene& scene, StaticWork& kept, const StageCallback& onStage,
                         TemporalReuse* temporal = nullptr) {
    RenderOutput out;
    const auto start = std::chrono::steady_clock::now();
    StageTimer timer(out.timings, onStage);
    const Options& o = scene.options;
    const Camera& camera = scene.camera;
    const VolumeRegion region = volumeRegion(scene);
    if (kept.region && !sameRegion(*kept.region, region)) {
        kept.sceneGeometry.reset();
        kept.sceneVisibility.reset();
        kept.relitShadows = {};
        kept.sceneRsms.reset();
        kept.sceneLight.reset();
        kept.sceneBounce.reset();
        kept.objectVolumes.reset();
    }
    kept.region = region;

    if (!kept.realOnly) kept.realOnly = std::make_unique<RayScene>(scene, SceneContent::RealOnly);
    const RayScene& realOnly = *kept.realOnly;
    // The virtual objects get their own BVH, layered over the reconstruction's; refit when they only moved.
    if (!scene.virtuals.empty() && !(kept.objects && kept.objects->refit(scene)))
        kept.objects = std::make_unique<RayScene>(scene, SceneContent::VirtualOnly, &realOnly);
    const RayScene* all = scene.virtuals.empty() ? nullptr : kept.objects.get();
    timer.lap("bvh");

    auto realSurfaces = [&]() -> const std::vector<SurfacePoint>& {
        if (!kept.realSurfacesMade) renderRealSurfaces(camera, realOnly, kept.realSurfaces);
        kept.realSurfacesMade = true;
        return kept.realSurfaces;
    };
    auto background = [&]() -> const Image& {
        if (scene.background) return *scene.background;
        if (!kept.background) kept.background = renderRealScene(scene, realOnly, realSurfaces());
        return *kept.background;
    };

    if (scene.virtuals.empty()) {
        // Nothing is added, so nothing changes: the composite is the background.
        out.background = background();
        timer.lap("background");
        out.composite = out.background;
        out.objectMask = Image(camera.width, camera.height, 1);
        out.delta = Image(camera.width, camera.height, 3);
        if (o.render.layers) {
            out.object = Image(camera.width, camera.height, 4);
            out.shadow = Image(camera.width, camera.height, 3);
            out.indirect = Image(camera.width, camera.height, 3);
            out.depth = depthImage(camera, GBuffer{}, realSurfaces());
        }
        out.totalMs =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        return out;
    }

    const std::vector<Light> lights = rsmLights(scene, realOnly);
    const DgiVolumes volumes = buildVolumes(scene, lights, region, realOnly, *all, kept, timer);

    // 5. G-buffer. Real surfaces are relit only where they show through (coverage < 1).
    GBuffer& gbuffer = kept.gbuffer;
    renderObjectSurfaces(camera, *all, boundsOf(scene.virtuals), o.render.samplesPerPixel, gbuffer);
    const bool wholeRealSurfaces = kept.cameraSteady || !scene.background || o.render.layers;
    const std::vector<SurfacePoint>& realPoints = wholeRealSurfaces
                                                      ? hideCoveredSurfaces(realSurfaces(), gbuffer, kept)
                                                      : renderRelitSurfaces(camera, realOnly, gbuffer, kept);
    timer.lap("gbuffer");

    // 6. Cone tracing (§3.3): virtual surfaces read the full light volume, real ones the delta volume; both
    // are occluded by both visibility volumes. Cones discount the back faces of their own surface's volume
    // only.
    const ShadowMode relightMode =
        o.render.doubleShadowFix ? ShadowMode::DeltaShadow : ShadowMode::DeltaSingleVisibility;
    // The pixels the objects' G-buffer was rendered over hold every virtual point; the real points differ
    // from the kept real surfaces only there, where the objects cover them.
    const PixelRect& objectPixels = gbuffer.written;
    if (kept.cameraSteady)
        for (InterpolationPlan& plan : kept.relitPlans) plan.surfaces = realSurfaces();
    const ShadowRayScenes shadowRays{&realOnly, all, boundsOf(scene.virtuals),
                                     objectSphereRadius(scene.virtuals)};
    // Emitting surfaces light the scene through shadow rays (with options.shadow.method "rays").
    const AreaLights emitters = o.shadow.method == "rays" ? AreaLights(scene, SceneContent::RealAndVirtual)
                                                          : AreaLights(Scene{}, SceneContent::RealOnly);
    // The environment map lights the scene through shadow rays too (with options.shadow.method "rays").
    if (environmentByRays(scene) && !kept.environmentSampler)
        kept.environmentSampler = std::make_unique<EnvironmentSampler>(*scene.environment);
    const EnvironmentSampler* environment =
        environmentByRays(scene) ? kept.environmentSampler.get() : nullptr;
    const std::vector<Light> direct = directLights(scene);
    const ConeJob jobs[] = {
        {gbuffer.object,
         volumes.fullLight,
         {volumes.sceneVisibility, volumes.objectVisibility, VisibilityVolumes::Self::Object},
         o.render.indirect,
         ShadowMode::Shaded,
         objectPixels,
         nullptr,
         nullptr,
         {},
         shadowRays,
         nullptr,
         nullptr,
         &emitters,
         environment,
         &gbuffer.objectSamples},
        {realPoints,
         volumes.deltaLight,
         {volumes.sceneVisibility, volumes.objectVisibility, VisibilityVolumes::Self::Scene},
         o.render.indirect && o.render.relightIndirect,
         relightMode,
         {0, 0, camera.width, camera.height},
         &kept.relitShadows,
         kept.cameraSteady ? &kept.relitPlans : nullptr,
         objectPixels,
         shadowRays,
         o.render.relightCones == "differential" ? volumes.fullLight : nullptr,
         volumes.objectLight,
         &emitters,
         environment}};
    std::vector<ConeResults> cones = traceCones(jobs, scene, o, direct, timer);
    ConeResults& object = cones[0];
    ConeResults& real = cones[1];

    // 7. Shading of virtual surfaces vs relighting of real ones (§3.3).
    auto objectRadiance =
        combineLighting(gbuffer.object, direct, object.shadows, ShadowMode::Shaded, object.diffuse,
                        object.specular, &objectPixels, camera.width, &gbuffer.objectSamples);
    // The real surfaces' change in its two parts, the direct light's (shadows) and the indirect light's: the
    // composite's layers.
    std::vector<glm::vec3> realIndirect;
    auto realShadow = combineLighting(realPoints, direct, real.shadows, relightMode, real.diffuse,
                                      real.specular, nullptr, 0, nullptr, &realIndirect);
    addInto(objectRadiance, std::move(object.areaLight));
    addInto(realShadow, std::move(real.areaLight));
    timer.lap("shading");

    // Beyond the paper: the frames before this one, reprojected, smooth over time the steps of the objects'
    // shading and of their shadows on real surfaces (FrameRenderer).
    if (temporal) {
        temporal->apply(o.render.temporalFrames, {&camera, scene.virtuals, &gbuffer, realPoints},
                        {objectRadiance, realShadow});
        timer.lap("temporal");
    }
    if (!o.render.layers) addInto(realShadow, std::move(realIndirect));  // one change, without the layers

    // The background: the photo, or the real scene rendered alone.
    out.background = background();
    timer.lap("background");

    // 8. Differential composite, and its layers.
    CompositeImages images =
        o.render.layers
            ? differentialComposite(out.background, gbuffer, objectRadiance, realShadow, realIndirect)
            : differentialComposite(out.background, gbuffer, objectRadiance, realShadow);
    out.composite = std::move(images.composite);
    out.objectMask = std::move(images.objectMask);
    out.delta = std::move(images.delta);
    out.object = std::move(images.object);
    out.shadow = std::move(images.shadow);
    out.indirect = std::move(images.indirect);
    if (o.render.layers) out.depth = depthImage(camera, gbuffer, realSurfaces());
    timer.lap("composite");
    out.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace

VolumeRegion volumeRegion(const Scene& scene) {
    const VolumeOptions& v = scene.options.volume;
    if (v.center && v.size) {
        return {*v.center - glm::vec3(0.5f * *v.size), *v.size, v.resolution};
    }
    if (!scene.virtuals.empty()) {
        const Bounds3f objects = boundsOf(scene.virtuals);
        VolumeRegion region = cubeAround(objects, v.extentScale, v.resolution);
        const Bounds3f real = boundsOf(scene.real);
        if (v.reachScale <= v.extentScale || real.empty()) return region;
        // Grow towards the real scene, at most to reach_scale times the objects' box.
        Bounds3f both = real;
        both.extend(objects);
        const float reach = std::max(objects.maxExtent(), 1e-6f) * v.reachScale;
        region.size = std::clamp(both.maxExtent() * (1.0f + 2.0f / static_cast<float>(v.resolution)),
                                 region.size, reach);
        // Around the objects, moved into the scene's bounds where the cube is smaller than them (the objects
        // stay inside it: the cube is at least extent_scale >= 1 times their box).
        glm::vec3 centre = objects.center();
        const float half = 0.5f * region.size;
        for (int a = 0; a < 3; ++a) {
            if (both.max[a] - both.min[a] <= region.size)
                centre[a] = 0.5f * (both.min[a] + both.max[a]);
            else
                centre[a] = std::clamp(centre[a], both.min[a] + half, both.max[a] - half);
            centre[a] = std::clamp(centre[a], objects.max[a] - half, objects.min[a] + half);
        }
        region.origin = centre - glm::vec3(half);
        return region;
    }
    return cubeAround(boundsOf(scene.real), 1.0f + 2.0f / static_cast<float>(v.resolution), v.resolution);
}

std::vector<ImageLayer> compositingLayers(const RenderOutput& output) {
    const std::vector<std::string> rgb = {"R", "G", "B"};
    return {{"composite", &output.composite, rgb},
            {"background", &output.background, rgb},
            {"object", &output.object, {"R", "G", "B", "A"}},
            {"shadow", &output.shadow, rgb},
            {"indirect", &output.indirect, rgb},
            {"delta", &output.delta, rgb},
            {"depth", &output.depth, {"Z"}}};
}

RenderOutput render(const Scene& scene, const StageCallback& onStage) {
    checkFrame(scene);
    StaticWork fresh;
    return renderFrame(scene, fresh, onStage);
}

struct FrameRenderer::State {
    StaticWork kept;
    KeptWork lastKept;
    TemporalReuse temporal;
};

FrameRenderer::FrameRenderer() : state_(std::make_unique<State>()) {}
FrameRenderer::~FrameRenderer() = default;

void FrameRenderer::clear() {
    state_->kept = StaticWork{};
    state_->temporal.clear();
}

void FrameRenderer::clearHistory() {
    state_->temporal.clear();
}

FrameRenderer::KeptWork FrameRenderer::lastFrameKept() const {
    return state_->lastKept;
}

RenderOutput FrameRenderer::render(const Scene& scene, const StageCallback& onStage) {
    checkFrame(scene);
    StaticWork& kept = state_->kept;
    const uint64_t world = worldSignature(scene);
    if (world != kept.signature) {
        kept = StaticWork{};
        kept.signature = world;
        state_->temporal.clear();  // frames of another scene, lights or options
    }
    const uint64_t camera = cameraSignature(scene.camera);
    state_->lastKept.camera = camera == kept.cameraSignature;
    kept.cameraSteady = state_->lastKept.camera;
    if (!state_->lastKept.camera) {
        forgetCameraWork(kept);
        kept.cameraSignature = camera;
    }
    keepWorldWork(scene, viewpointOf(scene), kept);
    state_->lastKept.world = kept.sceneRsms.has_value();
    return renderFrame(scene, kept, onStage, &state_->temporal);
}

}  // namespace deltagi
