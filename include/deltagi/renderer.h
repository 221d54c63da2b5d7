// The Delta Global Illumination pipeline (Thöner & Kuijper, §3): one call renders the augmented image.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "deltagi/image.h"
#include "deltagi/math.h"
#include "deltagi/scene.h"

namespace deltagi {

struct StageTiming {
    std::string name;  // voxelize, rsm, inject, mipmap, gbuffer, diffuse, specular, shadow, shading, composite...
    double ms = 0.0;
};

struct RenderOutput {
    Image composite;   // the augmented image, linear RGB
    Image background;  // the camera image used (given or rendered), linear RGB
    Image objectMask;  // 1 channel: coverage of virtual objects per pixel, in [0,1]
    Image delta;       // composite - background, linear RGB (negative where light was removed)
    std::vector<StageTiming> timings;  // in pipeline order
    double totalMs = 0.0;
};

// Called after each stage, for progress output: the stage's name and its time.
using StageCallback = std::function<void(const StageTiming&)>;

RenderOutput render(const Scene& scene, const StageCallback& onStage = {});

// The cubic region covered by the volumes: the explicit options.volume region, or extent_scale times the
// virtual objects' bounding box (§3.4); the real scene's bounds when there are no virtual objects.
struct VolumeRegion {
    glm::vec3 origin{0.0f};  // world-space corner with the smallest coordinates
    float size = 1.0f;       // edge length, world units
    int resolution = 1;      // voxels per edge (level 0)
    float voxelSize() const { return size / static_cast<float>(resolution); }
    Bounds3f bounds() const { return {origin, origin + glm::vec3(size)}; }
};
VolumeRegion volumeRegion(const Scene& scene);

}  // namespace deltagi
