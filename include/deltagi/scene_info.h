// What `deltagi info` prints: the size of a scene and of the volumes it needs.
#pragma once

#include <cstddef>

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
    // Each of the four volumes (two visibility, two light) stores 4 floats per voxel over the whole mip chain.
    size_t bytesPerVolume = 0;
    size_t bytesAllVolumes = 0;
};

SceneInfo sceneInfo(const Scene& scene);
nlohmann::json toJson(const SceneInfo& info);

// Bytes of one volume of `resolution`^3 voxels with its full mip chain, 16 bytes per voxel.
size_t volumeBytes(int resolution);

}  // namespace deltagi
