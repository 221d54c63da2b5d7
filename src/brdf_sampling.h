// Importance sampling of the one BRDF (brdf.h): a mixture of a cosine-weighted hemisphere for the Lambertian
// part and the Phong lobe cos^n around the mirror direction for the glossy part, each lobe chosen with a
// probability proportional to its reflectance. The reference path tracer samples with these; the BRDF values
// themselves always come from evalBrdf().
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "brdf.h"
#include "deltagi/scene.h"

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

// Cosine-weighted direction on the hemisphere around +z; pdf cos(theta)/pi.
inline glm::vec3 sampleCosineHemisphere(float u1, float u2) {
    const float r = std::sqrt(u1);
    const float phi = 2.0f * std::numbers::pi_v<float> * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1))};
}

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
inline float diffuseLobeProbability(const Material& m) {
    const float diffuse = (m.albedo.x + m.albedo.y + m.albedo.z) / 3.0f;
    const float glossy = (m.specular.x + m.specular.y + m.specular.z) / 3.0f;
    return diffuse + glossy > 0.0f ? diffuse / (diffuse + glossy) : 1.0f;
}

// The density (per unit solid angle, over the whole sphere) with which sampleBrdf() generates wi.
// n: unit normal on the side of wo; wo, wi: unit, pointing away from the surface.
inline float brdfPdf(const Material& m, glm::vec3 n, glm::vec3 wo, glm::vec3 wi) {
    const float pDiffuse = diffuseLobeProbability(m);
    float pdf = 0.0f;
    if (pDiffuse > 0.0f) pdf += pDiffuse * std::max(glm::dot(n, wi), 0.0f) * std::numbers::inv_pi_v<float>;
    if (pDiffuse < 1.0f) {
        const glm::vec3 mirror = glm::reflect(-wo, n);
        pdf += (1.0f - pDiffuse) * powerCosinePdf(m.phongExponent(), glm::dot(mirror, wi));
    }
    return pdf;
}

struct BrdfSample {
    glm::vec3 wi{0.0f};      // unit, away from the surface
    glm::vec3 weight{0.0f};  // f(wi, wo) * cos(theta_i) / pdf; zero when the sample is below the surface
    float pdf = 0.0f;
    bool valid() const { return pdf > 0.0f && weight != glm::vec3(0.0f); }
};

// Samples wi for the BRDF at a surface with unit normal n (on the side of wo) from three uniform numbers:
// uLobe picks the lobe, (u1, u2) the direction. The Phong lobe can reach below the surface: such samples come
// back with zero weight, which keeps the estimator unbiased (the lobe's mass there has zero integrand).
inline BrdfSample sampleBrdf(const Material& m, glm::vec3 n, glm::vec3 wo, float uLobe, float u1, float u2) {
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

}  // namespace deltagi
