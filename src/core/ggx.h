// The glTF 2.0 metallic-roughness BRDF (MaterialModel::MetallicRoughness; glTF 2.0 specification, appendix
// B): a Lambertian diffuse lobe under a GGX (Trowbridge-Reitz) specular lobe with height-correlated Smith
// visibility and Schlick's Fresnel,
//   f(wi, wo) = (1 - F(v.h)) * diffuseColor / pi + F(v.h) * D(n.h) * V(n.l, n.v),
// with diffuseColor = base * (1 - metallic), F0 = mix(0.04, base, metallic), alpha = roughness^2.
// Single scattering only: the lobe loses energy at high roughness (a white metal reflects 0.877 of the light
// at alpha 0.3 and 0.307 at alpha 1, seen from above; tests/core/ggx_test.cpp has the figures). The path
// tracer and the cone tracer are both to use it as it is, with no multiple-scattering compensation, so that
// they stay comparable. glTF's mix, (1 - F(v.h)) under the diffuse, reflects more than 1 from a white
// dielectric at grazing angles (1.39 at n.v = 0.1 and alpha 0.05): that is the specification's formula, kept.
//
// Also here: sampling of the visible normals (Heitz 2018) and a diffuse + specular mixture for the path
// tracer, in the shape of brdf_sampling.h; and the specular cone's aperture for the cone tracer.
// All directions are unit vectors pointing away from the surface; n is the unit normal on the side of wo.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "core/sampling.h"

