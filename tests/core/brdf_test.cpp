// The glossy lobe averaged over a sphere light's disk (phongLobeOverLight) against the average taken by
// brute force over directions spread uniformly over the disk, as the path tracer's light samples spread.
#include "core/brdf.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "core/brdf_sampling.h"

namespace deltagi {
namespace {

TEST(Brdf, TheLobeOverALightsDiskIsTheLobeOfTheWidenedExponent) {
    Material m;
    m.albedo = glm::vec3(0.0f);
    m.specular = glm::vec3(1.0f);
    m.roughness = 0.15f;  // exponent 87, the glossy example's ball
    const glm::vec3 n(0, 0, 1);
    const glm::vec3 wo = glm::normalize(glm::vec3(0.3f, 0.0f, 1.0f));
    const glm::vec3 mirror = glm::reflect(-wo, n);
    // Up to the example lamp seen from the ball (0.15 rad), where the disk is as wide as the lobe (n R^2 =
    // 2); a light far wider than the lobe makes a flat-topped highlight that the Gaussian does not follow.
    for (const float lightAngle : {0.05f, 0.1f, 0.15f}) {
        // The light centred at `offset` radians from the mirror direction.
        for (const float offset : {0.0f, 0.05f, 0.15f}) {
            const glm::mat3 toWorld = frameAround(mirror);
            const glm::vec3 centre = toWorld * glm::vec3(std::sin(offset), 0.0f, std::cos(offset));
            const glm::mat3 aroundCentre = frameAround(centre);
            double sum = 0.0;
            constexpr int kSide = 200;
            for (int i = 0; i < kSide; ++i)
                for (int j = 0; j < kSide; ++j) {
                    // Uniform over the cone of directions (the disk seen from afar).
                    const float u = (i + 0.5f) / kSide, v = (j + 0.5f) / kSide;
                    const float cosTheta = 1.0f - u * (1.0f - std::cos(lightAngle));
                    const float sinTheta = std::sqrt(1.0f - cosTheta * cosTheta);
                    const float phi = 2.0f * 3.14159265f * v;
                    const glm::vec3 wi = aroundCentre * glm::vec3(sinTheta * std::cos(phi),
                                                                  sinTheta * std::sin(phi), cosTheta);
                    sum += evalBrdf(m, n, wo, wi).x;
                }
            const float bruteForce = static_cast<float>(sum / (kSide * kSide));
            const float widened = evalBrdf(m, n, wo, centre, lightAngle).x;
            const float point = evalBrdf(m, n, wo, centre).x;
            SCOPED_TRACE(::testing::Message() << "light " << lightAngle << " rad, " << offset << " rad off");
            // Within 12 % of the peak, where the point light's lobe is 1.6 times too high at the centre.
            EXPECT_NEAR(widened, bruteForce, 0.12f * evalBrdf(m, n, wo, mirror, lightAngle).x);
            if (offset == 0.0f && lightAngle >= 0.15f) EXPECT_GT(point, 1.4f * bruteForce);
        }
    }
}

}  // namespace
}  // namespace deltagi

namespace deltagi {
namespace {

// The specular cone's weight (SurfaceMaterial::specularReflectance) is the Phong lobe's directional albedo:
// evalBrdf's glossy part times cos(theta_i), integrated over the hemisphere by a midpoint rule, for wide to
// narrow lobes and views from straight on to grazing. (A constant reflectance overstated a glossy ball's
// reflection of the room 1.28 times against the path tracer, which integrates this lobe.)
TEST(Brdf, ThePhongSpecularReflectanceIsTheLobesDirectionalAlbedo) {
    for (const float roughness : {0.9f, 0.6f, 0.4f, 0.15f}) {
        Material m;
        m.albedo = glm::vec3(0.0f);
        m.specular = glm::vec3(1.0f);
        m.roughness = roughness;
        const SurfaceMaterial s = constantSurfaceMaterial(m);
        const glm::vec3 n(0, 0, 1);
        for (const float mu : {1.0f, 0.7f, 0.4f, 0.15f, 0.05f}) {
            const glm::vec3 wo(std::sqrt(1.0f - mu * mu), 0.0f, mu);
            constexpr int kTheta = 400, kPhi = 800;
            double integral = 0.0;
            for (int i = 0; i < kTheta; ++i) {
                const double theta = (i + 0.5) * 0.5 * std::numbers::pi / kTheta;
                for (int j = 0; j < kPhi; ++j) {
                    const double phi = (j + 0.5) * 2.0 * std::numbers::pi / kPhi;
                    const glm::vec3 wi(static_cast<float>(std::sin(theta) * std::cos(phi)),
                                       static_cast<float>(std::sin(theta) * std::sin(phi)),
                                       static_cast<float>(std::cos(theta)));
                    integral += evalBrdf(s, n, wo, wi).x * std::cos(theta) * std::sin(theta);
                }
            }
            integral *= (0.5 * std::numbers::pi / kTheta) * (2.0 * std::numbers::pi / kPhi);
            EXPECT_NEAR(s.specularReflectance(mu).x, integral, 0.04)
                << "roughness " << roughness << ", n.v " << mu;
        }
    }
}

}  // namespace
}  // namespace deltagi
