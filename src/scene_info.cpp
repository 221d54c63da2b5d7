// What `deltagi info` reports: triangle and light counts, bounds, and the size of the four volumes (§3.2,
// §3.4).
#include "deltagi/scene_info.h"

#include <span>

namespace deltagi {
namespace {

// Each voxel of a volume holds 4 floats: RGB light + occlusion, or average normal + occlusion (§3.2).
constexpr size_t kBytesPerVoxel = 4 * sizeof(float);
// The four volumes of §3.2: visibility of the real scene and of the virtual objects, light for shading and
// the delta light for relighting.
constexpr size_t kVolumeCount = 4;

Bounds3f boundsOf(std::span<const TriangleMesh> meshes) {
    Bounds3f bounds;
    for (const TriangleMesh& mesh : meshes) bounds.extend(mesh.bounds());
    return bounds;
}

size_t trianglesOf(std::span<const TriangleMesh> meshes) {
    size_t count = 0;
    for (const TriangleMesh& mesh : meshes) count += mesh.triangleCount();
    return count;
}

// Levels of a full mip chain: resolution, resolution/2, ..., 1.
int mipLevelCount(int resolution) {
    int levels = 0;
    for (int r = resolution; r >= 1; r /= 2) ++levels;
    return levels;
}

nlohmann::json vecToJson(glm::vec3 v) {
    return nlohmann::json::array({v.x, v.y, v.z});
}

// An empty box (no meshes) has infinite corners, which JSON cannot hold: it is written as null.
nlohmann::json boundsToJson(const Bounds3f& bounds) {
    if (bounds.empty()) return nullptr;
    return {{"min", vecToJson(bounds.min)}, {"max", vecToJson(bounds.max)}};
}

}  // namespace

size_t volumeBytes(int resolution) {
    size_t voxels = 0;
    for (size_t r = resolution > 0 ? static_cast<size_t>(resolution) : 0; r >= 1; r /= 2) voxels += r * r * r;
    return voxels * kBytesPerVoxel;
}

SceneInfo sceneInfo(const Scene& scene) {
    SceneInfo info;
    info.realMeshes = scene.real.size();
    info.realTriangles = trianglesOf(scene.real);
    info.virtualMeshes = scene.virtuals.size();
    info.virtualTriangles = trianglesOf(scene.virtuals);
    info.lights = scene.lights.size();
    info.realBounds = boundsOf(scene.real);
    info.virtualBounds = boundsOf(scene.virtuals);
    info.region = volumeRegion(scene);
    info.mipLevels = mipLevelCount(info.region.resolution);
    info.bytesPerVolume = volumeBytes(info.region.resolution);
    info.bytesAllVolumes = kVolumeCount * info.bytesPerVolume;
    return info;
}

nlohmann::json toJson(const SceneInfo& info) {
    return {
        {"real",
         {{"meshes", info.realMeshes},
          {"triangles", info.realTriangles},
          {"bounds", boundsToJson(info.realBounds)}}},
        {"virtual",
         {{"meshes", info.virtualMeshes},
          {"triangles", info.virtualTriangles},
          {"bounds", boundsToJson(info.virtualBounds)}}},
        {"lights", info.lights},
        {"volume",
         {{"origin", vecToJson(info.region.origin)},
          {"size", info.region.size},
          {"resolution", info.region.resolution},
          {"voxel_size", info.region.voxelSize()},
          {"mip_levels", info.mipLevels},
          {"bytes_per_volume", info.bytesPerVolume},
          {"bytes_all_volumes", info.bytesAllVolumes}}},
    };
}

}  // namespace deltagi
