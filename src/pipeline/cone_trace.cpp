#include "pipeline/cone_trace.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "core/sampling.h"
#include "pipeline/cone_march.h"

namespace deltagi {

ConeTraceSettings coneTraceSettings(const TraceOptions& o) {
    const bool paper = o.accumulation == ConeAccumulation::Paper;
    return {o.stepScale, o.startOffset, o.maxOcclusion, o.normalWeight, o.backfaceWeight, o.jitter, paper};
}

float hashToUnit(uint64_t index, uint32_t stream) {
    // SplitMix64 finalizer over the index and stream.
    uint64_t z =
        index * 0x9E3779B97F4A7C15ull + (static_cast<uint64_t>(stream) << 32) + 0x632BE59BD9B4E019ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return static_cast<float>(z >> 40) * (1.0f / static_cast<float>(1ull << 24));
}

glm::vec3 coneOrigin(glm::vec3 position, glm::vec3 normal, glm::vec3 direction, const VolumeRegion& region,
                     const ConeTraceSettings& settings) {
    const float offset = settings.startOffset * region.voxelSize();
    // Along the normal, so the start leaves the surface's voxel; a little along the axis for grazing cones.
    return position + offset * normal + 0.5f * offset * direction;
}

namespace {

using namespace cone_march;

// Occlusion of a visibility sample seen along `dir` at mip `level`.
//
// Voxelization records surfaces, one voxel thick, so the occlusion of a coarse voxel (the fraction of filled
// sub-voxels, §3.2) of a surface crossing it is only 2^-level: read as an opacity, every thin wall would turn
// transparent at coarse levels and light would leak through it. The fraction is therefore scaled back by
// 2^level to the surface's coverage of the voxel's cross-section, and weighted by how the surface faces the
// cone (§3.1: "the occlusion value is thereby adapted with the normal stored in the volume"):
//   coherent normals (|mean normal| near 1): 1 for a surface facing the cone (seen obliquely, a surface
//     covers the cone's cross-section as well: the cone crosses more of its voxels), 1 - backface_weight
//     for one the cone leaves through its back (so that a convex surface does not shadow itself at grazing
//     angles);
//   incoherent normals (both sides of a thin part, a whole small object in one coarse voxel): the mean
//     projected area of randomly oriented surface, kIsotropicCoverage.
// normal_weight blends from the isotropic model (0) to the normal-adapted one (1).
// (kIsotropicCoverage and kBackfaceRamp: cone_march.h. A back face counts fully as one once cos(back) >=
// 1/kBackfaceRamp: the neighbours of a point on a convex surface face a grazing cone slightly from behind.)
// A cone's axis in lanes 1-3, lined up with a visibility voxel's mean normal (adaptedOcclusion's `dir`).
inline Float4 axisOf(const Cone& cone) {
    return Float4{0.0f, cone.direction.x, cone.direction.y, cone.direction.z};
}

inline float adaptedOcclusion(Float4 v, Float4 dir, float levelScale, const ConeTraceSettings& s,
                              float backfaceWeight) {
    const float occupancy = v[0];
    if (occupancy <= kEmpty) return 0.0f;
    const Float4 n = v / occupancy;  // lanes 1-3: the mean normal
    const Float4 squares = n * n, cosines = n * dir;
    const float coherence = std::min(std::sqrt(squares[1] + squares[2] + squares[3]), 1.0f);
    const float facing =
        coherence > 1e-6f ? (cosines[1] + cosines[2] + cosines[3]) / coherence : 0.0f;  // cos; > 0: back
    const float directional =
        facing > 0.0f ? 1.0f - backfaceWeight * std::min(1.0f, kBackfaceRamp * facing) : 1.0f;
    const float adapted = (1.0f - coherence) * kIsotropicCoverage + coherence * directional;
    const float weight = (1.0f - s.normalWeight) * kIsotropicCoverage + s.normalWeight * adapted;
    return std::clamp(occupancy * levelScale * weight, 0.0f, 1.0f);
}

// Marches the cone through the region of `reference` and calls visit(position, level, levelScale) at each
// step until visit returns false: the position in level-0 voxel units, the fractional mip level, 2^level.
template <typename Visit>
void marchCone(const Cone& cone, const MipVolume& reference, const ConeTraceSettings& settings,
               Visit&& visit) {
    const VolumeRegion& region = reference.region();
    const ConeSpan span = coneSpan(cone, region, settings);
    const float n = static_cast<float>(region.resolution);
    const float maxLevel = std::log2(n);
    for (float t = span.first; t < span.end;) {
        const float diameter = std::max(1.0f, 2.0f * t * cone.tanHalfAngle);
        const float level = std::min(fastLog2(diameter), maxLevel);
        // 2^level, the level's voxel width in level-0 voxels.
        const float levelScale = std::min(diameter, n);
        if (!visit(span.origin + t * cone.direction, level, levelScale)) return;
        t += diameter * settings.stepScale;
    }
}

const MipVolume& referenceOf(const MipVolume* a, const MipVolume* b) {
    return a ? *a : *b;
}

}  // namespace

glm::vec3 traceLightCone(const Cone& cone, const MipVolume& light, const VisibilityVolumes& visibility,
                         const ConeTraceSettings& settings, int64_t* steps) {
    Float4 lightAcc = {0.0f, 0.0f, 0.0f, 0.0f};
    float occlusionAcc = 0.0f;
    const auto [sceneBackface, objectBackface] = backfaceWeights(visibility, settings);
    const Float4 dir = axisOf(cone);
    int64_t count = 0;
    marchCone(cone, light, settings, [&](glm::vec3 position, float level, float levelScale) {
        // One set of corners for all the volumes of the region.
        const VolumeLookup at = light.lookup(position, level);
        ++count;
        float transmittance = 1.0f;
        if (visibility.scene)
            transmittance *= 1.0f - adaptedOcclusion(visibility.scene->gatherFloat4(at), dir, levelScale,
                                                     settings, sceneBackface);
        if (visibility.object)
            transmittance *= 1.0f - adaptedOcclusion(visibility.object->gatherFloat4(at), dir, levelScale,
                                                     settings, objectBackface);
        const float occlusionLocal = stepOpacity(1.0f - transmittance, settings.stepScale);
        if (occlusionLocal > 0.0f) {
            const Float4 l = light.gatherFloat4(at);
            const Float4 lightLocal = l[3] > 1e-6f ? l / l[3] : Float4{0.0f, 0.0f, 0.0f, 0.0f};
            // §3.1: light_acc = light_acc*occ_acc + light_local*occ_local*(1 - occ_acc) (as printed), or the
            // usual front-to-back compositing light_acc += light_local*occ_local*(1 - occ_acc).
            const Float4 contribution = lightLocal * (occlusionLocal * (1.0f - occlusionAcc));
            lightAcc =
                settings.paperAccumulation ? lightAcc * occlusionAcc + contribution : lightAcc + contribution;
            occlusionAcc += occlusionLocal * (1.0f - occlusionAcc);
        }
        return occlusionAcc < settings.maxOcclusion;
    });
    if (steps) *steps += count;
    return {lightAcc[0], lightAcc[1], lightAcc[2]};
}

glm::vec3 traceLightChangeCone(const Cone& cone, const MipVolume& fullLight, const MipVolume& deltaLight,
                               const VisibilityVolumes& visibility, const ConeTraceSettings& settings,
                               const MipVolume* objectLight) {
    // With the objects (a) and without them (b).
    Float4 lightA = {0.0f, 0.0f, 0.0f, 0.0f}, lightB = lightA;
    float occlusionA = 0.0f, occlusionB = 0.0f;
    const auto [sceneBackface, objectBackface] = backfaceWeights(visibility, settings);
    const Float4 dir = axisOf(cone);
    const Float4 zero = {0.0f, 0.0f, 0.0f, 0.0f};
    // A volume's radiance: rgb over its occupancy (w).
    auto radiance = [&](Float4 v) { return v[3] > 1e-6f ? v / v[3] : zero; };
    // `emitted`: the step's light times its opacity.
    auto composite = [&](Float4& light, float& occlusion, Float4 emitted, float opacity) {
        const Float4 contribution = emitted * (1.0f - occlusion);
        light = settings.paperAccumulation ? light * occlusion + contribution : light + contribution;
        occlusion += opacity * (1.0f - occlusion);
    };
    marchCone(cone, fullLight, settings, [&](glm::vec3 position, float level, float levelScale) {
        const VolumeLookup at = fullLight.lookup(position, level);
        const Float4 sceneVisibility = visibility.scene ? visibility.scene->gatherFloat4(at) : zero;
        const float scene = adaptedOcclusion(sceneVisibility, dir, levelScale, settings, sceneBackface);
        // Near the objects, a lookup of their own: their volumes (visibility, light) are stored over the same
        // windows around them, which it is placed in once for both.
        const bool nearObjects = visibility.object && visibility.object->mayReadNonZero(position, at.level0);
        VolumeLookup objectAt;
        if (nearObjects) objectAt = visibility.object->lookup(position, level);
        const float object = nearObjects ? adaptedOcclusion(visibility.object->gatherFloat4(objectAt), dir,
                                                            levelScale, settings, objectBackface)
                                         : 0.0f;
        const float opacityA = stepOpacity(scene + object - scene * object, settings.stepScale);
        const float opacityB = stepOpacity(scene, settings.stepScale);
        if (opacityA > 0.0f) {
            const Float4 full = fullLight.gatherFloat4(at);
            const Float4 delta = deltaLight.gatherFloat4(at);
            // The volumes hold radiance times occupancy (inject.cpp): the full volume's by the occupancy of
            // both visibility volumes, the scene's alone (full - delta) by the scene's. Dividing the scene's
            // light by the objects' occupancy too would dim it in every coarse voxel the objects share, while
            // its opacity (B) does not count them: B would fall short of A far from the objects.
            if (objectLight) {
                // The scene's surfaces (with the objects' effect on them) through the scene's opacity, the
                // objects' own light through the opacity they add.
                const Float4 objects = objectLight->gatherFloat4(nearObjects ? objectAt : at);
                const Float4 sceneRadiance = radiance(full - objects);
                if (settings.objectLightByRays)  // the rays bring the objects' light and what they hide
                    composite(lightA, occlusionA, sceneRadiance * opacityB, opacityB);
                else
                    composite(lightA, occlusionA,
                              sceneRadiance * opacityB + radiance(objects) * (opacityA - opacityB), opacityA);
            } else if (full[3] > 1e-6f) {
                composite(lightA, occlusionA, full / full[3] * opacityA, opacityA);
            }
            if (opacityB > 0.0f && sceneVisibility[0] > 1e-6f)
                composite(lightB, occlusionB, (full - delta) / sceneVisibility[0] * opacityB, opacityB);
        }
        return occlusionA < settings.maxOcclusion || occlusionB < settings.maxOcclusion;
    });
    const Float4 change = lightA - lightB;
    return {change[0], change[1], change[2]};
}

ShadowOcclusion traceShadowCone(const Cone& cone, const VisibilityVolumes& visibility,
                                const ConeTraceSettings& settings, int64_t* steps) {
    ShadowOcclusion acc;
    if (!visibility.scene && !visibility.object) return acc;
    const auto [sceneBackface, objectBackface] = backfaceWeights(visibility, settings);
    const MipVolume& reference = referenceOf(visibility.scene, visibility.object);
    const Float4 dir = axisOf(cone);
    int64_t count = 0;
    marchCone(cone, reference, settings, [&](glm::vec3 position, float level, float levelScale) {
        const VolumeLookup at = reference.lookup(position, level);
        ++count;
        float scene = 0.0f, object = 0.0f;
        if (visibility.scene)
            scene = stepOpacity(adaptedOcclusion(visibility.scene->gatherFloat4(at), dir, levelScale,
                                                 settings, sceneBackface),
                                settings.stepScale);
        if (visibility.object)
            object = stepOpacity(adaptedOcclusion(visibility.object->gatherFloat4(at), dir, levelScale,
                                                  settings, objectBackface),
                                 settings.stepScale);
        const float combined = scene + object - scene * object;  // exactly `scene` without objects
        acc.scene += scene * (1.0f - acc.scene);
        acc.object += object * (1.0f - acc.object);
        acc.combined += combined * (1.0f - acc.combined);
        // Stop once nothing more can change: the combined and the scene-only occlusion are both saturated.
        return acc.combined < settings.maxOcclusion || acc.scene < settings.maxOcclusion;
    });
    if (steps) *steps += count;
    return acc;
}

namespace {

// Occlusion accumulated along the cone by `volume` alone; `sparse`: skip the steps that cannot read a
// non-zero voxel.
float traceOneVolume(const Cone& cone, const MipVolume& volume, float backface, bool sparse,
                     const ConeTraceSettings& settings) {
    float acc = 0.0f;
    const Float4 dir = axisOf(cone);
    marchCone(cone, volume, settings, [&](glm::vec3 position, float level, float levelScale) {
        if (sparse && !volume.mayReadNonZero(position, static_cast<int>(level))) return true;
        const float local = stepOpacity(adaptedOcclusion(volume.gatherFloat4(volume.lookup(position, level)),
                                                         dir, levelScale, settings, backface),
                                        settings.stepScale);
        acc += local * (1.0f - acc);
        return acc < settings.maxOcclusion;
    });
    return acc;
}

}  // namespace

float traceSceneOcclusion(const Cone& cone, const VisibilityVolumes& visibility,
                          const ConeTraceSettings& settings) {
    if (!visibility.scene) return 0.0f;
    return traceOneVolume(cone, *visibility.scene, backfaceWeights(visibility, settings).first, false,
                          settings);
}

float traceObjectOcclusion(const Cone& cone, const VisibilityVolumes& visibility,
                           const ConeTraceSettings& settings) {
    if (!visibility.object) return 0.0f;
    return traceOneVolume(cone, *visibility.object, backfaceWeights(visibility, settings).second, true,
                          settings);
}

bool shadowConeMeetsObjects(const Cone& cone, const VisibilityVolumes& visibility,
                            const ConeTraceSettings& settings) {
    if (!visibility.object) return false;
    const MipVolume& objects = *visibility.object;
    const float backface = backfaceWeights(visibility, settings).second;
    bool meets = false;
    marchCone(cone, objects, settings, [&](glm::vec3 position, float level, float levelScale) {
        if (!objects.mayReadNonZero(position, static_cast<int>(level))) return true;
        const Float4 v = objects.gatherFloat4(objects.lookup(position, level));
        meets = adaptedOcclusion(v, axisOf(cone), levelScale, settings, backface) > 0.0f;
        return !meets;
    });
    return meets;
}

DiffuseConeSet makeDiffuseCones(int count, float apertureDeg) {
    DiffuseConeSet set;
    count = std::max(count, 1);
    constexpr float kMaxHalfAngle = std::numbers::pi_v<float> / 3.0f;  // 60 degrees: wider cones over-blur
    float halfAngle = apertureDeg > 0.0f ? 0.5f * glm::radians(apertureDeg)
                                         : std::acos(1.0f - 1.0f / static_cast<float>(count));
    set.tanHalfAngle = std::tan(std::min(halfAngle, kMaxHalfAngle));
    if (count == 1) {
        set.directions = {glm::vec3(0, 0, 1)};
        set.weights = {1.0f};
        return set;
    }
    // Equal-area bands in cos(theta), each cone at its band's centre; azimuths by the golden angle.
    const float goldenAngle = std::numbers::pi_v<float> * (3.0f - std::sqrt(5.0f));
    float weightSum = 0.0f;
    for (int i = 0; i < count; ++i) {
        const float cosTheta = 1.0f - (static_cast<float>(i) + 0.5f) / static_cast<float>(count);
        const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
        const float phi = goldenAngle * static_cast<float>(i);
        set.directions.emplace_back(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
        set.weights.push_back(cosTheta);  // equal solid angles: the cosine is the whole irradiance weight
        weightSum += cosTheta;
    }
    for (float& w : set.weights) w /= weightSum;
    return set;
}

void appendDiffuseCones(std::vector<Cone>& batch, const DiffuseConeSet& set, glm::vec3 position,
                        glm::vec3 normal, const VolumeRegion& region, const ConeTraceSettings& settings,
                        uint64_t jitterIndex, uint32_t firstStream) {
    const glm::mat3 frame = frameAround(normal);
    for (size_t k = 0; k < set.directions.size(); ++k) {
        Cone& cone = batch.emplace_back();
        cone.direction = frame * set.directions[k];
        cone.origin = coneOrigin(position, normal, cone.direction, region, settings);
        cone.tanHalfAngle = set.tanHalfAngle;
        cone.jitter = hashToUnit(jitterIndex, firstStream + static_cast<uint32_t>(k));
    }
}

glm::vec3 diffuseConesLight(const DiffuseConeSet& set, const glm::vec3* light) {
    glm::vec3 sum(0.0f);
    for (size_t k = 0; k < set.weights.size(); ++k) sum += set.weights[k] * light[k];
    return sum;
}

float specularConeTanHalfAngle(float phongExponent, float minApertureDeg, float maxApertureDeg) {
    // cos^n(theta) = 1/2 at the cone's edge.
    float halfAngle = phongExponent > 0.0f ? std::acos(std::pow(0.5f, 1.0f / phongExponent))
                                           : std::numbers::pi_v<float> / 2.0f;
    halfAngle =
        std::clamp(halfAngle, 0.5f * glm::radians(minApertureDeg), 0.5f * glm::radians(maxApertureDeg));
    return std::tan(std::min(halfAngle, glm::radians(89.0f)));
}

}  // namespace deltagi
