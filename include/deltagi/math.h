// Small geometric types shared by the public API. Vectors and matrices are GLM's.
#pragma once

#include <algorithm>
#include <limits>

#include <glm/glm.hpp>

#include "deltagi/export.h"

DELTAGI_API_BEGIN
namespace deltagi {

// Axis-aligned bounding box in world space. Empty when min > max.
struct Bounds3f {
    glm::vec3 min{std::numeric_limits<float>::infinity()};
    glm::vec3 max{-std::numeric_limits<float>::infinity()};

    bool empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    void extend(glm::vec3 p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    void extend(const Bounds3f& b) {
        min = glm::min(min, b.min);
        max = glm::max(max, b.max);
    }
    bool contains(glm::vec3 p) const {
        return p.x >= min.x && p.y >= min.y && p.z >= min.z && p.x <= max.x && p.y <= max.y && p.z <= max.z;
    }
    glm::vec3 center() const { return 0.5f * (min + max); }
    glm::vec3 diagonal() const { return max - min; }
    float maxExtent() const {
        glm::vec3 d = diagonal();
        return std::max(d.x, std::max(d.y, d.z));
    }
};

}  // namespace deltagi
DELTAGI_API_END
