#include "core/environment.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/parallel.h"

namespace deltagi {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr float kPiF = std::numbers::pi_v<float>;
// Converted maps are at least this many rows high, and at most this many (a 8192 x 4096 map).
constexpr int kMinConvertedHeight = 8;
constexpr int kMaxConvertedHeight = 4096;

// The fish-eye camera's frame in the environment frame: columns are its right, up and backward (+z of an
// OpenGL camera) axes. It looks along +y with the image's top towards -z, so its right is +y x -z = -x.
const glm::mat3 kEnvironmentFromFisheye(glm::vec3(-1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(0, -1, 0));

int convertedHeight(double pixelsPerRadian) {
    return std::clamp(static_cast<int>(std::lround(kPi * pixelsPerRadian)), kMinConvertedHeight,
                      kMaxConvertedHeight);
}

// Each converted pixel averages a k x k grid of lookups over its area, so that a small bright sun keeps its
// energy (one lookup per pixel would catch it or miss it).
constexpr int kConversionSubsamples = 3;
constexpr float kConversionStep = 1.0f / kConversionSubsamples;

int fisheyeHeight(const FisheyeProjection& p) {
    const float halfFov = 0.5f * glm::radians(p.fovDeg);
    const double perRadian = p.model == FisheyeProjection::Model::Equidistant
                                 ? p.radius / halfFov
                                 : p.radius / (2.0 * std::sin(0.5 * halfFov));
    return convertedHeight(perRadian);
}

}  // namespace

template <typename PixelOf>
EquirectConversion EquirectConversion::make(int sourceWidth, int sourceHeight, int height,
                                            PixelOf&& pixelOf) {
    EquirectConversion c;
    c.sourceWidth_ = sourceWidth;
    c.sourceHeight_ = sourceHeight;
    c.height_ = height;
    constexpr int kPerPixel = kConversionSubsamples * kConversionSubsamples;
    const int width = 2 * height;
    c.lookups_.resize(static_cast<size_t>(width) * height * kPerPixel);
    const float w = static_cast<float>(width), h = static_cast<float>(height);
    parallelFor(0, height, 4, [&](int64_t row) {
        Lookup* out = &c.lookups_[static_cast<size_t>(row) * width * kPerPixel];
        for (int col = 0; col < width; ++col)
            for (int j = 0; j < kConversionSubsamples; ++j)
                for (int i = 0; i < kConversionSubsamples; ++i) {
                    const glm::vec3 d = equirectDirection(
                        (static_cast<float>(col) + (static_cast<float>(i) + 0.5f) * kConversionStep) / w,
                        (static_cast<float>(row) + (static_cast<float>(j) + 0.5f) * kConversionStep) / h);
                    Lookup& lookup = *out++;
                    lookup = {kUnseen, 0, 0.0f, 0.0f};
                    // Bilinear in the camera pixel convention (pixel (i, j) centred at i + 0.5).
                    if (const std::optional<glm::vec2> pixel = pixelOf(d)) {
                        const float x = pixel->x - 0.5f, y = pixel->y - 0.5f;
                        lookup.x0 = static_cast<int>(std::floor(x));
                        lookup.y0 = static_cast<int>(std::floor(y));
                        lookup.fx = x - static_cast<float>(lookup.x0);
                        lookup.fy = y - static_cast<float>(lookup.y0);
                    }
                }
    });
    return c;
}

EquirectConversion EquirectConversion::fromFisheye(int sourceWidth, int sourceHeight,
                                                   const FisheyeProjection& p, int height) {
    return make(sourceWidth, sourceHeight, height > 0 ? height : fisheyeHeight(p),
                [&](glm::vec3 d) { return fisheyePixel(d, p); });
}

EquirectConversion EquirectConversion::fromMirrorBall(int sourceWidth, int sourceHeight,
                                                      const MirrorBallProjection& p, int height) {
    // At the ball's centre the reflected direction turns twice as fast as the normal: radius / 2 per radian.
    return make(sourceWidth, sourceHeight, height > 0 ? height : convertedHeight(0.5 * p.radius),
                [&](glm::vec3 d) { return mirrorBallPixel(d, p); });
}

Image EquirectConversion::apply(const Image& source) const {
    if (source.width() != sourceWidth_ || source.height() != sourceHeight_)
        throw std::invalid_argument("EquirectConversion::apply: an image of another size");
    constexpr int kPerPixel = kConversionSubsamples * kConversionSubsamples;
    Image out(2 * height_, height_, 3);
    auto at = [&](int i, int j) {
        return source.rgb(std::clamp(i, 0, sourceWidth_ - 1), std::clamp(j, 0, sourceHeight_ - 1));
    };
    parallelFor(0, height_, 4, [&](int64_t row) {
        const Lookup* lookup = &lookups_[static_cast<size_t>(row) * out.width() * kPerPixel];
        for (int col = 0; col < out.width(); ++col) {
            glm::vec3 sum(0.0f);
            for (int k = 0; k < kPerPixel; ++k, ++lookup) {
                if (lookup->x0 == kUnseen) continue;
                const auto [x0, y0, fx, fy] = *lookup;
                sum += glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), fx),
                                glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx), fy);
            }
            out.setRgb(col, static_cast<int>(row), sum * (kConversionStep * kConversionStep));
        }
    });
    return out;
}

