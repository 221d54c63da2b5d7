// Stage 5: the G-buffer from the camera: per pixel, the real surface the photo shows (a ray against the real
// scene alone), the virtual surface in front of it if any, and the coverage of virtual objects over the
// pixel's sub-samples, which anti-aliases the silhouette in the composite. Depth comparison decides which
// pixels are virtual (§3.3).
#pragma once

#include <vector>

#include "deltagi/scene.h"
#include "ray_scene.h"

namespace deltagi {

struct SurfacePoint {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};  // unit, facing the camera
    glm::vec3 toEye{0.0f};   // unit, from the surface to the camera
    const Material* material = nullptr;  // null: no surface
    bool valid() const { return material != nullptr; }
};

struct GBuffer {
    int width = 0, height = 0;
    std::vector<SurfacePoint> real;     // the real surface behind the pixel centre (what the photo shows)
    std::vector<SurfacePoint> object;   // the virtual surface seen in the pixel, where coverage > 0
    std::vector<float> coverage;        // fraction of sub-samples that see a virtual object first
};

// `samplesPerPixel` is a square number: the sub-samples are a regular k x k grid in the pixel.
GBuffer renderGBuffer(const Camera& camera, const RayScene& all, const RayScene& realOnly, int samplesPerPixel);

}  // namespace deltagi
