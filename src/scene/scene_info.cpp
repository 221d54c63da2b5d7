// What `deltagi info` reports: triangle and light counts, bounds, and the size of the four volumes (§3.2,
// §3.4).
#include "scene/scene_info.h"

#include <algorithm>
#include <cmath>
#include <span>

#include <fmt/format.h>

#include "scene/json_reader.h"

namespace deltagi {
namespace {

// Each voxel of a volume holds 4 bfloat16: RGB light + occlusion, or average normal + occlusion (§3.2).
constexpr size_t kBytesPerVoxel = 4 * sizeof(uint16_t);
// The volumes stored whole: the real scene's visibility, the full light for shading and the delta light for
// relighting (§3.2).
constexpr size_t kWholeVolumeCount = 3;
// The objects' visibility and their own light (the full light where they are) are stored over the objects'
// box and this many voxels around it (ObjectVolumes, pipeline/object_volumes.cpp: kWindowMargin).
constexpr size_t kObjectVolumeCount = 2;
constexpr int kObjectWindowMargin = 4;

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

// The point of triangle (a, b, c) closest to p (Ericson, Real-Time Collision Detection, 5.1.5).
glm::vec3 closestPointOnTriangle(glm::vec3 p, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
    const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f) return a;
    const glm::vec3 bp = p - b;
    const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3) return b;
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + ab * (d1 / (d1 - d3));
    const glm::vec3 cp = p - c;
    const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6) return c;
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + ac * (d2 / (d2 - d6));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const float denominator = va + vb + vc;
    if (!(std::abs(denominator) > 0.0f)) return a;  // a degenerate triangle: its first corner
    return a + ab * (vb / denominator) + ac * (vc / denominator);
}

// Distance from p to the closest triangle of the mesh.
float distanceToMesh(glm::vec3 p, const TriangleMesh& mesh) {
    float best = std::numeric_limits<float>::infinity();
    for (const glm::uvec3& t : mesh.triangles) {
        const glm::vec3 q =
            closestPointOnTriangle(p, mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]);
        best = std::min(best, glm::length(p - q));
    }
    return best;
}

}  // namespace

std::vector<std::string> lightPlacementWarnings(const Scene& scene) {
    Bounds3f bounds = boundsOf(scene.real);
    bounds.extend(boundsOf(scene.virtuals));
    const float clearance = kLightClearanceScale * (bounds.empty() ? 1.0f : bounds.maxExtent());
    std::vector<std::string> warnings;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& light = scene.lights[i];
        if (light.type == Light::Type::Directional || light.fromEnvironment) continue;
        const float reach = std::max(light.radius, clearance);
        std::string surfaces;
        float closest = std::numeric_limits<float>::infinity();
        for (const auto& [meshes, kind] :
             {std::pair{std::span<const TriangleMesh>(scene.real), "real"},
              std::pair{std::span<const TriangleMesh>(scene.virtuals), "virtual"}})
            for (const TriangleMesh& mesh : meshes) {
                const float d = distanceToMesh(light.position, mesh);
                if (!(d < reach)) continue;
                closest = std::min(closest, d);
                surfaces += fmt::format("{}{} '{}'", surfaces.empty() ? "" : ", ", kind, mesh.name);
            }
        if (surfaces.empty()) continue;
        const glm::vec3 p = light.position;
        if (light.radius > 0.0f)
            warnings.push_back(fmt::format(
                "lights[{}]: the light's sphere (centre ({:.4g}, {:.4g}, {:.4g}), radius {:.4g}) intersects "
                "the "
                "surface of {} ({:.4g} from its centre): the path tracer loses the light of the part inside "
                "or behind it, DGI does not; move the light at least {:.4g} further from the surface",
                i, p.x, p.y, p.z, light.radius, surfaces, closest, light.radius - closest));
        else
            warnings.push_back(
                fmt::format("lights[{}]: the light at ({:.4g}, {:.4g}, {:.4g}) lies on the surface of {} "
                            "({:.3g} from it): "
                            "half of its light goes behind the surface; move it off the surface",
                            i, p.x, p.y, p.z, surfaces, closest));
    }
    return warnings;
}

size_t windowedVolumeBytes(int resolution, glm::ivec3 lo, glm::ivec3 hi) {
    size_t voxels = 0;
    for (int r = resolution; r >= 1; r /= 2) {
        lo = glm::max(lo, glm::ivec3(0));
        hi = glm::min(hi, glm::ivec3(r));
        if (glm::any(glm::lessThanEqual(hi, lo))) return 0;
        voxels += static_cast<size_t>(hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
        lo >>= 1;
        hi = (hi + 1) >> 1;
    }
    return voxels * kBytesPerVoxel;
}

size_t volumeBytes(int resolution) {
    return windowedVolumeBytes(resolution, glm::ivec3(0), glm::ivec3(resolution));
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
    if (!scene.virtuals.empty()) {
        const float voxel = info.region.voxelSize();
        const glm::ivec3 lo = glm::ivec3(glm::floor((info.virtualBounds.min - info.region.origin) / voxel)) -
                              kObjectWindowMargin;
        const glm::ivec3 hi = glm::ivec3(glm::floor((info.virtualBounds.max - info.region.origin) / voxel)) +
                              1 + kObjectWindowMargin;
        info.bytesObjectVolumes = kObjectVolumeCount * windowedVolumeBytes(info.region.resolution, lo, hi);
    }
    info.bytesAllVolumes = kWholeVolumeCount * info.bytesPerVolume + info.bytesObjectVolumes;
    const size_t directional =
        static_cast<size_t>(std::count_if(scene.lights.begin(), scene.lights.end(),
                                          [](const Light& l) { return l.type == Light::Type::Directional; }));
    info.renderBytes = estimateRenderMemory(scene.options, scene.camera, scene.lights.size() - directional,
                                            directional, info.realTriangles + info.virtualTriangles);
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
          {"bytes_object_volumes", info.bytesObjectVolumes},
          {"bytes_all_volumes", info.bytesAllVolumes}}},
        {"render_memory_bytes", info.renderBytes},
    };
}

}  // namespace deltagi
