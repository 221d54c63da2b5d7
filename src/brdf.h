// The one BRDF of deltagi (see deltagi::Material): Lambertian diffuse plus a normalized Phong lobe around the
// mirror direction. The cone tracer and the reference path tracer both evaluate it here.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "deltagi/scene.h"

namespace deltagi {

// f(wi, wo) for unit vectors pointing away from the surface; n is the unit normal on the side of wo.
inline glm::vec3 evalBrdf(const Material& m, glm::vec3 n, glm::vec3 wo, glm::vec3 wi) {
    glm::vec3 f = m.albedo * std::numbers::inv_pi_v<float>;
    if (m.specular != glm::vec3(0.0f)) {
        const float exponent = m.phongExponent();
        const glm::vec3 mirror = glm::reflect(-wo, n);
        const float c = std::max(glm::dot(mirror, wi), 0.0f);
        f += m.specular * ((exponent + 2.0f) * 0.5f * std::numbers::inv_pi_v<float> * std::pow(c, exponent));
    }
    return f;
}

}  // namespace deltagi
