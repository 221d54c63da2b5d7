// Importance sampling of the BRDFs (brdf.h). Phong: a mixture of a cosine-weighted hemisphere for the
// Lambertian part and the Phong lobe cos^n around the mirror direction for the glossy part, each lobe chosen
// with a probability proportional to its reflectance. The reference path tracer samples with these; the BRDF
// values themselves always come from evalBrdf(). Metallic-roughness: ggx.h's mixture of the cosine hemisphere
// and GGX's visible normals.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "core/brdf.h"
#include "core/ggx.h"
#include "core/sampling.h"
#include "deltagi/scene.h"

namespace deltagi {

// Direction around +z distributed as cos^n(alpha); pdf (n+1)/(2 pi) cos^n(alpha) on the hemisphere around +z.
inline glm::vec3 samplePowerCosine(float exponent, float u1, float u2) {
    const float cosAlpha = std::pow(1.0f - u1, 1.0f / (exponent + 1.0f));  // 1 - u1 in (0, 1]: no pow(0, .)
    const float sinAlpha = std::sqrt(std::max(0.0f, 1.0f - cosAlpha * cosAlpha));
    const float phi = 2.0f * std::numbers::pi_v<float> * u2;
    return {sinAlpha * std::cos(phi), sinAlpha * std::sin(phi), cosAlpha};
}

inline float powerCosinePdf(float exponent, float cosAlpha) {
    if (cosAlpha <= 0.0f) return 0.0f;
    return (exponent + 1.0f) * 0.5f * std::numbers::inv_pi_v<float> * std::pow(cosAlpha, exponent);
}

// Probability of sampling the diffuse lobe: its share of the mean reflectance (1 for a black material).
inline float diffuseLobeProbability(const SurfaceMaterial& m) {
    const float diffuse = (m.diffuse.x + m.diffuse.y + m.diffuse.z) / 3.0f;
    const float glossy = (m.specular.x + m.specular.y + m.specular.z) / 3.0f;
    return diffuse + glossy > 0.0f ? diffuse / (diffuse + glossy) : 1.0f;
}

// The density (per unit solid angle, over the whole sphere) with which sampleBrdf() generates wi.
// n: unit normal on the side of wo; wo, wi: unit, pointing away from the surface.
inline float brdfPdf(const SurfaceMaterial& m, glm::vec3 n, glm::vec3 wo, glm::vec3 wi) {
    if (m.model == MaterialModel::MetallicRoughness)
        return gltfBrdfPdf(m.diffuse, m.specular, m.roughness * m.roughness, n, wo, wi);
    const float pDiffuse = diffuseLobeProbability(m);
    float pdf = 0.0f;
    if (pDiffuse > 0.0f) pdf += pDiffuse * std::max(glm::dot(n, wi), 0.0f) * std::numbers::inv_pi_v<float>;
    if (pDiffuse < 1.0f) {
        const glm::vec3 mirror = glm::reflect(-wo, n);
        pdf += (1.0f - pDiffuse) * powerCosinePdf(m.phongExponent(), glm::dot(mirror, wi));
    }
    return pdf;
}

// Samples wi for the BRDF at a surface with unit normal n (on the side of wo) from three uniform numbers:
// uLobe picks the lobe, (u1, u2) the direction. The Phong lobe can reach below the surface: such samples come
// back with zero weight, which keeps the estimator unbiased (the lobe's mass there has zero integrand).
inline BrdfSample sampleBrdf(const SurfaceMaterial& m, glm::vec3 n, glm::vec3 wo, float uLobe, float u1,
                             float u2) {
    if (m.model == MaterialModel::MetallicRoughness)
        return sampleGltfBrdf(m.diffuse, m.specular, m.roughness * m.roughness, n, wo, uLobe, u1, u2);
    BrdfSample s;
    if (uLobe < diffuseLobeProbability(m)) {
        s.wi = frameAround(n) * sampleCosineHemisphere(u1, u2);
    } else {
        const glm::vec3 mirror = glm::reflect(-wo, n);
        s.wi = frameAround(mirror) * samplePowerCosine(m.phongExponent(), u1, u2);
    }
    s.wi = glm::normalize(s.wi);
    const float cosTheta = glm::dot(n, s.wi);
    s.pdf = brdfPdf(m, n, wo, s.wi);
    if (cosTheta <= 0.0f || !(s.pdf > 0.0f) || !std::isfinite(s.pdf)) return s;
    s.weight = evalBrdf(m, n, wo, s.wi) * (cosTheta / s.pdf);
    return s;
}

// The same for a material's factors (no textures).
inline float brdfPdf(const Material& m, glm::vec3 n, glm::vec3 wo, glm::vec3 wi) {
    return brdfPdf(constantSurfaceMaterial(m), n, wo, wi);
}
inline BrdfSample sampleBrdf(const Material& m, glm::vec3 n, glm::vec3 wo, float uLobe, float u1, float u2) {
    return sampleBrdf(constantSurfaceMaterial(m), n, wo, uLobe, u1, u2);
}

}  // namespace deltagi
