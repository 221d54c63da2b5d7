// Light from point, spot and directional lights arriving at a point (no shadowing).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "deltagi/scene.h"

namespace deltagi {

// Spot cone: 1 inside the inner half-angle, 0 outside the outer one, smooth in between.
inline float spotFalloff(const Light& light, glm::vec3 directionFromLight) {
    if (light.lambertian) return std::max(glm::dot(directionFromLight, light.direction), 0.0f);
    if (light.type != Light::Type::Spot) return 1.0f;
    const float cosTheta = glm::dot(directionFromLight, light.direction);
    const float cosOuter = std::cos(glm::radians(light.outerAngleDeg));
    const float cosInner = std::cos(glm::radians(light.innerAngleDeg));
    if (cosInner - cosOuter <= 1e-6f) return cosTheta >= cosOuter ? 1.0f : 0.0f;
    return glm::smoothstep(cosOuter, cosInner, cosTheta);
}

struct LightSample {
    glm::vec3 wi{0.0f};          // unit direction from the point towards the light
    float distance = 0.0f;       // to the light; infinity for directional lights
    glm::vec3 irradiance{0.0f};  // on a surface facing the light (W/m^2): I/d^2 or E; times cos for others
};

inline LightSample sampleLight(const Light& light, glm::vec3 p) {
    LightSample s;
    if (light.type == Light::Type::Directional) {
        s.wi = -light.direction;
        s.distance = std::numeric_limits<float>::infinity();
        s.irradiance = light.power();
        return s;
    }
    glm::vec3 toLight = light.position - p;
    float d2 = glm::dot(toLight, toLight);
    if (!(d2 > 0.0f)) return s;
    s.distance = std::sqrt(d2);
    s.wi = toLight / s.distance;
    s.irradiance = light.power() * (spotFalloff(light, -s.wi) / d2);
    return s;
}

}  // namespace deltagi
