#include "pipeline/frame_cache.h"

#include <algorithm>
#include <string>
#include <utility>

#include "pipeline/bounce_light.h"

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace deltagi {

namespace {

// XXH3 (xxHash, Debian's libxxhash-dev, inlined) over bytes: the world's key reads every byte of the real
// meshes each frame, and a byte-wise FNV-1a took about 4 cycles a byte (40 ms a frame for a reconstruction
// of a million triangles).
class Hasher {
  public:
    Hasher() { XXH3_64bits_reset(&state_); }
    Hasher(const Hasher&) = delete;
    Hasher& operator=(const Hasher&) = delete;
    void bytes(const void* data, size_t size) { XXH3_64bits_update(&state_, data, size); }
    // One value's bytes: for types without padding.
    template <class T>
    void value(const T& v) {
        bytes(&v, sizeof(v));
    }
    template <class T>
    void values(const std::vector<T>& v) {
        bytes(v.data(), v.size() * sizeof(T));
    }
    uint64_t digest() const { return XXH3_64bits_digest(&state_); }

  private:
    XXH3_state_t state_;
};

template <class... T>
uint64_t keyOf(const T&... values) {
    Hasher h;
    (h.value(values), ...);
    return h.digest();
}

// A mesh's geometry, its attributes and material, and its positions' address (a kept BVH points into them).
void hashMesh(Hasher& h, const TriangleMesh& m) {
    h.value(m.positions.data());
    h.values(m.positions);
    h.values(m.normals);
    h.values(m.triangles);
    h.values(m.uvs);
    h.values(m.uvs1);
    h.values(m.tangents);
    h.values(m.colors);
    visitMaterialFields(m.material, [&](const auto& v) { h.value(v); });
}

// The real scene's geometry and materials. The scene's and its real meshes' addresses are part of it: the
// kept BVH and surfaces point into them.
uint64_t realMeshesKey(const Scene& scene) {
    Hasher h;
    h.value(&scene);
    h.value(scene.real.data());
    h.value(scene.real.size());
    for (const TriangleMesh& m : scene.real) hashMesh(h, m);
    // Whether there is a photo: without one the background is the real scene rendered alone.
    h.value(scene.background.has_value());
    return h.digest();
}

// The virtual objects' meshes, materials and placement, with their addresses (the objects' BVH points into
// them).
uint64_t objectsKey(const Scene& scene) {
    Hasher h;
    h.value(scene.virtuals.data());
    h.value(scene.virtuals.size());
    for (const TriangleMesh& m : scene.virtuals) {
        hashMesh(h, m);
        h.value(m.objectSpace.get());
        h.value(m.worldFromObject);
    }
    return h.digest();
}

uint64_t environmentKey(const Scene& scene) {
    if (!scene.environment) return 0;
    return keyOf(scene.environment->radiance.data().data(), scene.environment->worldFromEnvironment);
}

// Calls `f` with each field of a light that its light depends on.
template <class F>
void visitLightFields(const Light& l, F&& f) {
    f(l.type);
    f(l.color);
    f(l.intensity);
    f(l.position);
    f(l.direction);
    f(l.innerAngleDeg);
    f(l.outerAngleDeg);
    f(l.radius);
    f(l.fromEnvironment);
    f(l.angularRadius);
    f(l.lambertian);
}

// The real light: the lights and the environment map.
uint64_t lightsKey(const Scene& scene) {
    Hasher h;
    // field by field: Light has padding after its bools
    for (const Light& l : scene.lights) visitLightFields(l, [&](const auto& v) { h.value(v); });
    h.value(environmentKey(scene));
    return h.digest();
}

// Whether two lights are the same, field by field (bitwise: -0 and 0 differ, as in the keys).
bool sameLight(const Light& a, const Light& b) {
    auto bytes = [](const Light& l) {
        std::string out;
        visitLightFields(l, [&](const auto& v) { out.append(reinterpret_cast<const char*>(&v), sizeof(v)); });
        return out;
    };
    return bytes(a) == bytes(b);
}

// Whether the viewpoint lies in the plane of a real surface (side 0): it has no side to keep.
bool onASurfacesPlane(const std::vector<int8_t>& sides) {
    return std::find(sides.begin(), sides.end(), 0) != sides.end();
}

uint64_t regionKey(const VolumeRegion& r) {
    return keyOf(r.origin, r.size, r.resolution);
}

}  // namespace

void ViewWork::forget() {
    realSurfacesMade = false;
    for (InterpolationPlan& plan : relitPlans) {
        plan.stride = 0;
        plan.weights.clear();
        plan.samples.clear();
        plan.weighted.clear();
    }
    // The objects' G-buffer stays: renderObjectSurfaces clears the last frame's pixels of it, wherever the
    // camera was (an image of another size starts afresh). The relit surfaces keep their memory too; they
    // are made again from the real ones (hideCoveredSurfaces, renderRelitSurfaces) before they are read.
    relitSurfacesMade = false;
    hidden.clear();
}

void LightWork::forget() {
    Spare kept = std::move(spare);
    if (rsms) {
        kept.rsms = std::move(*rsms);
        kept.lights = std::move(rsmLights);
        kept.sides = std::move(rsmSides);
        kept.voxels = rsmVoxels;
        kept.injected.reset();
        if (injected)
            kept.injected = std::make_unique<RecycledGrid>(std::move(*injected), std::move(injectedVoxels));
    }
    *this = LightWork{};
    spare = std::move(kept);
}

std::optional<ReflectiveShadowMap> LightWork::spareRsm(const Light& light, int resolution, uint64_t voxels,
                                                       const std::vector<int8_t>& sides) {
    if (spare.voxels != voxels || spare.sides != sides || onASurfacesPlane(sides)) return std::nullopt;
    for (size_t i = 0; i < spare.lights.size(); ++i) {
        ReflectiveShadowMap& rsm = spare.rsms[i];
        if (rsm.resolution != resolution || !sameLight(spare.lights[i], light) || rsm.faces == 0) continue;
        ReflectiveShadowMap taken = std::move(rsm);
        rsm = ReflectiveShadowMap{};  // taken: faces 0
        return taken;
    }
    return std::nullopt;
}

glm::vec3 viewpointOf(const Scene& scene) {
    return scene.options.volume.viewpoint.value_or(scene.camera.position());
}

template <class Work>
bool FrameCache::renew(CachePart<Work>& part, uint64_t key) {
    if (part.version != 0 && part.key == key) return true;
    if constexpr (requires { part.work.forget(); })
        part.work.forget();
    else
        part.work = Work{};
    part.key = key;
    part.version = ++nextVersion_;
    return false;
}

void FrameCache::emptyLight(bool keepRsms) {
    LightWork& l = light.work;
    if (!keepRsms) {
        l.rsms.reset();
        l.rsmSides.clear();
    }
    l.injected.reset();
    l.injectedVoxels = {};
    l.injectedBounds.reset();
    l.bounce.reset();
    l.bounceSides.clear();
    light.version = ++nextVersion_;
}

void FrameCache::keepLightFor(const Scene& scene, glm::vec3 viewpoint) {
    if (viewpoint_ == viewpoint) return;
    viewpoint_ = viewpoint;
    LightWork& l = light.work;
    if (l.rsms) {
        const std::vector<int8_t> sides = rsmViewSides(scene.real, viewpoint);
        if (sides != l.rsmSides || onASurfacesPlane(sides)) {
            emptyLight(false);
            return;
        }
    }
    if (l.bounce && bounceViewSides(*voxels.work.visibility, viewpoint) != l.bounceSides) emptyLight(true);
}

void FrameCache::update(const Scene& scene) {
    if (!hasOptions_ || !(scene.options == options_)) {
        options_ = scene.options;
        hasOptions_ = true;
        optionsVersion_ = ++nextVersion_;
    }
    const uint64_t lights = lightsKey(scene);
    const uint64_t camera = keyOf(scene.camera);
    kept_.world = renew(world, keyOf(realMeshesKey(scene), optionsVersion_));
    const bool regionKept = renew(voxels, keyOf(world.version, regionKey(volumeRegion(scene))));
    kept_.world = kept_.world && regionKept;
    if (!renew(light, keyOf(voxels.version, lights))) viewpoint_.reset();
    keepLightFor(scene, viewpointOf(scene));
    kept_.light = light.work.rsms.has_value();
    kept_.camera = renew(view, keyOf(world.version, camera));
    view.work.steady = kept_.camera;
    renew(litView, keyOf(world.version, lights, view.version));
    renew(relitShadows, keyOf(voxels.version, lights, view.version));
    const bool objectRaysKept = renew(objectRays, keyOf(world.version));
    const bool objectVolumesKept = renew(
        objectVolumes, keyOf(voxels.version));  // a new light: ObjectVolumes starts from it (lightVersion)
    const uint64_t objects = objectsKey(scene);
    kept_.objects = objects == objectsKey_ && objectRaysKept && objectVolumesKept;
    objectsKey_ = objects;
    renew(environment, environmentKey(scene));
    const uint64_t realScene = keyOf(world.version, lights);
    newRealScene_ = realScene != realSceneKey_;
    realSceneKey_ = realScene;
}

}  // namespace deltagi
