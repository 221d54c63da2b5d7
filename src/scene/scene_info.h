// What `deltagi info` prints: the size of a scene and of the volumes it needs.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/renderer.h"
#include "deltagi/scene.h"

namespace deltagi {

struct SceneInfo {
    size_t realMeshes = 0, realTriangles = 0;
    size_t virtualMeshes = 0, virtualTriangles = 0;
    size_t lights = 0;
    Bounds3f realBounds, virtualBounds;
    VolumeRegion region;
    int mipLevels = 0;
    // A volume stores 4 bfloat16 per voxel over the whole mip chain: bytesPerVolume for each of the three
    // stored whole (the real scene's visibility, the full and the delta light), bytesObjectVolumes for the
    // objects' visibility and light over the objects' box, bytesAllVolumes for the five.
    size_t bytesPerVolume = 0;
    size_t bytesObjectVolumes = 0;
    size_t bytesAllVolumes = 0;
    // The memory guard's estimate of a render's peak (estimateRenderMemory, scene/json_reader.h).
    uint64_t renderBytes = 0;
};

SceneInfo sceneInfo(const Scene& scene);
nlohmann::json toJson(const SceneInfo& info);

// Point and spot lights placed where the path tracer cannot render them as the pipeline does: a light's
// sphere (its "radius"; a point light without one is a point) that intersects a surface of the real scene or
// of the virtual objects, i.e. whose centre lies within its radius of a triangle (for radius 0: on it, to
// kLightClearanceScale of the scene's extent). Part of such a lamp lies inside or behind the surface: the
// path tracer loses that part's light (shadow rays towards it are blocked), DGI's cones do not. One warning
// per light, naming the light by its JSON path ("lights[0]"), the surfaces and the distance.
std::vector<std::string> lightPlacementWarnings(const Scene& scene);

// Clearance of a light without radius, as a fraction of the scene's largest extent.
constexpr float kLightClearanceScale = 1e-4f;

// Bytes of one volume of `resolution`^3 voxels with its full mip chain, 8 bytes per voxel.
size_t volumeBytes(int resolution);
// The same for a volume stored over the level-0 voxels [lo, hi) (clipped to the grid) and their parents at
// each coarser level.
size_t windowedVolumeBytes(int resolution, glm::ivec3 lo, glm::ivec3 hi);

}  // namespace deltagi
