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
    const StageCallback& callback_;
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

std::vector<ReflectiveShadowMap> renderRsms(const RayScene& rays, std::span<const Light> lights,
                                            const VolumeRegion& region, int resolution) {
    std::vector<ReflectiveShadowMap> rsms;
    for (const Light& light : lights) rsms.push_back(renderReflectiveShadowMap(rays, light, region, resolution));
    return rsms;
}

// The real scene alone, rendered with regular voxel cone tracing over its own bounds: the background when the
// scene has no photo (the "already lit virtual scene" of the paper's Fig. 3).
std::vector<glm::vec3> renderRealScene(const Scene& scene, const RayScene& realOnly,
                                       std::span<const SurfacePoint> points) {
    const Options& o = scene.options;
    // One voxel of margin on each side so that surfaces on the bounds are inside.
    const float margin = 1.0f + 2.0f / static_cast<float>(o.volume.resolution);
    const VolumeRegion region = cubeAround(boundsOf(scene.real), margin, o.volume.resolution);
    VoxelGeometry geometry = voxelize(scene.real, region);
    const std::vector<ReflectiveShadowMap> rsms = renderRsms(realOnly, scene.lights, region, o.rsm.resolution);
    const VoxelGeometry* geometries[] = {&geometry};
    MipVolume light = buildMipChain(region, injectLight(rsms, region, geometries));
    MipVolume visibility = buildMipChain(region, std::move(geometry.visibility));
    const VisibilityVolumes vis{&visibility, nullptr};
    auto shadows = traceShadowCones(points, scene.lights, vis, o);
    std::vector<glm::vec3> diffuse, specular;
    if (o.render.indirect) {
        diffuse = traceDiffuseCones(points, light, vis, o);
        specular = traceSpecularCones(points, light, vis, o);
    }
    const DenoiseSettings filter{o.render.denoiseRadius};
    denoiseInPlace(shadows, static_cast<int>(scene.lights.size()), points, scene.camera, filter);
    denoiseInPlace(diffuse, 1, points, scene.camera, filter);
    return combineLighting(points, scene.lights, shadows, ShadowMode::SceneOnly, diffuse, specular);
}

Image toImage(std::span<const glm::vec3> pixels, int width, int height) {
    Image image(width, height, 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) image.setRgb(x, y, pixels[static_cast<size_t>(y) * width + x]);
    sanitize(image);
    return image;
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
            out.background = toImage(renderRealScene(scene, realOnly, gbuffer.real), camera.width, camera.height);
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

    // 1. Voxelization: one visibility volume for the reconstruction, one for the virtual objects (§3.2).
    VoxelGeometry sceneGeometry = voxelize(scene.real, region);
    VoxelGeometry objectGeometry = voxelize(scene.virtuals, region);
    timer.lap("voxelize");

    // 2. Reflective shadow maps: scene + objects, and scene alone.
    const std::vector<ReflectiveShadowMap> rsmFull = renderRsms(all, scene.lights, region, o.rsm.resolution);
    const std::vector<ReflectiveShadowMap> rsmScene = renderRsms(realOnly, scene.lights, region, o.rsm.resolution);
    timer.lap("rsm");

    // 3. Light injection: the full light volume and the delta volume = full - scene alone.
    const VoxelGeometry* both[] = {&sceneGeometry, &objectGeometry};
    const VoxelGeometry* sceneAlone[] = {&sceneGeometry};
    Grid3 fullLight = injectLight(rsmFull, region, both);
    Grid3 deltaLight = deltaVolume(fullLight, injectLight(rsmScene, region, sceneAlone));
    timer.lap("inject");

    // 4. Mipmaps of all four volumes.
    const MipVolume sceneVisibility = buildMipChain(region, std::move(sceneGeometry.visibility));
    const MipVolume objectVisibility = buildMipChain(region, std::move(objectGeometry.visibility));
    const MipVolume fullVolume = buildMipChain(region, std::move(fullLight));
    const MipVolume deltaVolumeMips = buildMipChain(region, std::move(deltaLight));
    timer.lap("mipmap");

    // 5. G-buffer.
    GBuffer gbuffer = renderGBuffer(camera, all, realOnly, o.render.samplesPerPixel);
    // Real surfaces are relit only where they show through (coverage < 1).
    std::vector<SurfacePoint> realPoints = gbuffer.real;
    for (size_t i = 0; i < realPoints.size(); ++i)
        if (gbuffer.coverage[i] >= 1.0f) realPoints[i] = {};
    timer.lap("gbuffer");

    // 6. Cone tracing. Shadow cones test both visibility volumes.
    // Cones from virtual surfaces discount the object volume's back faces, cones from real ones the scene's.
    const VisibilityVolumes fromObject{&sceneVisibility, &objectVisibility, VisibilityVolumes::Self::Object};
    const VisibilityVolumes fromReal{&sceneVisibility, &objectVisibility, VisibilityVolumes::Self::Scene};
    auto objectShadows = traceShadowCones(gbuffer.object, scene.lights, fromObject, o);
    auto realShadows = traceShadowCones(realPoints, scene.lights, fromReal, o);
    timer.lap("shadow");
    std::vector<glm::vec3> objectDiffuse, realDiffuse, objectSpecular, realSpecular;
    const bool relightIndirect = o.render.indirect && o.render.relightIndirect;
    if (o.render.indirect) objectDiffuse = traceDiffuseCones(gbuffer.object, fullVolume, fromObject, o);
    if (relightIndirect) realDiffuse = traceDiffuseCones(realPoints, deltaVolumeMips, fromReal, o);
    timer.lap("diffuse");
    if (o.render.indirect) objectSpecular = traceSpecularCones(gbuffer.object, fullVolume, fromObject, o);
    if (relightIndirect) realSpecular = traceSpecularCones(realPoints, deltaVolumeMips, fromReal, o);
    timer.lap("specular");

    // The jittered cone starts leave fine noise in shadows and diffuse light: an edge-aware filter per surface.
    const DenoiseSettings filter{o.render.denoiseRadius};
    const int lightCount = static_cast<int>(scene.lights.size());
    denoiseInPlace(objectShadows, lightCount, gbuffer.object, camera, filter);
    denoiseInPlace(realShadows, lightCount, realPoints, camera, filter);
    denoiseInPlace(objectDiffuse, 1, gbuffer.object, camera, filter);
    denoiseInPlace(realDiffuse, 1, realPoints, camera, filter);
    timer.lap("denoise");

    // 7. Shading of virtual surfaces vs relighting of real ones (§3.3).
    const auto objectRadiance = combineLighting(gbuffer.object, scene.lights, objectShadows, ShadowMode::Shaded,
                                                objectDiffuse, objectSpecular);
    const ShadowMode relightMode =
        o.render.doubleShadowFix ? ShadowMode::DeltaShadow : ShadowMode::DeltaSingleVisibility;
    const auto realChange =
        combineLighting(realPoints, scene.lights, realShadows, relightMode, realDiffuse, realSpecular);
    timer.lap("shading");

    // The background: the photo, or the real scene rendered alone.
    if (scene.background) {
        out.background = *scene.background;
    } else {
        out.background = toImage(renderRealScene(scene, realOnly, gbuffer.real), camera.width, camera.height);
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
