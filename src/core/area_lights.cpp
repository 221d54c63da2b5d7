#include "core/area_lights.h"

#include <algorithm>
#include <cmath>

#include "core/surface_material.h"

namespace deltagi {

AreaLights::AreaLights(const Scene& scene, SceneContent content) {
    auto add = [&](const TriangleMesh& mesh, bool isVirtual) {
        if (!mesh.material.emits()) return;
        for (unsigned i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3 t = mesh.triangles[i];
            const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
            const glm::vec3 cross = glm::cross(b - a, c - a);
            const float doubleArea = glm::length(cross);
            if (!(doubleArea > 0.0f)) continue;  // never sampled, and a ray cannot hit it either
            const glm::vec3 emission = triangleEmission(mesh, i);
            triangles_.push_back({a, b, c, cross / doubleArea, emission, isVirtual});
            for (const glm::vec3& corner : {a, b, c}) bounds_.extend(corner);
            anyVirtual_ = anyVirtual_ || isVirtual;
            totalPower_ += 0.5 * static_cast<double>(doubleArea) * emitterWeight(emission);
            cdf_.push_back(totalPower_);
        }
    };
    if (content != SceneContent::VirtualOnly)
        for (const TriangleMesh& m : scene.real) add(m, false);
    if (content != SceneContent::RealOnly)
        for (const TriangleMesh& m : scene.virtuals) add(m, true);
}

AreaLightSample AreaLights::sample(float uTriangle, float u1, float u2) const {
    AreaLightSample s;
    if (triangles_.empty()) return s;
    const double target = static_cast<double>(uTriangle) * totalPower_;
    const size_t i =
        std::min(static_cast<size_t>(std::upper_bound(cdf_.begin(), cdf_.end(), target) - cdf_.begin()),
                 triangles_.size() - 1);
    const Triangle& t = triangles_[i];
    // Uniform on the triangle: barycentrics (1 - sqrt(u1), u2 sqrt(u1)).
    const float su = std::sqrt(u1);
    const float b0 = 1.0f - su, b1 = u2 * su;
    s.position = b0 * t.a + b1 * t.b + (1.0f - b0 - b1) * t.c;
    s.normal = t.normal;
    s.radiance = t.radiance;
    s.pdfArea = pdfArea(t.radiance);
    s.isVirtual = t.isVirtual;
    return s;
}

}  // namespace deltagi
