// What the cone tracers of stage 6 share (cone_trace.cpp marches one cone at a time, cone_lanes.cpp eight in
// SIMD lanes): the part of a cone inside the volume, the fractional mip level of a step, the occlusion
// model's constants and a sample's opacity over a step. Internal to the pipeline.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

#include <glm/glm.hpp>

#include "pipeline/cone_trace.h"

namespace deltagi::cone_march {

// The part [tEnter, tExit] of a ray inside the volume [0, n]^3 (voxel units); empty when tEnter >= tExit.
inline std::pair<float, float> clipToVolume(glm::vec3 origin, glm::vec3 dir, float n) {
    float tEnter = 0.0f, tExit = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (std::abs(dir[a]) < 1e-12f) {
            if (origin[a] < 0.0f || origin[a] > n) return {1.0f, 0.0f};
            continue;
        }
        float inv = 1.0f / dir[a];
        float t0 = (0.0f - origin[a]) * inv, t1 = (n - origin[a]) * inv;
        if (t0 > t1) std::swap(t0, t1);
        tEnter = std::max(tEnter, t0);
        tExit = std::min(tExit, t1);
    }
    return {tEnter, tExit};
}

// A cone's march in level-0 voxel units: its origin, and the distances along it of its first sample and of
// its end. Empty (first >= end) when it misses the volume.
struct ConeSpan {
    glm::vec3 origin{0.0f};
    float first = 0.0f, end = 0.0f;
};
inline ConeSpan coneSpan(const Cone& cone, const VolumeRegion& region, const ConeTraceSettings& settings) {
    const float invVoxel = 1.0f / region.voxelSize();
    ConeSpan s;
    s.origin = (cone.origin - region.origin) * invVoxel;
    const auto [tEnter, tExit] =
        clipToVolume(s.origin, cone.direction, static_cast<float>(region.resolution));
    s.end = std::min(tExit, cone.maxDistance * invVoxel);
    // The first step is jittered: regular steps would alias into bands across neighbouring pixels.
    const float firstDiameter = std::max(1.0f, 2.0f * tEnter * cone.tanHalfAngle);
    s.first = tEnter + cone.jitter * settings.jitter * firstDiameter * settings.stepScale;
    return s;
}

// Occlusion of a visibility sample (adaptedOcclusion in cone_trace.cpp): voxelization records surfaces one
// voxel thick, so a coarse voxel's occupancy is scaled back by 2^level to the surface's coverage of its
// cross-section; incoherent normals cover kIsotropicCoverage of it, and a back face counts fully as one once
// cos(back) >= 1 / kBackfaceRamp.
constexpr float kIsotropicCoverage = 0.5f;
constexpr float kBackfaceRamp = 16.0f;
// Below these a voxel's occupancy (or a light voxel's weight) counts as empty, and normals as incoherent.
constexpr float kEmpty = 1e-6f;

// log2 of x >= 1 to within 3e-5 (the exponent, and a quintic in the mantissa m - 1, a least-squares fit over
// [1, 2] that is 0 at m = 1): std::log2 is a noticeable share of a cone step.
constexpr float kLog2Poly[5] = {0.04587075f, -0.19439043f, 0.41539777f, -0.70867494f, 1.44182512f};
inline float fastLog2(float x) {
    uint32_t bits;
    std::memcpy(&bits, &x, sizeof(bits));
    const float exponent = static_cast<float>(static_cast<int>(bits >> 23) - 127);
    bits = (bits & 0x007FFFFFu) | 0x3F800000u;
    float m;
    std::memcpy(&m, &bits, sizeof(m));
    const float u = m - 1.0f;
    const float p =
        ((((kLog2Poly[0] * u + kLog2Poly[1]) * u + kLog2Poly[2]) * u + kLog2Poly[3]) * u + kLog2Poly[4]) * u;
    return exponent + p;
}

// Opacity of a sample that covers a segment as long as the cone is wide, applied over a shorter step.
inline float stepOpacity(float alpha, float stepScale) {
    const float transmittance = std::max(1.0f - alpha, 0.0f);
    if (stepScale == 0.5f) return 1.0f - std::sqrt(transmittance);  // the default, without pow
    return stepScale == 1.0f ? alpha : 1.0f - std::pow(transmittance, stepScale);
}

// The most mip levels of a volume whose cones are traced in lanes (cone_lanes.cpp): a grid of 2^15 voxels a
// side.
constexpr int kMaxLevels = 16;

// The back-face weights of the scene and the object volume: only the starting surface's own volume gets one.
inline std::pair<float, float> backfaceWeights(const VisibilityVolumes& v, const ConeTraceSettings& s) {
    const bool sceneIsSelf = v.self == VisibilityVolumes::Self::Scene;
    return {sceneIsSelf ? s.backfaceWeight : 0.0f, sceneIsSelf ? 0.0f : s.backfaceWeight};
}

}  // namespace deltagi::cone_march
