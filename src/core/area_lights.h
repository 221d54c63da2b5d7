// Emissive triangles as lights for the reference path tracer (mesh area lights). Next-event estimation picks
// a triangle with probability proportional to its emitted power (area times the mean of its RGB radiance) and
// a uniform point on it, so that the density per unit area of a point is the same on every triangle of equal
// radiance: pdfArea() needs only the radiance of the surface a ray hit, not which triangle it was.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "core/ray_scene.h"
#include "deltagi/scene.h"

namespace deltagi {

// The scalar that emitters are sampled by: the mean of the RGB radiance.
inline float emitterWeight(glm::vec3 emission) {
    return (emission.x + emission.y + emission.z) / 3.0f;
}

struct AreaLightSample {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};    // unit plane normal of the triangle (either side: emitters are two-sided)
    glm::vec3 radiance{0.0f};  // emitted radiance
    float pdfArea = 0.0f;      // density of `position` per unit area
    bool isVirtual = false;    // on a virtual object's triangle
};

class AreaLights {
  public:
    // The emissive triangles of the meshes a RayScene of the same `content` holds (without a base layer), in
    // its order (real meshes, then virtual ones), so that two sets built from the same real meshes sample
    // them alike.
    AreaLights(const Scene& scene, SceneContent content);

    bool empty() const { return triangles_.empty(); }
    size_t size() const { return triangles_.size(); }
    // The box around every sampled point, and whether a virtual object's triangle is among them.
    const Bounds3f& bounds() const { return bounds_; }
    bool anyVirtual() const { return anyVirtual_; }
    // uTriangle picks the triangle, (u1, u2) the point on it; all three in [0, 1).
    AreaLightSample sample(float uTriangle, float u1, float u2) const;
    // The density per unit area with which sample() returns a point of a surface emitting `emission`.
    float pdfArea(glm::vec3 emission) const {
        return totalPower_ > 0.0 ? static_cast<float>(emitterWeight(emission) / totalPower_) : 0.0f;
    }

  private:
    struct Triangle {
        glm::vec3 a, b, c;
        glm::vec3 normal;
        glm::vec3 radiance;
        bool isVirtual;
    };
    std::vector<Triangle> triangles_;
    std::vector<double> cdf_;  // running sum of area * emitterWeight, one per triangle
    double totalPower_ = 0.0;
    Bounds3f bounds_;
    bool anyVirtual_ = false;
};

}  // namespace deltagi
