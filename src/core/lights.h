// Light from point, spot and directional lights arriving at a point (no shadowing).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <glm/glm.hpp>

#include "deltagi/scene.h"

namespace deltagi {

// A light's falloff over directions from it: spot cone, Lambertian emitter or none, with a spot's cosines
// computed once for many directions.
class SpotCone {
  public:
    explicit SpotCone(const Light& light)
        : direction_(light.direction),
          lambertian_(light.lambertian),
          spot_(!light.lambertian && light.type == Light::Type::Spot) {
        if (lambertian_) reach_ = 0.5f * std::numbers::pi_v<float>;
        if (!spot_) return;
        cosOuter_ = std::cos(glm::radians(light.outerAngleDeg));
        cosInner_ = std::cos(glm::radians(light.innerAngleDeg));
        reach_ = glm::radians(light.outerAngleDeg);
    }

    // 1 inside the inner half-angle, 0 outside the outer one, smooth in between (Lambertian emitters: the
    // cosine to the axis; other lights: 1).
    float falloff(glm::vec3 directionFromLight) const {
        if (lambertian_) return std::max(glm::dot(directionFromLight, direction_), 0.0f);
        if (!spot_) return 1.0f;
        const float cosTheta = glm::dot(directionFromLight, direction_);
        if (cosInner_ - cosOuter_ <= 1e-6f) return cosTheta >= cosOuter_ ? 1.0f : 0.0f;
        return glm::smoothstep(cosOuter_, cosInner_, cosTheta);
    }
    // The largest angle (radians) from the axis at which the falloff is not 0: pi for a light without one.
    float reach() const { return reach_; }
    // False only where falloff(normalize(d)) is 0 for sure, d any direction from the light (not unit length):
    // a test without square roots, a hair wider than the falloff's own.
    bool mayReach(glm::vec3 d) const {
        if (lambertian_) return glm::dot(d, direction_) > -1e-6f * glm::length(d);
        if (!spot_) return true;
        const float c = glm::dot(d, direction_);
        if (cosOuter_ <= 0.0f) return true;  // a cone of 90 degrees or more: the exact test decides
        constexpr float kMargin = 1e-4f;
        const float cosWider = cosOuter_ * (1.0f - kMargin);
        return c > 0.0f && c * c >= cosWider * cosWider * glm::dot(d, d);
    }

  private:
    glm::vec3 direction_;
    bool lambertian_, spot_;
    float cosOuter_ = -1.0f, cosInner_ = -1.0f, reach_ = std::numbers::pi_v<float>;
};

// Spot cone: 1 inside the inner half-angle, 0 outside the outer one, smooth in between.
inline float spotFalloff(const Light& light, glm::vec3 directionFromLight) {
    return SpotCone(light).falloff(directionFromLight);
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