glm::vec3 equirectDirection(float u, float v) {
    const float phi = 2.0f * kPiF * (u - 0.5f), theta = kPiF * (0.5f - v);
    return {std::sin(phi) * std::cos(theta), std::sin(theta), -std::cos(phi) * std::cos(theta)};
}

glm::vec2 equirectUv(glm::vec3 d) {
    const float horizontal = std::sqrt(d.x * d.x + d.z * d.z);
    const float theta = std::atan2(d.y, horizontal), phi = std::atan2(d.x, -d.z);
    float u = phi / (2.0f * kPiF) + 0.5f;
    if (u >= 1.0f) u -= 1.0f;
    return {std::max(u, 0.0f), std::clamp(0.5f - theta / kPiF, 0.0f, 1.0f)};
}

double equirectRowElevation(int row, int height) {
    return kPi * (0.5 - static_cast<double>(row) / height);
}

double equirectPixelSolidAngle(int row, int width, int height) {
    const double band =
        std::sin(equirectRowElevation(row, height)) - std::sin(equirectRowElevation(row + 1, height));
    return 2.0 * kPi * band / width;
}

glm::dvec3 integrateSphere(const Image& equirect) {
    glm::dvec3 sum(0.0);
    for (int y = 0; y < equirect.height(); ++y) {
        glm::dvec3 row(0.0);
        for (int x = 0; x < equirect.width(); ++x) row += glm::dvec3(equirect.rgb(x, y));
        sum += row * equirectPixelSolidAngle(y, equirect.width(), equirect.height());
    }
    return sum;
}

glm::vec3 sampleEquirect(const Image& map, glm::vec2 uv) {
    const int w = map.width(), h = map.height();
    const float x = uv.x * static_cast<float>(w) - 0.5f, y = uv.y * static_cast<float>(h) - 0.5f;
    const float xf = std::floor(x), yf = std::floor(y);
    const float fx = x - xf, fy = y - yf;
    const int x0 = ((static_cast<int>(xf) % w) + w) % w, x1 = (x0 + 1) % w;
    const int y0 = std::clamp(static_cast<int>(yf), 0, h - 1),
              y1 = std::clamp(static_cast<int>(yf) + 1, 0, h - 1);
    return glm::mix(glm::mix(map.rgb(x0, y0), map.rgb(x1, y0), fx),
                    glm::mix(map.rgb(x0, y1), map.rgb(x1, y1), fx), fy);
}

std::optional<glm::vec2> fisheyePixel(glm::vec3 direction, const FisheyeProjection& p) {
    const glm::vec3 c = glm::transpose(kEnvironmentFromFisheye) * glm::normalize(direction);
    const float theta = std::acos(std::clamp(-c.z, -1.0f, 1.0f));  // from the optical axis (-z)
    const float halfFov = 0.5f * glm::radians(p.fovDeg);
    if (theta > halfFov) return std::nullopt;
    const float r = p.model == FisheyeProjection::Model::Equidistant
                        ? p.radius * theta / halfFov
                        : p.radius * std::sin(0.5f * theta) / std::sin(0.5f * halfFov);
    const float lateral = std::sqrt(c.x * c.x + c.y * c.y);
    if (lateral < 1e-9f) return p.center;
    return p.center + r * glm::vec2(c.x, -c.y) / lateral;  // image +y is down
}

std::optional<glm::vec2> mirrorBallPixel(glm::vec3 direction, const MirrorBallProjection& p) {
    // The ball's normal halves the angle between the reflected direction and the way back to the camera (+z).
    const glm::vec3 halfway = glm::normalize(direction) + glm::vec3(0, 0, 1);
    const float length = glm::length(halfway);
    if (length < 1e-6f) return std::nullopt;  // straight behind the ball: the rim, in no one place
    const glm::vec3 n = halfway / length;
    return p.center + p.radius * glm::vec2(n.x, -n.y);
}

Image equirectFromFisheye(const Image& fisheye, const FisheyeProjection& p, int height) {
    return EquirectConversion::fromFisheye(fisheye.width(), fisheye.height(), p, height).apply(fisheye);
}

Image equirectFromMirrorBall(const Image& ball, const MirrorBallProjection& p, int height) {
    return EquirectConversion::fromMirrorBall(ball.width(), ball.height(), p, height).apply(ball);
}

size_t sanitizeRadiance(Image& image) {
    size_t bad = 0;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x) {
            bool repaired = false;
            for (int c = 0; c < image.channels(); ++c) {
                float& v = image.at(x, y, c);
                if (!(v >= 0.0f) || !std::isfinite(v)) {
                    v = 0.0f;
                    repaired = true;
                }
            }
            bad += repaired ? 1 : 0;
        }
    return bad;
}

glm::vec3 environmentRadiance(const Environment& environment, glm::vec3 direction) {
    return sampleEquirect(environment.radiance, equirectUv(environment.environmentFromWorld() * direction));
}

}  // namespace deltagi
