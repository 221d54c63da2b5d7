#include "pipeline/cone_trace.h"

#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "pipeline/mipmap.h"

namespace deltagi {
namespace {

constexpr int kN = 32;
const VolumeRegion kRegion{glm::vec3(0.0f), 1.0f, kN};

MipVolume uniformVolume(glm::vec4 value) {
    Grid3 g(kN);
    for (size_t i = 0; i < g.size(); ++i) g[i] = value;
    return buildMipChain(kRegion, std::move(g));
}

Cone centreCone(glm::vec3 dir, float tanHalf) {
    Cone c;
    c.origin = glm::vec3(0.5f);
    c.direction = glm::normalize(dir);
    c.tanHalfAngle = tanHalf;
    return c;
}

ConeTraceSettings settings(bool paper) {
    ConeTraceSettings s;
    s.paperAccumulation = paper;
    s.jitter = 0.0f;
    return s;
}

// A uniform participating "fog" of occlusion a and radiance L, traced with a ray (a cone of zero aperture
// stays at level 0): front-to-back compositing gives L times the accumulated occlusion; the paper's formula
// keeps light_acc at L times one step's opacity. Incoherent normals: the isotropic coverage (0.5) applies.
TEST(ConeTrace, UniformEmittingVolumeGivesTheClosedFormRadiance) {
    const glm::vec3 radiance(0.3f, 0.6f, 0.9f);
    const float a = 0.6f;
    MipVolume light = uniformVolume(glm::vec4(radiance * a, a));
    MipVolume vis = uniformVolume(glm::vec4(a, 0.0f, 0.0f, 0.0f));
    for (glm::vec3 dir : {glm::vec3(1, 0, 0), glm::vec3(1, 1, 1), glm::vec3(-0.2f, 0.5f, -1.0f)}) {
        const Cone cone = centreCone(dir, 0.0f);
        ConeTraceSettings f2b = settings(false);
        glm::vec3 l = traceLightCone(cone, light, {&vis, nullptr}, f2b);
        // Occlusion saturates well inside the volume: the result is L * (something in [maxOcclusion, 1]).
        // The volumes hold L * a and a in bfloat16: L is read back within 2^-7 (two roundings of 2^-8).
        const float rounding = std::ldexp(1.0f, -7);
        for (int c = 0; c < 3; ++c) {
            EXPECT_GE(l[c], radiance[c] * (1.0f - rounding) * f2b.maxOcclusion - 1e-5f);
            EXPECT_LE(l[c], radiance[c] * (1.0f + rounding) + 1e-5f);
        }
        ConeTraceSettings paper = settings(true);
        const float stepAlpha = 1.0f - std::pow(1.0f - 0.5f * a, paper.stepScale);
        glm::vec3 lp = traceLightCone(cone, light, {&vis, nullptr}, paper);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(lp[c], radiance[c] * stepAlpha, 2.0f * rounding * radiance[c] * stepAlpha);
    }
}

TEST(ConeTrace, EmptyVolumeGivesNoLightAndNoOcclusion) {
    MipVolume empty = uniformVolume(glm::vec4(0.0f));
    const Cone cone = centreCone({0, 1, 0}, 0.5f);
    EXPECT_EQ(traceLightCone(cone, empty, {&empty, &empty}, settings(false)), glm::vec3(0.0f));
    ShadowOcclusion o = traceShadowCone(cone, {&empty, &empty}, settings(false));
    EXPECT_EQ(o.scene, 0.0f);
    EXPECT_EQ(o.object, 0.0f);
    EXPECT_EQ(o.combined, 0.0f);
}

// A solid wall of the object volume across the cone's path occludes it; the scene volume stays clear.
TEST(ConeTrace, ShadowConeSeparatesSceneAndObjectOcclusion) {
    Grid3 wall(kN);
    for (int z = 0; z < kN; ++z)
        for (int y = 0; y < kN; ++y)
            for (int x = 24; x < 27; ++x) wall.at(x, y, z) = glm::vec4(1.0f, -1.0f, 0.0f, 0.0f);
    MipVolume object = buildMipChain(kRegion, std::move(wall));
    MipVolume empty = uniformVolume(glm::vec4(0.0f));
    ShadowOcclusion o = traceShadowCone(centreCone({1, 0, 0}, 0.05f), {&empty, &object}, settings(false));
    EXPECT_EQ(o.scene, 0.0f);
    EXPECT_GT(o.object, 0.95f);
    EXPECT_FLOAT_EQ(o.combined, o.object);
    // Away from the wall nothing occludes.
    ShadowOcclusion away = traceShadowCone(centreCone({-1, 0, 0}, 0.05f), {&empty, &object}, settings(false));
    EXPECT_LT(away.object, 1e-3f);
    // A cone that stops before the wall is not occluded by it.
    Cone shortCone = centreCone({1, 0, 0}, 0.05f);
    shortCone.maxDistance = 0.2f;
    EXPECT_EQ(traceShadowCone(shortCone, {&empty, &object}, settings(false)).object, 0.0f);
}

// The relit cone's change (traceLightChangeCone) along a ray from the centre: a lit real wall (radiance L)
// behind a black object's slab. With the objects in the cones, the slab hides the wall: -L. With the objects
// left to rays (objectLightByRays, traceObjectBounceRays brings what they hide), the cone sees no change.
TEST(ConeTrace, TheLightChangeConeLeavesTheObjectsToTheRaysWhenAsked) {
    const glm::vec3 radiance(0.5f, 0.25f, 0.1f);
    Grid3 sceneWall(kN), objectSlab(kN), full(kN), delta(kN), objects(kN);
    for (int z = 0; z < kN; ++z)
        for (int y = 0; y < kN; ++y) {
            for (int x = 26; x < 29; ++x) {
                sceneWall.at(x, y, z) = glm::vec4(1.0f, -1.0f, 0.0f, 0.0f);
                full.at(x, y, z) = glm::vec4(radiance, 1.0f);
                delta.at(x, y, z) = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
            }
            for (int x = 20; x < 23; ++x) {
                objectSlab.at(x, y, z) = glm::vec4(1.0f, -1.0f, 0.0f, 0.0f);
                full.at(x, y, z) = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
                delta.at(x, y, z) = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
                objects.at(x, y, z) = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
            }
        }
    const MipVolume sceneVisibility = buildMipChain(kRegion, std::move(sceneWall));
    const MipVolume objectVisibility = buildMipChain(kRegion, std::move(objectSlab));
    const MipVolume fullLight = buildMipChain(kRegion, std::move(full));
    const MipVolume deltaLight = buildMipChain(kRegion, std::move(delta));
    const MipVolume objectLight = buildMipChain(kRegion, std::move(objects));
    const VisibilityVolumes visibility{&sceneVisibility, &objectVisibility, VisibilityVolumes::Self::Scene};
    const Cone ray = centreCone({1, 0, 0}, 0.0f);
    ConeTraceSettings s = settings(false);
    const glm::vec3 hidden = traceLightChangeCone(ray, fullLight, deltaLight, visibility, s, &objectLight);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(hidden[c], -radiance[c], 0.03f * radiance[c]) << c;
    s.objectLightByRays = true;
    const glm::vec3 none = traceLightChangeCone(ray, fullLight, deltaLight, visibility, s, &objectLight);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(none[c], 0.0f, 1e-6f) << c;
}

// Each volume marched on its own gives traceShadowCone's share of it (as long as neither saturates, which
// stops the joint march earlier), and the combined occlusion is 1 - (1 - scene)(1 - object).
TEST(ConeTrace, EachVolumeAloneGivesItsShareOfTheShadowCone) {
    Grid3 sceneWall(kN), objectWall(kN);
    for (int z = 0; z < kN; ++z)
        for (int y = 0; y < kN; ++y) {
            sceneWall.at(20, y, z) = glm::vec4(0.3f, -0.3f, 0.0f, 0.0f);
            objectWall.at(26, y, z) = glm::vec4(0.4f, -0.4f, 0.0f, 0.0f);
        }
    const MipVolume scene = buildMipChain(kRegion, std::move(sceneWall));
    const MipVolume object = buildMipChain(kRegion, std::move(objectWall));
    const ConeTraceSettings s = settings(false);
    for (glm::vec3 dir : {glm::vec3(1, 0, 0), glm::vec3(1, 0.3f, -0.2f)}) {
        const Cone cone = centreCone(dir, 0.02f);
        const VisibilityVolumes both{&scene, &object, VisibilityVolumes::Self::Scene};
        const ShadowOcclusion joint = traceShadowCone(cone, both, s);
        const float sceneAlone = traceSceneOcclusion(cone, both, s);
        const float objectAlone = traceObjectOcclusion(cone, both, s);
        EXPECT_GT(sceneAlone, 0.1f);
        EXPECT_GT(objectAlone, 0.1f);
        EXPECT_FLOAT_EQ(sceneAlone, joint.scene);
        EXPECT_FLOAT_EQ(objectAlone, joint.object);
        EXPECT_NEAR(1.0f - (1.0f - sceneAlone) * (1.0f - objectAlone), joint.combined, 1e-5f);
    }
    EXPECT_EQ(traceObjectOcclusion(centreCone({-1, 0, 0}, 0.02f), {&scene, &object}, s), 0.0f);
    EXPECT_EQ(traceSceneOcclusion(centreCone({1, 0, 0}, 0.02f), {nullptr, &object}, s), 0.0f);
}

// The stored normal adapts occlusion: a surface occludes a cone that meets its front, not one that leaves
// through its back (backface_weight 1), so a surface does not shadow the cones that start on it.
TEST(ConeTrace, BackFacesDoNotOccludeWithFullBackfaceWeight) {
    Grid3 slab(kN);
    for (int z = 0; z < kN; ++z)
        for (int x = 0; x < kN; ++x) slab.at(x, 16, z) = glm::vec4(1.0f, 0.0f, 1.0f, 0.0f);  // normal +y
    MipVolume vis = buildMipChain(kRegion, std::move(slab));
    ConeTraceSettings s = settings(false);
    Cone fromAbove = centreCone({0, -1, 0}, 0.05f);
    fromAbove.origin = glm::vec3(0.5f, 0.6f, 0.5f);
    Cone fromBelow = centreCone({0, 1, 0}, 0.05f);
    fromBelow.origin = glm::vec3(0.5f, 0.4f, 0.5f);
    // Trilinear filtering spreads a one-voxel slab over two layers, so a head-on cone sees ~0.8, not 1.
    EXPECT_GT(traceShadowCone(fromAbove, {&vis, nullptr}, s).scene, 0.75f);
    EXPECT_EQ(traceShadowCone(fromBelow, {&vis, nullptr}, s).scene, 0.0f);
    s.backfaceWeight = 0.0f;
    EXPECT_GT(traceShadowCone(fromBelow, {&vis, nullptr}, s).scene, 0.75f);
    // normal_weight 0: the isotropic model, the same from both sides.
    s.normalWeight = 0.0f;
    EXPECT_FLOAT_EQ(traceShadowCone(fromBelow, {&vis, nullptr}, s).scene,
                    traceShadowCone(fromAbove, {&vis, nullptr}, s).scene);
}

TEST(DiffuseCones, CoverTheHemisphereWithCosineWeightsSummingToOne) {
    for (int count : {1, 6, 9, 16, 32}) {
        DiffuseConeSet set = makeDiffuseCones(count, 0.0f);
        ASSERT_EQ(set.directions.size(), static_cast<size_t>(count));
        EXPECT_NEAR(std::accumulate(set.weights.begin(), set.weights.end(), 0.0f), 1.0f, 1e-5f);
        for (glm::vec3 d : set.directions) {
            EXPECT_NEAR(glm::length(d), 1.0f, 1e-5f);
            EXPECT_GT(d.z, 0.0f);
        }
        if (count > 2) {
            // Solid angles add up to the hemisphere: N * 2 pi (1 - cos) = 2 pi.
            const float cosHalf = std::cos(std::atan(set.tanHalfAngle));
            EXPECT_NEAR(count * (1.0f - cosHalf), 1.0f, 1e-4f);
        }
        // Mean direction is the normal's (cosine-weighted irradiance of a uniform sky is along the normal).
        glm::vec3 mean(0.0f);
        for (size_t k = 0; k < set.directions.size(); ++k) mean += set.weights[k] * set.directions[k];
        if (count >= 9) EXPECT_LT(glm::length(glm::vec2(mean)), 0.15f) << count;
    }
    EXPECT_NEAR(makeDiffuseCones(6, 60.0f).tanHalfAngle, std::tan(glm::radians(30.0f)), 1e-6f);
}

TEST(SpecularCone, ApertureNarrowsWithGlossinessAndIsClamped) {
    const float rough =
        specularConeTanHalfAngle(Material{glm::vec3(0), glm::vec3(0), 0.8f}.phongExponent(), 1, 90);
    const float glossy =
        specularConeTanHalfAngle(Material{glm::vec3(0), glm::vec3(0), 0.1f}.phongExponent(), 1, 90);
    EXPECT_GT(rough, glossy);
    // Mirror-like: clamped to the minimum aperture.
    EXPECT_NEAR(specularConeTanHalfAngle(1e6f, 4.0f, 90.0f), std::tan(glm::radians(2.0f)), 1e-6f);
    // Lambertian-like: clamped to the maximum.
    EXPECT_NEAR(specularConeTanHalfAngle(0.0f, 4.0f, 60.0f), std::tan(glm::radians(30.0f)), 1e-6f);
}

}  // namespace
}  // namespace deltagi
