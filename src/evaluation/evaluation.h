// Internals of the evaluation (deltagi/evaluation.h), exposed for tests.
#pragma once

#include "core/ray_scene.h"
#include "deltagi/evaluation.h"

namespace deltagi {

// Light samples per light (a square grid over the sphere light's disk) for the lit/shadowed decision.
constexpr int kVisibilitySamplesPerLight = 16;

// Fraction of the unoccluded direct irradiance at `position` (normal `normal`) that arrives past `occluders`;
// -1 where no light reaches the point at all (facing away, outside every spot cone).
double directVisibility(const RayScene& occluders, std::span<const Light> lights, glm::vec3 position,
                        glm::vec3 normal, float rayOffset);

// Real, object and silhouette pixels from the two coverage masks (1 channel each), and lit vs shadowed real
// pixels by directVisibility() in the scene with the objects.
PixelClasses classifyPixels(const Scene& scene, const Image& dgiMask, const Image& referenceMask);

}  // namespace deltagi
