#include "pipeline/object_volumes.h"

#include <algorithm>

#include "pipeline/bounce_light.h"
#include "pipeline/object_bounce_rays.h"
#include "pipeline/shadow_rays.h"

namespace deltagi {

namespace {

// A frame whose changed box holds more than this fraction of the voxels injects every voxel instead: the
// box's share of the texels would then cost more to gather than to scatter them all.
constexpr size_t kFreshInjectionFraction = 4;  // 1/4

// The window of the objects' voxels and their own volumes: their box and this many voxels around it, so that
// an object that moves a little stays inside.
constexpr int kWindowMargin = 4;

bool sameRegion(const VolumeRegion& a, const VolumeRegion& b) {
    return a.origin == b.origin && a.size == b.size && a.resolution == b.resolution;
}

}  // namespace

void ObjectVolumes::voxelize(std::span<const TriangleMesh> objects, const VolumeRegion& region,
                             bool withEmission, bool withAlbedo, bool unchanged) {
    const bool fresh = objectVisibility_.empty() || !sameRegion(region, region_);
    if (unchanged && !fresh) {
        objectsChanged_ = VoxelBox{};
        return;
    }
    if (fresh) {
        *this = ObjectVolumes{};
        region_ = region;
        objects_ = deltagi::voxelize(objects, region, withEmission, withAlbedo, kWindowMargin);
        objectsChanged_ = VoxelBox::all(region.resolution);
        window_ = objects_.visibility.window();
        return;
    }
    objectsChanged_ = revoxelize(objects_, objects, region, withEmission);
    objectsChanged_.extend(objects_.bounds);
    if (objects_.visibility.window() != window_) {
        // The objects left the window: their voxels start over a new one, and their volumes afresh there.
        window_ = objects_.visibility.window();
        objectVisibility_ = MipVolume{};
        objectLight_ = MipVolume{};
    }
}

void ObjectVolumes::inject(const RealSceneVolumes& real, std::span<const RsmUpdate> updates) {
    const bool newLight = fullLight_.empty() || real.lightVersion != sceneLightVersion_;
    lightNew_ = newLight;
    if (newLight) {
        sceneLightVersion_ = real.lightVersion;
        sceneTexels_.reset();
        sceneLightBounds_.reset();
    }
    const RsmChanges changes = compareRsms(real.rsms, updates, region_);
    const VoxelGeometry* both[] = {&real.geometry, &objects_};
    // Where the objects change the light: their voxels and those of the texels they change, row by row (with
    // many lights the texels' voxels lie in many regions apart, whose one bounding box would be most of the
    // volume).
    VoxelRows differs = changes.voxels;
    differs.add(objects_.bounds);
    // A new light rewrites the whole full volume, but the delta volume only where the objects change the
    // light now or did last frame: elsewhere it is (0, 0, 0, occupancy) whatever the light.
    const bool wholeDelta = deltaLight_.empty();
    VoxelRows changed = differs;
    if (!wholeDelta && lightDiffers_.resolution() == region_.resolution) changed.add(lightDiffers_);
    lightDiffers_ = std::move(differs);
    const VoxelBox all = VoxelBox::all(region_.resolution);
    if (changed.count() > all.count() / kFreshInjectionFraction) {
        std::vector<ReflectiveShadowMap> withObjects;
        for (size_t l = 0; l < updates.size(); ++l)
            withObjects.push_back(applyRsmUpdate(real.rsms[l], updates[l]));
        Grid3 full = injectLight(withObjects, region_, both);
        if (real.bounce) addBounce(full, *real.bounce, real.geometry);
        freshDelta_.emplace(deltaVolume(full, real.light));
        freshFull_.emplace(full);
        lightChanged_ = all;
        reinjected_ = all.count();
        return;
    }
    // A new light bins the texels of the voxels it re-injects only (a live light is new every frame); voxels
    // beyond the binned ones under the same light bin them all.
    if (!sceneTexels_ || !sceneTexels_->voxels.contains(changed))
        sceneTexels_ = binTexels(real.rsms, region_, newLight ? changed : VoxelRows::all(region_.resolution));
    if (!sceneLightBounds_)
        sceneLightBounds_ = real.lightBounds ? *real.lightBounds : nonZeroBounds(real.light, all);
    if (newLight) {
        // Outside `changed` the full volume is the scene's, bit for bit (the same texels, summed alike).
        const VoxelGeometry* scene[] = {&real.geometry};
        freshFull_.emplace(real.lightVoxels ? packInjected(real.light, scene, *real.lightVoxels)
                                            : PackedGrid3(real.light));
        if (wholeDelta) freshDelta_.emplace(deltaVolume(real.light, real.light));
    }
    reinjectLight(changed, *sceneTexels_, real.rsms, changes, both, real.light,
                  newLight ? *freshFull_ : fullLight_.levelForUpdate(0),
                  wholeDelta ? *freshDelta_ : deltaLight_.levelForUpdate(0), real.bounce);
    lightChanged_ = wholeDelta ? all : changed.bounds();
    reinjected_ = changed.count();
}

namespace {

// The mip level at which the objects gather their further bounce: voxels of 4 level-0 voxels, a few hundred
// for a statue at 128^3 (a few milliseconds a frame).
constexpr int kObjectBounceLevel = 2;
// roomChange(): the real surfaces within resolution / kRoomChangeMarginDivisor level-0 voxels of the objects'
// box (16 at 128^3: 7.5 cm in the Cornell box's volume), gathered at the voxels of mip level kRoomChangeLevel
// (4 level-0 voxels: coarser ones make the objects' pixels flicker as they move, design.md) that have a
// gathering normal (bounce_light.h: not a corner's two faces).
constexpr int kRoomChangeMarginDivisor = 8;
constexpr int kRoomChangeLevel = 2;

VoxelBox unionOf(VoxelBox a, const VoxelBox& b) {
    if (a.empty()) return b;
    if (!b.empty()) a.extend(b);
    return a;
}

}  // namespace

void ObjectVolumes::updateObjectLight(const VoxelBox& box) {
    const PackedGrid3& full = fullLight_.level(0);
    const bool fresh = objectLight_.empty();
    PackedGrid3 freshLevel0;
    if (fresh) freshLevel0 = PackedGrid3(region_.resolution, window_);
    PackedGrid3& level0 = fresh ? freshLevel0 : objectLight_.levelForUpdate(0);
    const VoxelBox rewrite = fresh ? level0.window() : box.intersection(level0.window());
    forEachRow(rewrite, [&](int y, int z) {
        for (int x = rewrite.lo.x; x < rewrite.hi.x; ++x) {
            const size_t i = objects_.indexOf(x, y, z);
            const bool occupied = i != VoxelGeometry::kOutside && objects_.visibility[i].x > 0.0f;
            level0.set(x, y, z, occupied ? full[full.index(x, y, z)] : glm::vec4(0.0f));
        }
    });
    if (fresh)
        objectLight_ = buildMipChain(region_, std::move(freshLevel0));
    else
        updateMipChain(objectLight_, rewrite, nonZeroBounds(level0, rewrite));
}

void ObjectVolumes::mipmap(const MipVolume* sceneVisibility, const Options* options, const RayScene* rays,
                           const RoomChangeInputs* room) {
    buildLightMips();
    // The objects' light is non-zero only where they are and were: inside what this frame's injection
    // rewrote.
    updateObjectLight(lightChanged_);
    const bool bounces = sceneVisibility && options && objects_.withAlbedo && !objects_.bounds.empty();
    if (bounces) addObjectBounce(*sceneVisibility, *options, rays);
    if (!bounces || !room || !room->rays.scene || !room->rays.objects || !room->geometry.withAlbedo ||
        options->diffuse.objectGatherRays == 0) {
        roomChange_ = MipVolume{};
        roomChangeOptions_.reset();
        return;
    }
    if (objectsChanged_.empty() && !lightNew_ && roomChangeOptions_ == *options) return;  // kept
    roomChange_ = MipVolume{};
    updateRoomChange(*sceneVisibility, *options, *room);
    roomChangeOptions_ = *options;
}

void ObjectVolumes::addObjectBounce(const MipVolume& sceneVisibility, const Options& options,
                                    const RayScene* rays) {
    const VoxelBox& box = objects_.bounds;
    const std::vector<glm::vec3> added =
        rays && options.diffuse.objectRays > 0
            ? gatherObjectBounceByRays(fullLight_, objects_, objectVisibility_, sceneVisibility, *rays,
                                       options, box, kObjectBounceLevel)
            : gatherObjectBounce(fullLight_, objects_, objectVisibility_, sceneVisibility, options, box,
                                 kObjectBounceLevel);
    PackedGrid3& full = fullLight_.levelForUpdate(0);
    PackedGrid3& delta = deltaLight_.levelForUpdate(0);
    const glm::ivec3 extent = box.hi - box.lo;
    forEachRow(box, [&](int y, int z) {
        size_t k = (static_cast<size_t>(z - box.lo.z) * extent.y + (y - box.lo.y)) * extent.x;
        for (size_t i = full.index(box.lo.x, y, z), end = i + extent.x; i < end; ++i, ++k) {
            full.set(i, full[i] + glm::vec4(added[k], 0.0f));
            delta.set(i, delta[i] + glm::vec4(added[k], 0.0f));
        }
    });
    updateMipChain(fullLight_, box, unionOf(fullLight_.occupiedBounds(), box));
    updateMipChain(deltaLight_, box, unionOf(deltaLight_.occupiedBounds(), box));
    updateObjectLight(box);
}

void ObjectVolumes::updateRoomChange(const MipVolume& sceneVisibility, const Options& options,
                                     const RoomChangeInputs& room) {
    const VoxelGeometry& realGeometry = room.geometry;
    const int n = region_.resolution;
    const PackedGrid3& coarse =
        sceneVisibility.level(std::min(kRoomChangeLevel, sceneVisibility.levelCount() - 1));
    const int factor = n / coarse.resolution();
    const float voxelSize = region_.voxelSize(), coarseSize = voxelSize * static_cast<float>(factor);
    const VoxelBox& box = objects_.bounds;
    const int margin = std::max(1, n / kRoomChangeMarginDivisor);
    // The coarse voxels within the margin of the objects' box.
    const glm::ivec3 lo = glm::max(box.lo - margin, glm::ivec3(0)) / factor,
                     hi = (glm::min(box.hi + margin, glm::ivec3(n)) + factor - 1) / factor;
    const glm::vec3 objectCentre = room.rays.objectBounds.center();
    const RayScene& real = *room.rays.scene;
    // A point on each coherent coarse voxel's real surface, on the side that faces the objects.
    static const Material kGathering{};
    std::vector<SurfacePoint> points;
    std::vector<glm::ivec3> voxels;
    for (int z = lo.z; z < hi.z; ++z)
        for (int y = lo.y; y < hi.y; ++y)
            for (int x = lo.x; x < hi.x; ++x) {
                const std::optional<glm::vec3> meanNormal = gatheringNormal(coarse.at(x, y, z));
                if (!meanNormal) continue;
                const glm::vec3 centre = region_.origin + (glm::vec3(x, y, z) + 0.5f) * coarseSize;
                const glm::vec3 normal =
                    glm::dot(*meanNormal, objectCentre - centre) < 0.0f ? -*meanNormal : *meanNormal;
                const RayLanding surface = voxelSurfaceAlong(real, centre, normal, coarseSize);
                if (!surface.hit()) continue;
                SurfacePoint p;
                p.position = surface.position;
                p.normal = normal;
                p.material = &kGathering;
                p.surface.diffuse = glm::vec3(1.0f);  // the incoming light's change; the voxels' albedo below
                points.push_back(p);
                voxels.push_back({x, y, z});
            }
    if (points.empty()) return;
    const std::vector<glm::vec3> change = traceObjectBounceRays(points, objectLight_, room.rays, options, {},
                                                                RealLight{&fullLight_, &deltaLight_});
    // Each coarse voxel's change at its real surface voxels, by their albedo.
    const VoxelBox window{lo * factor, glm::min(hi * factor, glm::ivec3(n))};
    PackedGrid3 level0(n, window);
    VoxelBox written;
    for (size_t j = 0; j < points.size(); ++j) {
        const glm::vec3 incoming = change[j];
        if (incoming == glm::vec3(0.0f)) continue;
        const glm::ivec3 v0 = voxels[j] * factor, v1 = glm::min(v0 + factor, glm::ivec3(n));
        for (int z = v0.z; z < v1.z; ++z)
            for (int y = v0.y; y < v1.y; ++y) {
                auto [k, kEnd] = surfaceVoxelsInRow(realGeometry, y, z, v0.x);
                for (; k < kEnd; ++k) {
                    const uint32_t i = realGeometry.surfaceVoxels[k];
                    const int x = static_cast<int>(i % static_cast<uint32_t>(n));
                    if (x >= v1.x) break;
                    const float occupancy = realGeometry.occupancy(realGeometry.indexOf(i));
                    level0.set(x, y, z, glm::vec4(realGeometry.albedo[k] * incoming * occupancy, 0.0f));
                }
            }
        written.extend(VoxelBox{v0, v1});
    }
    if (written.empty()) return;
    roomChange_ = buildMipChain(region_, std::move(level0));
}

void ObjectVolumes::buildLightMips() {
    if (objectVisibility_.empty()) {
        objectVisibility_ = buildMipChain(region_, PackedGrid3(objects_.visibility, window_));
    } else {
        // Level 0 is the objects' voxels again: copy the box that changed (inside the window, which holds
        // where they are and were).
        PackedGrid3& level0 = objectVisibility_.levelForUpdate(0);
        const VoxelBox box = objectsChanged_.intersection(level0.window());
        forEachRow(box, [&](int y, int z) {
            for (int x = box.lo.x; x < box.hi.x; ++x) level0.set(x, y, z, objects_.visibility.at(x, y, z));
        });
        updateMipChain(objectVisibility_, box, nonZeroBounds(level0, objects_.bounds));
    }
    // Outside lightDiffers_ both are non-zero only where the scene's light is.
    auto occupiedOf = [&](const PackedGrid3& level0) {
        VoxelBox occupied = *sceneLightBounds_;
        occupied.extend(nonZeroBounds(level0, lightDiffers_.bounds()));
        return occupied;
    };
    auto update = [&](MipVolume& volume) {
        updateMipChain(volume, lightChanged_, occupiedOf(volume.level(0)));
    };
    if (freshFull_) {
        // Its occupied box from the scene's light's where that is known, not read from every voxel.
        if (sceneLightBounds_) {
            const VoxelBox occupied = occupiedOf(*freshFull_);
            fullLight_ = buildMipChain(region_, std::move(*freshFull_), occupied);
        } else {
            fullLight_ = buildMipChain(region_, std::move(*freshFull_));
        }
        freshFull_.reset();
        if (freshDelta_)
            deltaLight_ = buildMipChain(region_, std::move(*freshDelta_));
        else
            update(deltaLight_);  // a new light: the delta volume was rewritten in lightChanged_ only
        freshDelta_.reset();
        return;
    }
    update(fullLight_);
    update(deltaLight_);
}

}  // namespace deltagi
