// Synthetic camera frames of AprilTag markers for the registration tests: markers printed on white paper
// lying in a grey room, seen by a camera as a sensor would record them (each pixel the mean of 4 x 4 rays
// through its area, through the lens distortion; Gaussian noise; 8-bit sRGB), and decoded back to linear
// RGB as readImage() does.
#pragma once

#include <cmath>
#include <span>

#include <glm/gtc/matrix_transform.hpp>

#include "core/rng.h"
#include "deltagi/image.h"
#include "deltagi/scene.h"
#include "deltagi/transforms.h"
#include "io/image_encode.h"
#include "live/marker_registration.h"

namespace deltagi::test {

inline constexpr float kPaperWhite = 0.8f, kInkBlack = 0.03f, kRoomGrey = 0.18f;

// A marker lying on the floor (y up): printed face up, its top towards -z, its centre at `centre`.
inline Marker floorMarker(int id, float size, glm::vec3 centre, float turnDeg = 0.0f) {
    Marker m;
    m.id = id;
    m.size = size;
    m.worldFromMarker = glm::translate(glm::mat4(1.0f), centre) *
                        glm::rotate(glm::mat4(1.0f), glm::radians(turnDeg), glm::vec3(0, 1, 0)) *
                        glm::rotate(glm::mat4(1.0f), glm::radians(-90.0f), glm::vec3(1, 0, 0));
    return m;
}

// The linear radiance a ray from `origin` along `dir` sees.
inline float markerSceneRadiance(std::span<const Marker> markers, std::span<const std::vector<bool>> cells,
                                 glm::vec3 origin, glm::vec3 dir) {
    float nearest = INFINITY, value = kRoomGrey;
    for (size_t m = 0; m < markers.size(); ++m) {
        const glm::mat4 markerFromWorld = glm::inverse(markers[m].worldFromMarker);
        const glm::vec3 o(markerFromWorld * glm::vec4(origin, 1.0f));
        const glm::vec3 d(markerFromWorld * glm::vec4(dir, 0.0f));
        if (!(std::abs(d.z) > 1e-9f)) continue;
        const float t = -o.z / d.z;
        if (!(t > 0.0f) || t >= nearest) continue;
        const glm::vec3 p = o + t * d;
        const float cell = markers[m].size / 8.0f;
        const float paperHalf = 6.0f * cell;  // the tag's 10 cells and one more cell of white paper around
        if (std::abs(p.x) > paperHalf || std::abs(p.y) > paperHalf) continue;
        nearest = t;
        const int column = static_cast<int>(std::floor(p.x / cell + 5.0f));
        const int row = static_cast<int>(std::floor(5.0f - p.y / cell));
        const bool inTag = column >= 0 && column < kMarkerCells && row >= 0 && row < kMarkerCells;
        value = inTag && cells[m][static_cast<size_t>(row) * kMarkerCells + column] ? kInkBlack : kPaperWhite;
    }
    return value;
}

// One frame from `camera` (its pose, intrinsics and distortion); `noise`: the sensor noise's standard
// deviation in 8-bit levels; `seed` makes each frame's noise its own.
inline Image renderMarkerFrame(const Camera& camera, std::span<const Marker> markers, float noise = 1.5f,
                               uint64_t seed = 0) {
    std::vector<std::vector<bool>> cells;
    for (const Marker& m : markers) cells.push_back(markerCells(m.id));
    Image image(camera.width, camera.height, 3);
    const glm::vec3 origin = camera.position();
    const std::array<float, 256>& linear = srgb8ToLinearValues();
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            float sum = 0.0f;
            for (int s = 0; s < 16; ++s) {
                const float px = static_cast<float>(x) + (static_cast<float>(s % 4) + 0.5f) / 4.0f;
                const float py = static_cast<float>(y) + (static_cast<float>(s / 4) + 0.5f) / 4.0f;
                sum +=
                    markerSceneRadiance(markers, cells, origin, glm::normalize(camera.rayDirection(px, py)));
            }
            Rng rng(static_cast<uint64_t>(y) * camera.width + x, seed, 77);
            // Box-Muller from two uniforms.
            const float u1 = std::max(rng.uniform(), 1e-7f), u2 = rng.uniform();
            const float gaussian = std::sqrt(-2.0f * std::log(u1)) * std::cos(6.2831853f * u2);
            const float level = 255.0f * linearToSrgbValue(sum / 16.0f) + noise * gaussian;
            const float value = linear[static_cast<size_t>(std::clamp(std::lround(level), 0l, 255l))];
            image.setRgb(x, y, glm::vec3(value));
        }
    return image;
}

// A camera of `width` x `height` with a vertical field of view of `fovDeg`, at `position` looking at
// `target`.
inline Camera markerCamera(int width, int height, float fovDeg, glm::vec3 position, glm::vec3 target) {
    Camera camera;
    camera.width = width;
    camera.height = height;
    camera.setFieldOfView(fovDeg);
    camera.worldFromCamera = lookAtPose(position, target);
    return camera;
}

// Where a camera's pose differs from the truth: position (world units) and rotation (degrees).
struct PoseError {
    float position = 0.0f, rotationDeg = 0.0f;
};
inline PoseError poseError(const glm::mat4& estimated, const glm::mat4& truth) {
    PoseError e;
    e.position = glm::length(glm::vec3(estimated[3]) - glm::vec3(truth[3]));
    const glm::mat3 r = glm::transpose(glm::mat3(truth)) * glm::mat3(estimated);
    const float cosine = std::clamp(0.5f * (r[0][0] + r[1][1] + r[2][2] - 1.0f), -1.0f, 1.0f);
    e.rotationDeg = glm::degrees(std::acos(cosine));
    return e;
}

}  // namespace deltagi::test
