// Brute-force integration over a cone of directions (a sphere light's disk seen from a point), for checking
// the lobes and quadratures that stand for it.
#pragma once

#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "core/sampling.h"

namespace deltagi::test {

// The mean of f(wi) over directions wi spread uniformly over the solid angle of the cone of half-angle
// `halfAngle` around the unit `axis` (as the path tracer's samples of a sphere light spread), on a
// side x side grid in (cos theta, phi).
template <typename F>
double meanOverCone(glm::vec3 axis, float halfAngle, int side, F&& f) {
    const glm::mat3 around = frameAround(axis);
    double sum = 0.0;
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const float cosTheta = 1.0f - (i + 0.5f) / side * (1.0f - std::cos(halfAngle));
            const float sinTheta = std::sqrt(1.0f - cosTheta * cosTheta);
            const float phi = 2.0f * std::numbers::pi_v<float> * (j + 0.5f) / side;
            sum += f(around * glm::vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta));
        }
    return sum / (static_cast<double>(side) * side);
}

}  // namespace deltagi::test
