// Stage 6: voxel cone tracing (Crassin et al. 2011) with the accumulation of §3.1 of the paper.
//
// A cone is marched through the volumes; at each step it reads the mip level whose voxels are as wide as the
// cone there, and the step is a fraction of that width (§3.1: "the step size ... is adjusted to the voxel
// size"). Occlusion comes from the visibility volumes, adapted by their stored average normal; light from one
// light volume. Shadow cones (§3.5) read only occlusion.
#pragma once

#include <limits>
#include <span>
#include <vector>

#include "deltagi/options.h"
#include "pipeline/volume.h"

namespace deltagi {

struct ConeTraceSettings {
    float stepScale = 0.5f;
    float startOffset = 1.5f;  // level-0 voxels
    float maxOcclusion = 0.98f;
    float normalWeight = 1.0f;
    float backfaceWeight = 1.0f;
    float jitter = 1.0f;
    bool paperAccumulation = false;
    // traceLightChangeCone: the objects' own light and their occlusion are left out (the cones carry the
    // change of the real surfaces' light, through the scene's visibility): rays bring both instead
    // (traceObjectBounceRays).
    bool objectLightByRays = false;
};
ConeTraceSettings coneTraceSettings(const TraceOptions& options);

// The visibility volumes a cone is occluded by; either may be null (absent). `self` names the volume of the
// surface the cones start from: only its back faces are discounted (backface_weight), so that the surface
// does not shadow itself, while the other volume occludes from both sides (a floor point right under a ball,
// whose cones start inside the ball, must stay shadowed by it).
struct VisibilityVolumes {
    enum class Self { Scene, Object };
    const MipVolume* scene = nullptr;
    const MipVolume* object = nullptr;
    Self self = Self::Scene;
};

struct Cone {
    glm::vec3 origin{0.0f};        // world space, already offset from the surface (coneOrigin)
    glm::vec3 direction{0, 0, 1};  // unit
    float tanHalfAngle = 0.5f;
    float maxDistance = std::numeric_limits<float>::infinity();  // world units from origin
    float jitter = 0.0f;  // in [0, 1): the first sample is this fraction of a step further along
};

// A deterministic random number in [0, 1) for (pixel or voxel index, stream): cones of one point get
// different streams. Independent of the thread count by construction.
float hashToUnit(uint64_t index, uint32_t stream);

// Moves a surface point off its surface along the normal and the cone axis by `startOffset` voxels, so that
// the surface's own voxel does not occlude its cones.
glm::vec3 coneOrigin(glm::vec3 position, glm::vec3 normal, glm::vec3 direction, const VolumeRegion& region,
                     const ConeTraceSettings& settings);

// Light arriving along the cone: radiance from `light`, occluded by both visibility volumes. `steps`, if
// given, is incremented by the number of samples taken (for the microbenchmarks).
glm::vec3 traceLightCone(const Cone& cone, const MipVolume& light, const VisibilityVolumes& visibility,
                         const ConeTraceSettings& settings, int64_t* steps = nullptr);

// The change the virtual objects make to the light arriving along a cone at a real surface (relighting,
// §3.3), as a difference of two cones marched together: the full light volume seen through both visibility
// volumes, minus the light of the real scene alone (full - delta) seen through the scene's visibility alone.
// The paper reads the delta volume through both visibility volumes, which holds what the objects add and the
// light they take from surfaces they shadow, but not the light they block on its way between two real
// surfaces (the red wall's light that no longer reaches the floor behind the object); the difference holds
// all three, and is exactly the delta volume's cone wherever the objects do not occlude the cone.
// With `objectLight` (the full volume's voxels the objects occupy, ObjectVolumes::objectLight), a step's
// light with the objects is told apart: the scene's surfaces shine with their own radiance through the
// scene's opacity, the objects with theirs through the opacity they add. Without it the full volume's
// radiance, an average over both, would shine through the objects' opacity too: a black ball would glow with
// the floor's light in every coarse voxel it shares with the floor.
glm::vec3 traceLightChangeCone(const Cone& cone, const MipVolume& fullLight, const MipVolume& deltaLight,
                               const VisibilityVolumes& visibility, const ConeTraceSettings& settings,
                               const MipVolume* objectLight = nullptr);

// traceLightCone and traceLightChangeCone of every cone of a batch: out[i] is cone i's light. The cones are
// marched eight at a time in SIMD lanes (cone_lanes.cpp): the same light to within float rounding, several
// times faster. Where a volume the lookups share is not stored whole (none of the pipeline's), each cone is
// traced alone. `out` has a place for every cone.
void traceLightCones(std::span<const Cone> cones, const MipVolume& light, const VisibilityVolumes& visibility,
                     const ConeTraceSettings& settings, std::span<glm::vec3> out, int64_t* steps = nullptr);
void traceLightChangeCones(std::span<const Cone> cones, const MipVolume& fullLight,
                           const MipVolume& deltaLight, const VisibilityVolumes& visibility,
                           const ConeTraceSettings& settings, const MipVolume* objectLight,
                           std::span<glm::vec3> out);

// Occlusion accumulated along a shadow cone, by the scene volume alone, the object volume alone and both.
struct ShadowOcclusion {
    float scene = 0.0f, object = 0.0f, combined = 0.0f;
};
ShadowOcclusion traceShadowCone(const Cone& cone, const VisibilityVolumes& visibility,
                                const ConeTraceSettings& settings, int64_t* steps = nullptr);

// The occlusion along a shadow cone by one visibility volume alone, marched on its own: what
// traceShadowCone accumulates as `scene` (traceSceneOcclusion) or `object` (traceObjectOcclusion; steps where
// the sparse object volume reads only zeros are skipped). 0 without that volume. Since combined occlusion is
// 1 - (1 - scene)(1 - object), the relit shadow change scene - combined is -(1 - scene) * object: the scene's
// share, which only the real scene changes, can be kept from frame to frame.
float traceSceneOcclusion(const Cone& cone, const VisibilityVolumes& visibility,
                          const ConeTraceSettings& settings);
float traceObjectOcclusion(const Cone& cone, const VisibilityVolumes& visibility,
                           const ConeTraceSettings& settings);

// Whether the object volume occludes the shadow cone anywhere along its march (traceShadowCone would give
// object > 0). When it does not, scene and combined occlusion are equal: the objects change nothing for the
// point, and relighting can skip the cone. Reads the object volume alone, only near its occupied voxels.
bool shadowConeMeetsObjects(const Cone& cone, const VisibilityVolumes& visibility,
                            const ConeTraceSettings& settings);

// Directions of the diffuse cones around +z (a spiral of equal-solid-angle cells over the hemisphere), their
// cosine weights (summing to 1) and the half-angle that makes their solid angles cover the hemisphere.
struct DiffuseConeSet {
    std::vector<glm::vec3> directions;  // tangent space, z = normal
    std::vector<float> weights;
    float tanHalfAngle = 0.0f;
};
DiffuseConeSet makeDiffuseCones(int count, float apertureDeg);

// The cones of `set` around `normal` from `position` (coneOrigin's offset applied), appended to `batch`, each
// jittered by hashToUnit(jitterIndex, firstStream + its index); diffuseConesLight gives their light back as
// one value, weighted by the set's weights (`light`: theirs, in order).
void appendDiffuseCones(std::vector<Cone>& batch, const DiffuseConeSet& set, glm::vec3 position,
                        glm::vec3 normal, const VolumeRegion& region, const ConeTraceSettings& settings,
                        uint64_t jitterIndex, uint32_t firstStream);
glm::vec3 diffuseConesLight(const DiffuseConeSet& set, const glm::vec3* light);

// Half-angle tangent of the specular cone for a Phong exponent: the lobe falls to half its peak at the cone's
// edge; clamped to the options' aperture range.
float specularConeTanHalfAngle(float phongExponent, float minApertureDeg, float maxApertureDeg);

}  // namespace deltagi
