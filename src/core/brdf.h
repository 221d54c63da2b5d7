// The BRDFs of deltagi (see deltagi::Material): Lambertian diffuse plus a normalized Phong lobe around the
// mirror direction, or glTF's metallic-roughness BRDF (ggx.h). The cone tracer and the reference path tracer
// both evaluate them here.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "core/ggx.h"
#include "core/surface_material.h"
#include "deltagi/scene.h"

namespace deltagi {

// The Phong lobe cos^n averaged over a light of angular radius R (radians, the half-angle it subtends), as
// the lobe `scale * cos^exponent` of the light's centre: the lobe is about a Gaussian of angular variance
// 1/n, the uniform disk of the light has R^2 / 4 per axis, and their convolution has the sum (the exponent);
// its peak is the Gaussian's mean over the disk, 2 (1 - exp(-n R^2 / 2)) / (n R^2) of the lobe's (the scale).
// So a point light's BRDF shades a sphere light's glossy highlight as wide and as dim as its disk makes it.
struct LobeOverLight {
    float exponent;
    float scale;
};
inline LobeOverLight phongLobeOverLight(float exponent, float lightAngle) {
    const float spread = exponent * lightAngle * lightAngle;
    if (!(spread > 1e-4f)) return {exponent, 1.0f};
    return {1.0f / (1.0f / exponent + 0.25f * lightAngle * lightAngle),
            2.0f * (1.0f - std::exp(-0.5f * spread)) / spread};
}

// f(wi, wo) for unit vectors pointing away from the surface; n is the unit normal on the side of wo.
// `lightAngle`: the half-angle of the light wi points at (0: a point), see phongLobeOverLight.
inline glm::vec3 evalBrdf(const SurfaceMaterial& m, glm::vec3 n, glm::vec3 wo, glm::vec3 wi,
                          float lightAngle = 0.0f) {
    if (m.model == MaterialModel::MetallicRoughness)
        return evalGltfBrdf(m.diffuse, m.specular, m.roughness * m.roughness, n, wo, wi, lightAngle);
    glm::vec3 f = m.diffuse * std::numbers::inv_pi_v<float>;
    if (m.specular != glm::vec3(0.0f)) {
        const float exponent = m.phongExponent();
        const LobeOverLight lobe = phongLobeOverLight(exponent, lightAngle);
        const glm::vec3 mirror = glm::reflect(-wo, n);
        const float c = std::max(glm::dot(mirror, wi), 0.0f);
        f += m.specular * ((exponent + 2.0f) * 0.5f * std::numbers::inv_pi_v<float> * lobe.scale *
                           std::pow(c, lobe.exponent));
    }
    return f;
}

// The BRDF of a material's factors (no textures): tests and callers without a surface point.
inline glm::vec3 evalBrdf(const Material& m, glm::vec3 n, glm::vec3 wo, glm::vec3 wi,
                          float lightAngle = 0.0f) {
    return evalBrdf(constantSurfaceMaterial(m), n, wo, wi, lightAngle);
}

}  // namespace deltagi
