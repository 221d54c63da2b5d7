// Sampling building blocks shared by the BRDFs' samplers (brdf_sampling.h, ggx.h) and the cone and ray
// passes: a frame around a direction, cosine-weighted hemisphere directions, and a BRDF sample.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

namespace deltagi {

// An orthonormal frame whose third column is the unit vector z (Duff et al. 2017, "Building an Orthonormal
// Basis, Revisited"): local (x, y, z) maps to world by frame * local.
inline glm::mat3 frameAround(glm::vec3 z) {
    const float sign = std::copysign(1.0f, z.z);
    const float a = -1.0f / (sign + z.z);
    const float b = z.x * z.y * a;
    const glm::vec3 x(1.0f + sign * z.x * z.x * a, sign * b, -sign * z.x);
    const glm::vec3 y(b, sign + z.y * z.y * a, -z.y);
    return glm::mat3(x, y, z);
}

// Shirley & Chiu's concentric map of the unit square onto the unit disk: keeps the grid's strata compact.
inline glm::vec2 concentricDisk(float u, float v) {
    const float a = 2.0f * u - 1.0f, b = 2.0f * v - 1.0f;
    if (a == 0.0f && b == 0.0f) return glm::vec2(0.0f);
    constexpr float kQuarterPi = std::numbers::pi_v<float> / 4.0f;
    float r, phi;
    if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = kQuarterPi * (b / a);
    } else {
        r = b;
        phi = 2.0f * kQuarterPi - kQuarterPi * (a / b);
    }
    return r * glm::vec2(std::cos(phi), std::sin(phi));
}

// Cosine-weighted direction on the hemisphere around +z; pdf cos(theta)/pi.
inline glm::vec3 sampleCosineHemisphere(float u1, float u2) {
    const float r = std::sqrt(u1);
    const float phi = 2.0f * std::numbers::pi_v<float> * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1))};
}

// One sampled direction of a BRDF: wi, the estimator's weight and the density it was drawn with.
struct BrdfSample {
    glm::vec3 wi{0.0f};      // unit, away from the surface
    glm::vec3 weight{0.0f};  // f(wi, wo) * cos(theta_i) / pdf; zero when the sample is below the surface
    float pdf = 0.0f;        // per unit solid angle, over the whole sphere
    bool valid() const { return pdf > 0.0f && weight != glm::vec3(0.0f); }
};

}  // namespace deltagi
