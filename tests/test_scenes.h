// Small scenes built in code for the pipeline tests (no files needed).
#pragma once

#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/scene.h"
#include "pipeline/gbuffer.h"
#include "scene/mesh_io.h"
#include "scene/shapes.h"

namespace deltagi::test {

inline TriangleMesh placed(TriangleMesh mesh, glm::vec3 translate, Material material,
                           std::string name = "mesh") {
    transformMesh(mesh, glm::translate(glm::mat4(1.0f), translate));
    mesh.material = material;
    mesh.name = std::move(name);
    return mesh;
}

inline Material diffuse(glm::vec3 albedo) {
    Material m;
    m.albedo = albedo;
    return m;
}

// A camera at `eye` looking at `target`, +y up.
inline Camera lookAtCamera(glm::vec3 eye, glm::vec3 target, int width, int height, float fovYDeg) {
    Camera c;
    c.width = width;
    c.height = height;
    c.fy = 0.5f * height / std::tan(0.5f * glm::radians(fovYDeg));
    c.fx = c.fy;
    c.cx = 0.5f * width;
    c.cy = 0.5f * height;
    c.worldFromCamera = glm::inverse(glm::lookAt(eye, target, glm::vec3(0, 1, 0)));
    return c;
}

// The pixel (x, y) that sees world point p (assumes p is in front of the camera).
inline glm::ivec2 project(const Camera& c, glm::vec3 p) {
    glm::vec3 q = glm::vec3(glm::inverse(c.worldFromCamera) * glm::vec4(p, 1.0f));
    float px = c.cx + c.fx * (q.x / -q.z);
    float py = c.cy - c.fy * (q.y / -q.z);
    return {static_cast<int>(std::floor(px)), static_cast<int>(std::floor(py))};
}

// A G-buffer point at `p` on a floor (normal and view +y) of `material`.
inline SurfacePoint floorPoint(glm::vec3 p, const Material& material) {
    SurfacePoint s;
    s.position = p;
    s.normal = glm::vec3(0, 1, 0);
    s.toEye = glm::vec3(0, 1, 0);
    s.material = &material;
    s.surface = constantSurfaceMaterial(material);
    return s;
}

inline Light pointLight(glm::vec3 position, float intensity) {
    Light l;
    l.type = Light::Type::Point;
    l.position = position;
    l.intensity = intensity;
    return l;
}

// A directional light along `direction` (normalized here) with irradiance `irradiance`.
inline Light directionalLight(glm::vec3 direction, float irradiance) {
    Light l;
    l.type = Light::Type::Directional;
    l.direction = glm::normalize(direction);
    l.intensity = irradiance;
    return l;
}

// A 2 x 2 grey floor at y = 0, a point light 1.5 above it and a camera looking down at it from the front.
// Small volumes and images, so a render takes well under a second.
inline Scene floorScene() {
    Scene s;
    s.real.push_back(placed(makeQuad({2.0f, 2.0f}), {0, 0, 0}, diffuse(glm::vec3(0.5f)), "floor"));
    s.lights.push_back(pointLight({0.0f, 1.5f, 0.0f}, 2.0f));
    s.camera = lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, 64, 48, 60.0f);
    s.options.volume.resolution = 32;
    s.options.rsm.resolution = 128;
    s.options.diffuse.count = 6;
    return s;
}

}  // namespace deltagi::test
