// The pipeline of §3 / Fig. 2, stage by stage. Each stage is a function of explicit inputs to outputs, in its
// own file pair; this file only wires them up and times them.
#include "deltagi/renderer.h"

#include <chrono>

#include "composite.h"
#include "denoise.h"
#include "gbuffer.h"
#include "inject.h"
#include "mipmap.h"
#include "ray_scene.h"
#include "reflective_shadow_map.h"
#include "shading.h"
#include "sky_light.h"
#include "voxelize.h"

namespace deltagi {

namespace {

class StageTimer {
public:
    StageTimer(std::vector<StageTiming>& timings, const StageCallback& callback)
        : timings_(timings), callback_(callback), start_(Clock::now()) {}
    // Ends the current stage under `name` and starts the next one.
    void lap(std::string name) {
        const auto now = Clock::now();
        StageTiming t{std::move(name), std::chrono::duration<double, std::milli>(now - start_).count()};
        start_ = now;
        timings_.push_back(t);
        if (callback_) callback_(t);
    }

private:
    using Clock = std::chrono::steady_clock;
    std::vector<StageTiming>& timings_;
    StageCallback callback_;
    Clock::time_point start_;
};

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

std::vector<ReflectiveShadowMap> renderRsms(const RayScene& rays, std::span<const Light> lights,
                                            const VolumeRegion& region, int resolution) {
    std::vector<ReflectiveShadowMap> rsms;
    for (const Light& light : lights) rsms.push_back(renderReflectiveShadowMap(rays, light, region, resolution));
    return rsms;
}

// One set of surfaces to trace cones from, against a light volume and visibility volumes.
struct ConeJob {
    std::span<const SurfacePoint> points;
    const MipVolume* light;
    VisibilityVolumes visibility;
    bool indirect;  // trace diffuse and specular cones too
    ShadowMode mode;  // how the sky through the cones counts (shaded, relit, or the real scene alone)
};

struct ConeResults {
    std::vector<ShadowOcclusion> shadows;  // points x lights
    std::vector<glm::vec3> diffuse, specular;  // empty without indirect light
};

// a += b, where an empty `a` is zero.
void addInto(std::vector<glm::vec3>& a, std::vector<glm::vec3>&& b) {
    if (a.empty()) {
        a = std::move(b);
        return;
    }
    for (size_t i = 0; i < a.size(); ++i) a[i] += b[i];
}

// Stage 6 for every job: shadow, diffuse and specular cones (each timed as one stage over all jobs), then
// the edge-aware filter over the shadow and diffuse results.
std::vector<ConeResults> traceCones(std::span<const ConeJob> jobs, const Scene& scene, StageTimer& timer) {
    const Options& o = scene.options;
    std::vector<ConeResults> results(jobs.size());
    for (size_t j = 0; j < jobs.size(); ++j)
        results[j].shadows = traceShadowCones(jobs[j].points, scene.lights, jobs[j].visibility, o);
    timer.lap("shadow");
    for (size_t j = 0; j < jobs.size(); ++j)
        if (jobs[j].indirect)
            results[j].diffuse = traceDiffuseCones(jobs[j].points, *jobs[j].light, jobs[j].visibility, o);
    timer.lap("diffuse");
    for (size_t j = 0; j < jobs.size(); ++j)
        if (jobs[j].indirect)
            results[j].specular = traceSpecularCones(jobs[j].points, *jobs[j].light, jobs[j].visibility, o);
    timer.lap("specular");
    // Sky light through the cones, added to their indirect light (and so filtered with the diffuse part).
    if (scene.environment && !scene.environment->sky.empty()) {
        for (size_t j = 0; j < jobs.size(); ++j) {
            SkyLight sky =
                traceSkyCones(jobs[j].points, *scene.environment, jobs[j].visibility, jobs[j].mode, o);
            addInto(results[j].diffuse, std::move(sky.diffuse));
            addInto(results[j].specular, std::move(sky.specular));
        }
        timer.lap("sky");
    }
    // The jittered cone starts leave fine noise in shadows and diffuse light: an edge-aware filter per surface.
    const DenoiseSettings filter{o.render.denoiseRadius};
    for (size_t j = 0; j < jobs.size(); ++j) {
        denoiseInPlace(results[j].shadows, static_cast<int>(scene.lights.size()), jobs[j].points, scene.camera,
                       filter);
        denoiseInPlace(results[j].diffuse, 1, jobs[j].points, scene.camera, filter);
    }
    timer.lap("denoise");
    return results;
}

// Stages 1-4 (§3.2): the two visibility volumes, the full light volume and the delta volume, mip-mapped.
struct DgiVolumes {
    MipVolume sceneVisibility, objectVisibility, fullLight, deltaLight;
};

DgiVolumes buildVolumes(const Scene& scene, const VolumeRegion& region, const RayScene& realOnly,
                        const RayScene& all, StageTimer& timer) {
    const int rsmResolution = scene.options.rsm.resolution;
    // 1. Voxelization: one visibility volume for the reconstruction, one for the virtual objects.
    VoxelGeometry sceneGeometry = voxelize(scene.real, region);
    VoxelGeometry objectGeometry = voxelize(scene.virtuals, region);
    timer.lap("voxelize");
    // 2. Reflective shadow maps: scene + objects, and scene alone.
    const std::vector<ReflectiveShadowMap> rsmFull = renderRsms(all, scene.lights, region, rsmResolution);
    const std::vector<ReflectiveShadowMap> rsmScene = renderRsms(realOnly, scene.lights, region, rsmResolution);
    timer.lap("rsm");
    // 3. Light injection: the full light volume and the delta volume = full - scene alone.
    const VoxelGeometry* both[] = {&sceneGeometry, &objectGeometry};
    const VoxelGeometry* sceneAlone[] = {&sceneGeometry};
    Grid3 fullLight = injectLight(rsmFull, region, both);
    Grid3 deltaLight = deltaVolume(fullLight, injectLight(rsmScene, region, sceneAlone));
    timer.lap("inject");
    // 4. Mipmaps of all four volumes.
    DgiVolumes v{buildMipChain(region, std::move(sceneGeometry.visibility)),
                 buildMipChain(region, std::move(objectGeometry.visibility)),
                 buildMipChain(region, std::move(fullLight)), buildMipChain(region, std::move(deltaLight))};
    timer.lap("mipmap");
    return v;
}

// The real scene alone, rendered with regular voxel cone tracing over its own bounds: the background when the
// scene has no photo (the "already lit virtual scene" of the paper's Fig. 3). Its stages are timed together.
Image renderRealScene(const Scene& scene, const RayScene& realOnly, std::span<const SurfacePoint> points) {
    const Options& o = scene.options;
    // One voxel of margin on each side so that surfaces on the bounds are inside.
    const float margin = 1.0f + 2.0f / static_cast<float>(o.volume.resolution);
    const VolumeRegion region = cubeAround(boundsOf(scene.real), margin, o.volume.resolution);
    VoxelGeometry geometry = voxelize(scene.real, region);
    const std::vector<ReflectiveShadowMap> rsms = renderRsms(realOnly, scene.lights, region, o.rsm.resolution);
    const VoxelGeometry* geometries[] = {&geometry};
    const MipVolume light = buildMipChain(region, injectLight(rsms, region, geometries));
    const MipVolume visibility = buildMipChain(region, std::move(geometry.visibility));
    const ConeJob job{points,
                      &light,
                      {&visibility, nullptr, VisibilityVolumes::Self::Scene},
                      o.render.indirect,
                      ShadowMode::SceneOnly};
    std::vector<StageTiming> ignored;
    StageTimer quiet(ignored, {});
    const ConeResults cones = std::move(traceCones({&job, 1}, scene, quiet)[0]);
    const std::vector<glm::vec3> radiance = combineLighting(points, scene.lights, cones.shadows,
                                                            ShadowMode::SceneOnly, cones.diffuse, cones.specular);
    return toImage(radiance, scene.camera.width, scene.camera.height);
}


}  // namespace

VolumeRegion volumeRegion(const Scene& scene) {
    const VolumeOptions& v = scene.options.volume;
    if (v.center && v.size) {
        return {*v.center - glm::vec3(0.5f * *v.size), *v.size, v.resolution};
    }
    if (!scene.virtuals.empty()) return cubeAround(boundsOf(scene.virtuals), v.extentScale, v.resolution);
    return cubeAround(boundsOf(scene.real), 1.0f + 2.0f / static_cast<float>(v.resolution), v.resolution);
}

RenderOutput render(const Scene& scene, const StageCallback& onStage) {
    RenderOutput out;
    const auto start = std::chrono::steady_clock::now();
    StageTimer timer(out.timings, onStage);
    const Options& o = scene.options;
    const Camera& camera = scene.camera;
    const VolumeRegion region = volumeRegion(scene);

    if (scene.virtuals.empty()) {
        // Nothing is added, so nothing changes: the composite is the background.
        const RayScene realOnly(scene, SceneContent::RealOnly);
        if (scene.background) {
            out.background = *scene.background;
        } else {
            GBuffer gbuffer = renderGBuffer(camera, realOnly, realOnly, 1);
            timer.lap("gbuffer");
            out.background = renderRealScene(scene, realOnly, gbuffer.real);
            timer.lap("background");
        }
        out.composite = out.background;
        out.objectMask = Image(camera.width, camera.height, 1);
        out.delta = Image(camera.width, camera.height, 3);
        out.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        return out;
    }

    const RayScene realOnly(scene, SceneContent::RealOnly);
    const RayScene all(scene, SceneContent::RealAndVirtual);
    timer.lap("bvh");

    const DgiVolumes volumes = buildVolumes(scene, region, realOnly, all, timer);

    // 5. G-buffer. Real surfaces are relit only where they show through (coverage < 1).
    GBuffer gbuffer = renderGBuffer(camera, all, realOnly, o.render.samplesPerPixel);
    std::vector<SurfacePoint> realPoints = gbuffer.real;
    for (size_t i = 0; i < realPoints.size(); ++i)
        if (gbuffer.coverage[i] >= 1.0f) realPoints[i] = {};
    timer.lap("gbuffer");

    // 6. Cone tracing (§3.3): virtual surfaces read the full light volume, real ones the delta volume; both are
    // occluded by both visibility volumes. Cones discount the back faces of their own surface's volume only.
    const ShadowMode relightMode =
        o.render.doubleShadowFix ? ShadowMode::DeltaShadow : ShadowMode::DeltaSingleVisibility;
    const ConeJob jobs[] = {
        {gbuffer.object,
         &volumes.fullLight,
         {&volumes.sceneVisibility, &volumes.objectVisibility, VisibilityVolumes::Self::Object},
         o.render.indirect,
         ShadowMode::Shaded},
        {realPoints,
         &volumes.deltaLight,
         {&volumes.sceneVisibility, &volumes.objectVisibility, VisibilityVolumes::Self::Scene},
         o.render.indirect && o.render.relightIndirect,
         relightMode}};
    const std::vector<ConeResults> cones = traceCones(jobs, scene, timer);
    const ConeResults& object = cones[0];
    const ConeResults& real = cones[1];

    // 7. Shading of virtual surfaces vs relighting of real ones (§3.3).
    const auto objectRadiance = combineLighting(gbuffer.object, scene.lights, object.shadows,
                                                ShadowMode::Shaded, object.diffuse, object.specular);
    const auto realChange =
        combineLighting(realPoints, scene.lights, real.shadows, relightMode, real.diffuse, real.specular);
    timer.lap("shading");

    // The background: the photo, or the real scene rendered alone.
    if (scene.background) {
        out.background = *scene.background;
    } else {
        out.background = renderRealScene(scene, realOnly, gbuffer.real);
        timer.lap("background");
    }

    // 8. Differential composite.
    CompositeImages images = differentialComposite(out.background, gbuffer, objectRadiance, realChange);
    out.composite = std::move(images.composite);
    out.objectMask = std::move(images.objectMask);
    out.delta = std::move(images.delta);
    timer.lap("composite");
    out.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace deltagi
