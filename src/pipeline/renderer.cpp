// The pipeline of §3 / Fig. 2, stage by stage. Each stage is a function of explicit inputs to outputs, in its
// own file pair; this file only wires them up and times them.
#include "deltagi/renderer.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <limits>
#include <optional>

#include "core/environment_sampling.h"
#include "core/parallel.h"
#include "core/ray_scene.h"
#include "pipeline/area_light_rays.h"
#include "pipeline/bounce_light.h"
#include "pipeline/composite.h"
#include "pipeline/cone_jobs.h"
#include "pipeline/denoise.h"
#include "pipeline/frame_cache.h"
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

// One map per light, each at its resolution (rsmResolutions); `kept(light, resolution)` gives one made
// before, if it has it.
using KeptRsm = std::function<std::optional<ReflectiveShadowMap>(const Light&, int)>;
std::vector<ReflectiveShadowMap> renderRsms(const RayScene& rays, std::span<const Light> lights,
                                            const VolumeRegion& region, const Options& options,
                                            glm::vec3 viewpoint, const KeptRsm& kept = {}) {
    const std::vector<int> resolutions = rsmResolutions(options, lights, region);
    std::vector<ReflectiveShadowMap> rsms;
    for (size_t l = 0; l < lights.size(); ++l) {
        std::optional<ReflectiveShadowMap> rsm = kept ? kept(lights[l], resolutions[l]) : std::nullopt;
        rsms.push_back(rsm ? std::move(*rsm)
                           : renderReflectiveShadowMap(rays, lights[l], region, resolutions[l], viewpoint));
    }
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
    return scene.environment && scene.options.shadow.method == ShadowMethod::Rays;
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
    if (scene.options.shadow.method == ShadowMethod::Rays) {
        const std::vector<Light> standIns = emitterStandInLights(scene, realOnly);
        lights.insert(lights.end(), standIns.begin(), standIns.end());
    }
    return lights;
}

