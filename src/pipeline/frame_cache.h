// What FrameRenderer keeps from one frame for the next, by lifetime. Each part holds the work made from the
// same inputs and carries a key of them; FrameCache::update() compares the keys with the new frame's and
// empties a part whose inputs changed. A part's key holds the versions of the parts it is made from, so a
// change empties exactly its dependents:
//
//   world: the real meshes, their materials, the options      realOnly BVH
//   ├─ voxels: + the volume region                            the real scene's voxels and visibility mipmaps
//   │  ├─ light: + the lights, the environment map, the       its RSMs, injected and bounced light
//   │  │         viewpoint's side of each real surface
//   │  └─ object volumes                                      the objects' voxels and the four light volumes,
//   │                                                          which start from each new light themselves
//   ├─ view: + the camera                                     the real G-buffer, the filter's weights
//   │  ├─ lit view: + the lights                              the background rendered without a photo
//   │  └─ relit shadows: + the region, the lights             the scene's share of the relit shadow cones
//   └─ object BVH                                             the objects' layer over realOnly
//   environment: the environment map                          its sampler
//
// The objects' parts (their BVH and volumes, and the objects' half of the G-buffer in `view`) are also
// brought up to date by their own code where the objects move (RayScene::refit, ObjectVolumes,
// renderObjectSurfaces). Everything is made lazily by the frame that needs it (renderer.cpp); update() only
// forgets.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/environment_sampling.h"
#include "core/ray_scene.h"
#include "deltagi/renderer.h"
#include "deltagi/scene.h"
#include "pipeline/denoise.h"
#include "pipeline/gbuffer.h"
#include "pipeline/mipmap.h"
#include "pipeline/object_volumes.h"
#include "pipeline/reflective_shadow_map.h"
#include "pipeline/shading.h"
#include "pipeline/voxelize.h"