namespace deltagi {

// The smallest GGX alpha used: below it D's peak 1 / (pi alpha^2) and its float arithmetic stop being
// meaningful (at 1e-3 the peak is 3e5 per steradian, a lobe 1.3 milliradians wide: a mirror, for any image).
inline constexpr float kMinGgxAlpha = 1e-3f;
inline float clampGgxAlpha(float alpha) {
    return std::clamp(alpha, kMinGgxAlpha, 1.0f);
}

// glTF's dielectric reflectance at normal incidence (an index of refraction of 1.5).
inline constexpr float kGltfDielectricF0 = 0.04f;

// The two lobes of a glTF material from its base colour, metallic and perceptual roughness (each in [0, 1]).
struct GltfLobes {
    glm::vec3 diffuseColor{0.0f};     // Lambertian reflectance: base * (1 - metallic)
    glm::vec3 f0{kGltfDielectricF0};  // Fresnel reflectance at normal incidence: mix(0.04, base, metallic)
    float alpha = 1.0f;               // GGX alpha: roughness^2, clamped to [kMinGgxAlpha, 1]
};
inline GltfLobes gltfLobes(glm::vec3 baseColor, float metallic, float perceptualRoughness) {
    const float m = std::clamp(metallic, 0.0f, 1.0f);
    const float r = std::clamp(perceptualRoughness, 0.0f, 1.0f);
    return {baseColor * (1.0f - m), glm::mix(glm::vec3(kGltfDielectricF0), baseColor, m),
            clampGgxAlpha(r * r)};
}

// The GGX normal distribution D(h) = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2); zero below the surface.
// Normalized so that the projected area integrates to one: the integral of D(h) (n.h) over h is 1.
inline float ggxD(float nDotH, float alpha) {
    if (nDotH <= 0.0f) return 0.0f;
    const float a2 = alpha * alpha;
    const float c2 = nDotH * nDotH;
    const float d = c2 * a2 + (1.0f - c2);  // = c2 (alpha^2 + tan^2 theta_h)
    return a2 / (std::numbers::pi_v<float> * d * d);
}

// sqrt(alpha^2 + (1 - alpha^2) cos^2): the term of Smith's Lambda for GGX that both G1 and V share.
inline float ggxSmithRoot(float cosTheta, float alpha) {
    const float a2 = alpha * alpha;
    return std::sqrt(a2 + (1.0f - a2) * cosTheta * cosTheta);
}

// Smith's masking G1 = 1 / (1 + Lambda) for a direction at cosTheta > 0 to the normal.
inline float ggxG1(float cosTheta, float alpha) {
    return 2.0f * cosTheta / (cosTheta + ggxSmithRoot(cosTheta, alpha));
}

// The height-correlated Smith visibility V = G2 / (4 |n.l| |n.v|) (glTF 2.0 appendix B, "Specular BRDF"),
// G2 = 1 / (1 + Lambda(l) + Lambda(v)). Symmetric in l and v.
inline float ggxVisibility(float nDotL, float nDotV, float alpha) {
    const float denominator = nDotL * ggxSmithRoot(nDotV, alpha) + nDotV * ggxSmithRoot(nDotL, alpha);
    return denominator > 0.0f ? 0.5f / denominator : 0.0f;
}

// Schlick's Fresnel with f90 = 1: F0 + (1 - F0) (1 - cos)^5.
inline glm::vec3 schlickFresnel(float cosTheta, glm::vec3 f0) {
    const float m = std::clamp(1.0f - cosTheta, 0.0f, 1.0f);
    const float m2 = m * m;
    return f0 + (1.0f - f0) * (m2 * m2 * m);
}

// f(wi, wo) of the glTF BRDF; zero when wi or wo is below the surface. alpha is clamped to [kMinGgxAlpha, 1].
inline glm::vec3 evalGltfBrdf(glm::vec3 diffuseColor, glm::vec3 f0, float alpha, glm::vec3 n, glm::vec3 wo,
                              glm::vec3 wi) {
    const float nDotV = glm::dot(n, wo);
    const float nDotL = glm::dot(n, wi);
    if (nDotV <= 0.0f || nDotL <= 0.0f) return glm::vec3(0.0f);
    const glm::vec3 sum = wo + wi;
    const float length = glm::length(sum);
    if (!(length > 0.0f)) return glm::vec3(0.0f);
    const glm::vec3 h = sum / length;
    const float a = clampGgxAlpha(alpha);
    const glm::vec3 fresnel = schlickFresnel(glm::dot(wo, h), f0);
    const float specular = ggxD(glm::dot(n, h), a) * ggxVisibility(nDotL, nDotV, a);
    return (1.0f - fresnel) * diffuseColor * std::numbers::inv_pi_v<float> + fresnel * specular;
}

// The GGX alpha that shades a light of angular radius `lightAngle` (radians, the half-angle it subtends)
// when the BRDF is evaluated at the light's centre, like phongLobeOverLight for the Phong lobe:
//   alpha' = sqrt(alpha^2 + rho^2 / v.h),  rho = lightAngle / 2.
// The half vector h = (wi + wo) / |wi + wo| turns half as far as wi across the plane of incidence and
// 1 / (2 v.h) as far out of it (|wi + wo| = 2 v.h), so the light's disk is an ellipse of semi-axes rho and
// rho / v.h in the space of microfacet slopes, where D is 1 / (pi alpha^2 (1 + s^2 / alpha^2)^2). D averaged
// over a disk of radius rho around its peak is exactly 1 / (pi (alpha^2 + rho^2)), the peak of D with
// alpha'; the ellipse is taken as the disk of its area. So the widened lobe has the convolution's peak and,
// being a normalized D, its energy. Seen at grazing angles (a rim lit from above) the ellipse is twice as
// wide or more: without 1 / v.h those highlights were half as wide as the path tracer's.
// Not Karis 2013's "roughness widening" alpha + radius / (2 distance) with its energy factor
// (alpha / alpha')^2: that is for his representative point, where the unwidened D is read at its peak; at
// the light's centre, adding widths linearly dims a highlight 20 % where the disk barely changes it
// (alpha 0.2, lightAngle 0.05), and the quadrature stays within 12 % of the peak
// (tests/core/ggx_test.cpp).
inline float ggxAlphaOverLight(float alpha, float lightAngle, float vDotH = 1.0f) {
    const float a = clampGgxAlpha(alpha);
    const float rho = 0.5f * std::max(lightAngle, 0.0f);
    return clampGgxAlpha(std::sqrt(a * a + rho * rho / std::clamp(vDotH, 0.05f, 1.0f)));
}

// f(wi, wo) for wi pointing at the centre of a light of angular radius `lightAngle` (0: a point light): the
// BRDF averaged over the light's disk, approximately (ggxAlphaOverLight).
inline glm::vec3 evalGltfBrdf(glm::vec3 diffuseColor, glm::vec3 f0, float alpha, glm::vec3 n, glm::vec3 wo,
                              glm::vec3 wi, float lightAngle) {
    if (!(lightAngle > 0.0f)) return evalGltfBrdf(diffuseColor, f0, alpha, n, wo, wi);
    const glm::vec3 sum = wi + wo;
    const float length = glm::length(sum);
    const float vDotH = length > 1e-6f ? glm::dot(wo, sum) / length : 1.0f;
    return evalGltfBrdf(diffuseColor, f0, ggxAlphaOverLight(alpha, lightAngle, vDotH), n, wo, wi);
}

inline glm::vec3 evalGltfBrdf(const GltfLobes& lobes, glm::vec3 n, glm::vec3 wo, glm::vec3 wi,
                              float lightAngle = 0.0f) {
    return evalGltfBrdf(lobes.diffuseColor, lobes.f0, lobes.alpha, n, wo, wi, lightAngle);
}

// Samples wi by reflecting wo about a normal drawn from the distribution of the normals visible from wo
// (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", listing 1): stretch wo to the
// configuration of alpha = 1, sample the projected hemisphere there (a disk, of which the half hidden behind
// the hemisphere's edge is folded onto the visible half), and unstretch the normal. The reflected direction
// can be below the surface (then f is zero there); u1, u2 uniform in [0, 1).
inline glm::vec3 sampleGgxReflection(glm::vec3 n, glm::vec3 wo, float alpha, float u1, float u2) {
    const float a = clampGgxAlpha(alpha);
    const glm::mat3 frame = frameAround(n);
    const glm::vec3 woLocal(glm::dot(frame[0], wo), glm::dot(frame[1], wo), glm::dot(n, wo));
    const glm::vec3 woStretched = glm::normalize(glm::vec3(a * woLocal.x, a * woLocal.y, woLocal.z));
    // An orthonormal basis (t1, t2, woStretched); t1 is horizontal.
    const float horizontal2 = woStretched.x * woStretched.x + woStretched.y * woStretched.y;
    const glm::vec3 t1 = horizontal2 > 0.0f
                             ? glm::vec3(-woStretched.y, woStretched.x, 0.0f) / std::sqrt(horizontal2)
                             : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 t2 = glm::cross(woStretched, t1);
    // A uniform point of the unit disk, its lower half squeezed into the part of the disk in view.
    const float r = std::sqrt(u1);
    const float phi = 2.0f * std::numbers::pi_v<float> * u2;
    const float p1 = r * std::cos(phi);
    const float s = 0.5f * (1.0f + woStretched.z);
    const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * r * std::sin(phi);
    const glm::vec3 hStretched =
        p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * woStretched;
    const glm::vec3 hLocal =
        glm::normalize(glm::vec3(a * hStretched.x, a * hStretched.y, std::max(hStretched.z, 0.0f)));
    const glm::vec3 h = frame * hLocal;
    return glm::normalize(2.0f * glm::dot(wo, h) * h - wo);
}

// The density (per unit solid angle, over the whole sphere) with which sampleGgxReflection() generates wi:
// D_wo(h) / (4 |wo.h|), D_wo(h) = G1(wo) max(0, wo.h) D(h) / (n.wo) the visible normals' density, so
//   pdf = G1(wo) D(h) / (4 n.wo) = D(h) / (2 (n.wo + sqrt(alpha^2 + (1 - alpha^2) (n.wo)^2))).
// It integrates to 1 over the sphere; over the upper hemisphere to less, the more so at grazing angles.
inline float ggxReflectionPdf(glm::vec3 n, glm::vec3 wo, glm::vec3 wi, float alpha) {
    const float nDotV = glm::dot(n, wo);
    if (nDotV <= 0.0f) return 0.0f;
    const glm::vec3 sum = wo + wi;
    const float length = glm::length(sum);
    if (!(length > 0.0f)) return 0.0f;
    const glm::vec3 h = sum / length;
    if (glm::dot(wo, h) <= 0.0f) return 0.0f;
    const float a = clampGgxAlpha(alpha);
    return ggxD(glm::dot(n, h), a) / (2.0f * (nDotV + ggxSmithRoot(nDotV, a)));
}

// The probability of sampling the diffuse lobe: its share of an estimate of the reflectance, the diffuse
// colour times 1 - F and the specular F, with F taken at the angle of view (the average of v.h over the
// lobe is near n.v for the narrow lobes where the choice matters). 1 for a black material.
inline float gltfDiffuseLobeProbability(glm::vec3 diffuseColor, glm::vec3 f0, float nDotV) {
    const glm::vec3 fresnel = schlickFresnel(nDotV, f0);
    const glm::vec3 diffuseWeight = diffuseColor * (1.0f - fresnel);
    const float diffuse = (diffuseWeight.x + diffuseWeight.y + diffuseWeight.z) / 3.0f;
    const float specular = (fresnel.x + fresnel.y + fresnel.z) / 3.0f;
    return diffuse + specular > 0.0f ? diffuse / (diffuse + specular) : 1.0f;
}

// The density (per unit solid angle, over the whole sphere) with which sampleGltfBrdf() generates wi.
inline float gltfBrdfPdf(glm::vec3 diffuseColor, glm::vec3 f0, float alpha, glm::vec3 n, glm::vec3 wo,
                         glm::vec3 wi) {
    const float nDotV = glm::dot(n, wo);
    if (nDotV <= 0.0f) return 0.0f;
    const float pDiffuse = gltfDiffuseLobeProbability(diffuseColor, f0, nDotV);
    float pdf = 0.0f;
    if (pDiffuse > 0.0f) pdf += pDiffuse * std::max(glm::dot(n, wi), 0.0f) * std::numbers::inv_pi_v<float>;
    if (pDiffuse < 1.0f) pdf += (1.0f - pDiffuse) * ggxReflectionPdf(n, wo, wi, alpha);
    return pdf;
}

// Samples wi for the glTF BRDF from three uniform numbers in [0, 1): uLobe picks the lobe (cosine-weighted
// hemisphere for the diffuse, visible normals for the specular), (u1, u2) the direction. Specular samples
// below the surface come back with zero weight (as in sampleBrdf). For a white metal the weight is
// F G2 / G1(wo) <= 1: the visible normals cancel all but the masking of wi.
inline BrdfSample sampleGltfBrdf(glm::vec3 diffuseColor, glm::vec3 f0, float alpha, glm::vec3 n, glm::vec3 wo,
                                 float uLobe, float u1, float u2) {
    BrdfSample s;
    const float nDotV = glm::dot(n, wo);
    if (nDotV <= 0.0f) return s;
    if (uLobe < gltfDiffuseLobeProbability(diffuseColor, f0, nDotV)) {
        s.wi = glm::normalize(frameAround(n) * sampleCosineHemisphere(u1, u2));
    } else {
        s.wi = sampleGgxReflection(n, wo, alpha, u1, u2);
    }
    const float cosTheta = glm::dot(n, s.wi);
    s.pdf = gltfBrdfPdf(diffuseColor, f0, alpha, n, wo, s.wi);
    if (cosTheta <= 0.0f || !(s.pdf > 0.0f) || !std::isfinite(s.pdf)) return s;
    s.weight = evalGltfBrdf(diffuseColor, f0, alpha, n, wo, s.wi) * (cosTheta / s.pdf);
    return s;
}

inline BrdfSample sampleGltfBrdf(const GltfLobes& lobes, glm::vec3 n, glm::vec3 wo, float uLobe, float u1,
                                 float u2) {
    return sampleGltfBrdf(lobes.diffuseColor, lobes.f0, lobes.alpha, n, wo, uLobe, u1, u2);
}

inline float gltfBrdfPdf(const GltfLobes& lobes, glm::vec3 n, glm::vec3 wo, glm::vec3 wi) {
    return gltfBrdfPdf(lobes.diffuseColor, lobes.f0, lobes.alpha, n, wo, wi);
}

// The half-angle (radians, around the mirror direction) of the cone the specular lobe fills, for the cone
// tracer: where D falls to half its peak, seen at normal incidence. With D proportional to
// 1 / (cos^2 theta_h (alpha^2 - 1) + 1)^2, D(theta_h) = D(0) / 2 where
//   cos^2 theta_h (alpha^2 - 1) + 1 = sqrt(2) alpha^2,
//   cos^2 theta_h = (1 - sqrt(2) alpha^2) / (1 - alpha^2),
//   tan^2 theta_h = (sqrt(2) - 1) alpha^2 / (1 - sqrt(2) alpha^2),
// so theta_h ~ 0.644 alpha for a narrow lobe. The reflected direction turns twice as far as the half vector:
// the cone's half-angle is 2 theta_h (~1.29 alpha), capped at pi/2 (the hemisphere). For alpha^2 >=
// 1/sqrt(2) (alpha >= 0.841) D never falls to half on the hemisphere (at alpha = 1 it is uniform): pi/2.
inline float ggxConeHalfAngle(float alpha) {
    const float a = clampGgxAlpha(alpha);
    const float a2 = a * a;
    const float rest = 1.0f - std::numbers::sqrt2_v<float> * a2;
    if (rest <= 0.0f) return 0.5f * std::numbers::pi_v<float>;
    const float thetaH = std::atan(a * std::sqrt((std::numbers::sqrt2_v<float> - 1.0f) / rest));
    return std::min(2.0f * thetaH, 0.5f * std::numbers::pi_v<float>);
}

// The Phong exponent whose lobe cos^n has the same half-width as the GGX lobe of alpha:
// cos^n(ggxConeHalfAngle) = 1/2, so that code taking a Phong exponent (specularConeTanHalfAngle) opens the
// same cone. 0 (the hemisphere) where the cone is the hemisphere. ln cos x = ln(1 - sin^2 x) / 2 keeps narrow
// lobes exact.
inline float ggxPhongExponent(float alpha) {
    const float halfAngle = ggxConeHalfAngle(alpha);
    if (halfAngle >= 0.5f * std::numbers::pi_v<float>) return 0.0f;
    const float sine = std::sin(halfAngle);
    return -std::numbers::ln2_v<float> / (0.5f * std::log1p(-sine * sine));
}

}  // namespace deltagi