// Makes the pixels the objects cover fully invalid in `points`, listing them in `hidden`.
void hideCovered(const GBuffer& gbuffer, SurfacePoints& points, std::vector<uint32_t>& hidden) {
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
const SurfacePoints& hideCoveredSurfaces(const SurfacePoints& real, const GBuffer& gbuffer, ViewWork& kept) {
    SurfacePoints& points = kept.relitSurfaces;
    if (!kept.relitSurfacesMade || points.size() != real.size()) {  // a new camera: copied in parallel
        points.resize(real.size());
        kept.relitSurfacesMade = true;
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
const SurfacePoints& renderRelitSurfaces(const Camera& camera, const RayScene& realOnly,
                                         const GBuffer& gbuffer, ViewWork& kept) {
    SurfacePoints& points = kept.relitSurfaces;
    renderRealSurfaces(camera, realOnly, points);
    kept.relitSurfacesMade = true;
    kept.hidden.clear();
    hideCovered(gbuffer, points, kept.hidden);
    return points;
}

// Stages 1-4 (§3.2): the two visibility volumes, the full light volume and the delta volume, mip-mapped. The
// scene's share comes from `cache` when it is there; the objects' volumes are kept there too and updated
// where the objects changed them since the last frame (ObjectVolumes).
struct DgiVolumes {
    const MipVolume *sceneVisibility, *objectVisibility, *fullLight, *deltaLight, *objectLight, *roomChange;
};

DgiVolumes buildVolumes(const Scene& scene, std::span<const Light> lights, const VolumeRegion& region,
                        const RayScene& realOnly, const RayScene& all, const ShadowRayScenes& objectRays,
                        FrameCache& cache, StageTimer& timer) {
    VoxelWork& real = cache.voxels.work;
    LightWork& light = cache.light.work;
    const glm::vec3 viewpoint = viewpointOf(scene);
    // With area lights by rays, emitting surfaces light the volumes through their stand-ins' RSMs instead.
    const bool withEmission = scene.options.shadow.method != ShadowMethod::Rays;
    std::optional<ObjectVolumes>& keptObjects = cache.objectVolumes.work.volumes;
    ObjectVolumes& objects = keptObjects ? *keptObjects : keptObjects.emplace();
    // 1. Voxelization: one visibility volume for the reconstruction, one for the virtual objects.
    const int bounces = scene.options.render.lightBounces - 1;
    // The real scene's voxels, packed: its visibility's level 0 goes straight to its mip chain.
    if (!real.geometry) {
        real.geometry = voxelizePacked(scene.real, region, withEmission, bounces > 0);
        real.visibility = buildMipChain(region, std::move(real.geometry->packedVisibility));
    }
    objects.voxelize(scene.virtuals, region, withEmission, bounces > 0, cache.kept().objects);
    timer.lap("voxelize");
    // 2. Reflective shadow maps: scene alone, and scene + objects (the texels that can see the objects traced
    // again).
    // The injected grid of the light before, recycled below when it was made over these voxels.
    std::unique_ptr<RecycledGrid> recycled;
    if (light.spare.voxels == cache.voxels.version) recycled = std::move(light.spare.injected);
    if (!light.rsms) {
        light.rsmSides = rsmViewSides(scene.real, viewpoint);
        light.rsmsKept = 0;
        light.rsms =
            renderRsms(realOnly, lights, region, scene.options, viewpoint, [&](const Light& l, int res) {
                std::optional<ReflectiveShadowMap> kept =
                    light.spareRsm(l, res, cache.voxels.version, light.rsmSides);
                light.rsmsKept += kept.has_value();
                return kept;
            });
        light.rsmLights.assign(lights.begin(), lights.end());
        light.rsmVoxels = cache.voxels.version;
        light.spare = {};
    }
    std::vector<RsmUpdate> updates;
    for (size_t l = 0; l < lights.size(); ++l)
        updates.push_back(
            traceRsmUpdate((*light.rsms)[l], all, lights[l], region, objectRays.objectBounds, viewpoint));
    timer.lap("rsm");
    const MipVolume& sceneVisibility = *real.visibility;
    // 3. Light injection: the full light volume and the delta volume = full - scene alone.
    const VoxelGeometry* sceneAlone[] = {&*real.geometry};
    if (!light.injected) {
        InjectedVoxels written;
        light.injected = injectLight(*light.rsms, region, sceneAlone, &written, recycled.get());
        recycled.reset();
        if (bounces > 0) {
            timer.lap("inject");
            light.bounce = bounceLight(*light.injected, *real.geometry, sceneVisibility, scene.options,
                                       bounces, viewpoint, &realOnly, &written);
            light.bounceSides = bounceViewSides(sceneVisibility, viewpoint);
            addBounce(*light.injected, *light.bounce, *real.geometry);
            timer.lap("bounce");
        }
        // The bounces changed the surface voxels alone: the injection's voxels still hold every non-zero one.
        light.injectedBounds = injectedBounds(*light.injected, sceneAlone, written);
        light.injectedVoxels = std::move(written);
    }
    objects.inject(
        {*real.geometry, *light.rsms, *light.injected, light.bounce ? &*light.bounce : nullptr,
         cache.light.version, light.injectedBounds ? &*light.injectedBounds : nullptr, &light.injectedVoxels},
        updates);
    timer.lap("inject");
    // 4. Mipmaps of all four volumes. With further bounces the objects reflect the room's light they receive
    // too.
    const RoomChangeInputs room{*real.geometry, objectRays};
    objects.mipmap(bounces > 0 ? &sceneVisibility : nullptr, &scene.options, &all, &room);
    timer.lap("mipmap");
    return {&sceneVisibility,      &objects.objectVisibility(), &objects.fullLight(),
            &objects.deltaLight(), &objects.objectLight(),      &objects.roomChange()};
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
    const bool areaRays = o.shadow.method == ShadowMethod::Rays;
    const int bounces = o.render.lightBounces - 1;
    VoxelGeometry geometry = voxelizePacked(scene.real, region, !areaRays, bounces > 0);
    const std::vector<ReflectiveShadowMap> rsms =
        renderRsms(realOnly, rsmLights(scene, realOnly), region, o, viewpointOf(scene));
    const AreaLights emitters(scene, SceneContent::RealOnly);
    std::optional<EnvironmentSampler> environment;
    if (environmentByRays(scene)) environment.emplace(*scene.environment);
    const std::vector<Light> shaded = directLights(scene);
    const VoxelGeometry* geometries[] = {&geometry};
    const MipVolume visibility = buildMipChain(region, std::move(geometry.packedVisibility));
    InjectedVoxels written;
    Grid3 direct = injectLight(rsms, region, geometries, &written);
    if (bounces > 0) {
        const SurfaceRadiance bounced =
            bounceLight(direct, geometry, visibility, o, bounces, viewpointOf(scene), &realOnly, &written);
        addBounce(direct, bounced, geometry);
    }
    const MipVolume light = buildMipChain(region, std::move(direct));
    const ConeJob job{.points = points,
                      .light = &light,
                      .visibility = {&visibility, nullptr, VisibilityVolumes::Self::Scene},
                      .indirect = o.render.indirect,
                      .mode = ShadowMode::SceneOnly,
                      .bounds = {0, 0, scene.camera.width, scene.camera.height},
                      .rays = {&realOnly, nullptr, {}},
                      .emitters = areaRays ? &emitters : nullptr,
                      .environment = environment ? &*environment : nullptr};
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

// One frame; `cache` holds the work of earlier frames of the same scene that this frame's inputs keep
// (FrameCache::update), or nothing. A `still` (render(), FrameRenderer::renderStill) resolves the options'
// "auto" as a single render does (refineBudgetFor, objectGatherRaysFor); a session's frame keeps its time.
RenderOutput renderFrame(const Scene& scene, FrameCache& cache, const StageCallback& onStage, bool still,
                         TemporalReuse* temporal = nullptr) {
    RenderOutput out;
    const auto start = std::chrono::steady_clock::now();
    StageTimer timer(out.timings, onStage);
    const Options& o = scene.options;
    const Camera& camera = scene.camera;
    const VolumeRegion region = volumeRegion(scene);
    ViewWork& view = cache.view.work;

    std::unique_ptr<RayScene>& realRays = cache.world.work.realOnly;
    if (!realRays) realRays = std::make_unique<RayScene>(scene, SceneContent::RealOnly);
    const RayScene& realOnly = *realRays;
    // The virtual objects get their own BVH, layered over the reconstruction's; refit when they only moved,
    // kept when they did not.
    std::unique_ptr<RayScene>& objectRays = cache.objectRays.work.objects;
    if (!scene.virtuals.empty() && !(objectRays && (cache.kept().objects || objectRays->refit(scene))))
        objectRays = std::make_unique<RayScene>(scene, SceneContent::VirtualOnly, &realOnly);
    const RayScene* all = scene.virtuals.empty() ? nullptr : objectRays.get();
    timer.lap("bvh");

    auto realSurfaces = [&]() -> const SurfacePoints& {
        if (!view.realSurfacesMade) renderRealSurfaces(camera, realOnly, view.realSurfaces);
        view.realSurfacesMade = true;
        return view.realSurfaces;
    };
    auto background = [&]() -> const Image& {
        if (scene.background) return *scene.background;
        std::optional<Image>& rendered = cache.litView.work.background;
        if (!rendered) rendered = renderRealScene(scene, realOnly, realSurfaces());
        return *rendered;
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
    // The rays of the relit points and of the objects' change of the room towards the objects.
    const ShadowRayScenes shadowRays{&realOnly, all, boundsOf(scene.virtuals),
                                     objectSphereRadius(scene.virtuals)};
    const DgiVolumes volumes = buildVolumes(scene, lights, region, realOnly, *all, shadowRays, cache, timer);

    // 5. G-buffer. Real surfaces are relit only where they show through (coverage < 1).
    GBuffer& gbuffer = view.gbuffer;
    // A still resolves narrow glossy lobes' highlights finer than a session's frames (design.md, "Glossy
    // highlights narrower than a pixel").
    renderObjectSurfaces(camera, *all, boundsOf(scene.virtuals), o.render.samplesPerPixel, gbuffer, still);
    const bool wholeRealSurfaces = view.steady || !scene.background || o.render.layers;
    const SurfacePoints& realPoints = wholeRealSurfaces
                                          ? hideCoveredSurfaces(realSurfaces(), gbuffer, view)
                                          : renderRelitSurfaces(camera, realOnly, gbuffer, view);
    timer.lap("gbuffer");

    // 6. Cone tracing (§3.3): virtual surfaces read the full light volume, real ones the delta volume; both
    // are occluded by both visibility volumes. Cones discount the back faces of their own surface's volume
    // only.
    const ShadowMode relightMode =
        o.render.doubleShadowFix ? ShadowMode::DeltaShadow : ShadowMode::DeltaSingleVisibility;
    // The pixels the objects' G-buffer was rendered over hold every virtual point; the real points differ
    // from the kept real surfaces only there, where the objects cover them.
    const PixelRect& objectPixels = gbuffer.written;
    if (view.steady)
        for (InterpolationPlan& plan : view.relitPlans) plan.surfaces = realSurfaces();
    // Emitting surfaces light the scene through shadow rays (with options.shadow.method "rays").
    const AreaLights emitters = o.shadow.method == ShadowMethod::Rays
                                    ? AreaLights(scene, SceneContent::RealAndVirtual)
                                    : AreaLights(Scene{}, SceneContent::RealOnly);
    // The environment map lights the scene through shadow rays too (with options.shadow.method "rays").
    std::unique_ptr<EnvironmentSampler>& sampler = cache.environment.work.sampler;
    if (environmentByRays(scene) && !sampler)
        sampler = std::make_unique<EnvironmentSampler>(*scene.environment);
    const EnvironmentSampler* environment = environmentByRays(scene) ? sampler.get() : nullptr;
    const std::vector<Light> direct = directLights(scene);
    const ConeJob jobs[] = {
        {.points = gbuffer.object,
         .light = volumes.fullLight,
         .visibility = {volumes.sceneVisibility, volumes.objectVisibility, VisibilityVolumes::Self::Object},
         .indirect = o.render.indirect,
         .mode = ShadowMode::Shaded,
         .bounds = objectPixels,
         .rays = shadowRays,
         .lightChange = volumes.roomChange,
         .emitters = &emitters,
         .environment = environment,
         .pixelSamples = &gbuffer.objectSamples,
         .still = still},
        {.points = realPoints,
         .light = volumes.deltaLight,
         .visibility = {volumes.sceneVisibility, volumes.objectVisibility, VisibilityVolumes::Self::Scene},
         .indirect = o.render.indirect && o.render.relightIndirect,
         .mode = relightMode,
         .bounds = {0, 0, camera.width, camera.height},
         .sceneShadows = &cache.relitShadows.work.occlusion,
         .plans = view.steady ? &view.relitPlans : nullptr,
         .changed = objectPixels,
         .rays = shadowRays,
         .fullLight = o.render.relightCones == RelightCones::Differential ? volumes.fullLight : nullptr,
         .objectLight = volumes.objectLight,
         .emitters = &emitters,
         .environment = environment,
         // A session's frames keep their time; a still refines.
         .refineBudget = refineBudgetFor(o.render, still)}};
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
    FrameCache fresh;
    return renderFrame(scene, fresh, onStage, true);
}

struct FrameRenderer::State {
    FrameCache cache;
    TemporalReuse temporal;
};

FrameRenderer::FrameRenderer() : state_(std::make_unique<State>()) {}
FrameRenderer::~FrameRenderer() = default;

void FrameRenderer::clear() {
    state_->cache.clear();
    state_->temporal.clear();
}

void FrameRenderer::clearHistory() {
    state_->temporal.clear();
}

FrameRenderer::KeptWork FrameRenderer::lastFrameKept() const {
    FrameRenderer::KeptWork kept = state_->cache.kept();
    if (!kept.light) kept.lightMapsKept = state_->cache.light.work.rsmsKept;
    return kept;
}

size_t FrameRenderer::volumeBytes() const {
    const FrameCache& cache = state_->cache;
    size_t bytes = cache.voxels.work.visibility ? cache.voxels.work.visibility->bytes() : 0;
    if (const std::optional<ObjectVolumes>& objects = cache.objectVolumes.work.volumes; objects)
        bytes += objects->objectVisibility().bytes() + objects->fullLight().bytes() +
                 objects->deltaLight().bytes() + objects->objectLight().bytes();
    return bytes;
}

RenderOutput FrameRenderer::render(const Scene& scene, const StageCallback& onStage) {
    return renderKept(scene, onStage, false);
}

RenderOutput FrameRenderer::renderStill(const Scene& scene, const StageCallback& onStage) {
    clearHistory();
    return renderKept(scene, onStage, true);
}

RenderOutput FrameRenderer::renderKept(const Scene& scene, const StageCallback& onStage, bool still) {
    checkFrame(scene);
    FrameCache& cache = state_->cache;
    cache.update(scene);
    if (cache.newRealScene()) state_->temporal.clear();  // frames of another scene, lights or options
    return renderFrame(scene, cache, onStage, still, &state_->temporal);
}

}  // namespace deltagi
