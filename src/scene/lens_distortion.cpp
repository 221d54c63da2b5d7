// Lens distortion models (include/deltagi/scene.h, LensDistortion): OpenCV's Brown-Conrady model and its
// equidistant fisheye model, forward and inverted by Newton's method.
#include <cmath>

#include "deltagi/scene.h"

namespace deltagi {

namespace {

// Newton's iterations for undistort(): enough for the radial polynomials of real lenses to converge to float
// precision from the distorted point as the first guess.
constexpr int kNewtonIterations = 20;

}  // namespace

glm::vec2 LensDistortion::distort(glm::vec2 u) const {
    switch (model) {
        case Model::None:
            return u;
        case Model::OpenCV: {
            const float r2 = glm::dot(u, u);
            const float radial = 1.0f + r2 * (k1 + r2 * (k2 + r2 * k3));
            return {u.x * radial + 2.0f * p1 * u.x * u.y + p2 * (r2 + 2.0f * u.x * u.x),
                    u.y * radial + p1 * (r2 + 2.0f * u.y * u.y) + 2.0f * p2 * u.x * u.y};
        }
        case Model::Fisheye: {
            const float r = glm::length(u);
            if (!(r > 0.0f)) return u;
            const float theta = std::atan(r), t2 = theta * theta;
            const float thetaD = theta * (1.0f + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))));
            return u * (thetaD / r);
        }
    }
    return u;
}

glm::vec2 LensDistortion::undistort(glm::vec2 d) const {
    if (model == Model::None) return d;
    // Newton's method on distort(u) = d, with a numerical Jacobian (the models are smooth near the image).
    glm::vec2 u = d;
    for (int i = 0; i < kNewtonIterations; ++i) {
        const glm::vec2 f = distort(u) - d;
        if (std::abs(f.x) < 1e-7f && std::abs(f.y) < 1e-7f) break;
        const float h = 1e-4f * std::max(1.0f, glm::length(u));
        const glm::vec2 dx = (distort(u + glm::vec2(h, 0.0f)) - distort(u - glm::vec2(h, 0.0f))) / (2.0f * h);
        const glm::vec2 dy = (distort(u + glm::vec2(0.0f, h)) - distort(u - glm::vec2(0.0f, h))) / (2.0f * h);
        const float det = dx.x * dy.y - dy.x * dx.y;
        if (!(std::abs(det) > 1e-12f)) break;
        u -= glm::vec2(dy.y * f.x - dy.x * f.y, -dx.y * f.x + dx.x * f.y) / det;
        if (!std::isfinite(u.x) || !std::isfinite(u.y)) return d;
    }
    return u;
}

}  // namespace deltagi