namespace deltagi {

// The real scene's geometry.
struct WorldWork {
    std::unique_ptr<RayScene> realOnly;
};

// The real scene over the volume region.
struct VoxelWork {
    std::optional<VoxelGeometry> geometry;
    std::optional<MipVolume> visibility;
};

// The real light in the region: one RSM per light, and the light injected from them plus its further bounces.
// The RSMs of directional lights keep a real surface's texels on the viewpoint's side only (a point or spot
// light's keep every texel), and the bounces gather on its side of each voxel: `rsmSides` and `bounceSides`
// are those sides, and what depends on them is redone where the viewpoint crossed a surface's plane
// (FrameCache::update; for all the lights, also those whose maps do not depend on it).
struct LightWork {
    // The maps of `rsmLights`, made over the voxel part of version `rsmVoxels`.
    std::optional<std::vector<ReflectiveShadowMap>> rsms;
    std::vector<Light> rsmLights;
    uint64_t rsmVoxels = 0;
    int rsmsKept = 0;  // of them, taken from the spare ones
    std::vector<int8_t> rsmSides;
    std::optional<Grid3> injected;          // from `rsms`, plus `bounce`
    InjectedVoxels injectedVoxels;          // the voxels injectLight wrote into `injected`
    std::optional<SurfaceRadiance> bounce;  // the further bounces (options.render.light_bounces)
    std::optional<VoxelBox>
        injectedBounds;  // around `injected`'s non-zero voxels, where injectedBounds found it
    std::vector<bool> bounceSides;
    // The maps of the light before, when it changed: a light that did not change (a lamp beside a light
    // camera's environment) takes its map from here as long as the region's voxels and the viewpoint's sides
    // are those it was made for (spareRsm). The next injection recycles its grid over the same voxels.
    struct Spare {
        std::vector<ReflectiveShadowMap> rsms;
        std::vector<Light> lights;
        std::vector<int8_t> sides;
        uint64_t voxels = 0;
        std::unique_ptr<RecycledGrid> injected;
    } spare;
    // Empties it for another light; its maps become the spare ones.
    void forget();
    // The spare map of `light` at `resolution`, over the voxel part of version `voxels` with the viewpoint's
    // sides `sides`, taken out of the spare ones; nullopt when there is none.
    std::optional<ReflectiveShadowMap> spareRsm(const Light& light, int resolution, uint64_t voxels,
                                                const std::vector<int8_t>& sides);
};

// The environment map's sampler (its CDFs), when its light is traced by rays.
struct EnvironmentWork {
    std::unique_ptr<EnvironmentSampler> sampler;
};

// What the camera sees of the real scene, and the objects' half of the G-buffer over it.
struct ViewWork {
    // The camera is the last frame's: the filter's weights over the real surfaces are worth keeping (a
    // camera that moves every frame would build them for one use; its passes compute only those they need).
    bool steady = false;
    SurfacePoints realSurfaces;  // the G-buffer's real half, when realSurfacesMade
    bool realSurfacesMade = false;
    std::array<InterpolationPlan, 5> relitPlans;  // the relit passes' filter weights over realSurfaces
    GBuffer gbuffer;                              // the objects' half, redone where they were and are
    // realSurfaces without the pixels the objects cover (the last frame's `hidden`), when relitSurfacesMade.
    SurfacePoints relitSurfaces;
    bool relitSurfacesMade = false;
    std::vector<uint32_t> hidden;
    // Empties it for another camera. The large buffers keep their memory and their size (28 MiB each at 640 x
    // 480: allocated afresh, their pages would be faulted in every frame; resized from empty, each element
    // would be set twice, the first time on one thread).
    void forget();
};

// The real scene lit and seen from the camera.
struct LitViewWork {
    std::optional<Image> background;  // the real scene rendered alone (no photo)
};

// The scene's share of the real surfaces' shadow cones, through the region's voxels, towards the lights.
struct RelitShadowWork {
    SceneOcclusionCache occlusion;
};

// The virtual objects' layer of rays over WorldWork::realOnly, refit as they move.
struct ObjectRayWork {
    std::unique_ptr<RayScene> objects;
};

// The objects' volumes, updated where the objects changed them since the last frame (and from the new light
// when the light changed: ObjectVolumes follows the light part's version itself).
struct ObjectVolumeWork {
    std::optional<ObjectVolumes> volumes;
};

// A part of the cache, the key of what it was made from, and its version: a number new each time the part
// is emptied, which the keys of its dependents hold.
template <class Work>
struct CachePart {
    Work work;
    uint64_t key = 0;
    uint64_t version = 0;
};

class FrameCache {
  public:
    // Empties every part whose inputs differ in `scene` from the last frame's, and the parts made from it.
    // `scene` must stay alive and in place between calls for the kept work to be reused (the key holds its
    // address and its real meshes': the BVH and the surfaces point into them).
    void update(const Scene& scene);
    // Empties everything: the next frame is a cold one.
    void clear() { *this = FrameCache{}; }

    // Whether the last update() kept the part from the frame before.
    FrameRenderer::KeptWork kept() const { return kept_; }
    // Whether the last update() found other real meshes, options, lights or environment than the frame
    // before's (not only another region or camera, or another side of a real surface).
    bool newRealScene() const { return newRealScene_; }

    CachePart<WorldWork> world;
    CachePart<VoxelWork> voxels;
    CachePart<LightWork> light;
    CachePart<ViewWork> view;
    CachePart<LitViewWork> litView;
    CachePart<RelitShadowWork> relitShadows;
    CachePart<ObjectRayWork> objectRays;
    CachePart<ObjectVolumeWork> objectVolumes;
    CachePart<EnvironmentWork> environment;

  private:
    // Brings `part` to `key`: kept when it is its key already (true), else emptied with a new version.
    template <class Work>
    bool renew(CachePart<Work>& part, uint64_t key);
    // Redoes the light's work that depends on the viewpoint's side of the real surfaces where it changed.
    void keepLightFor(const Scene& scene, glm::vec3 viewpoint);
    void emptyLight(bool keepRsms);

    uint64_t nextVersion_ = 0;
    Options options_;  // the last frame's, and the version of the world's key that stands for them
    uint64_t optionsVersion_ = 0;
    bool hasOptions_ = false;
    std::optional<glm::vec3> viewpoint_;  // the one LightWork's sides were taken for
    uint64_t realSceneKey_ = 0;
    bool newRealScene_ = true;
    uint64_t objectsKey_ = 0;
    FrameRenderer::KeptWork kept_;
};

// The point whose side of the real surfaces the volumes light (options.volume.viewpoint; the camera's).
glm::vec3 viewpointOf(const Scene& scene);

}  // namespace deltagi
