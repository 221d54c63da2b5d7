// ObjectVolumes keeps the objects' volumes from frame to frame and redoes only what the objects change: every
// level of every volume must be the one computed from scratch, bit for bit, whatever the objects do.
#include "pipeline/object_volumes.h"

#include <gtest/gtest.h>

#include "pipeline/bounce_light.h"
#include "pipeline/object_bounce_rays.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

using test::diffuse;
using test::placed;

// A floor and a red block under a lamp inside the region (a 6-face RSM), a spot light outside it, and a ball.
Scene floorWithBall() {
    Scene s = test::floorScene();
    s.real.push_back(
        placed(makeBox({0.3f, 0.6f, 0.3f}), {-0.5f, 0.3f, -0.3f}, diffuse({0.8f, 0.2f, 0.2f}), "block"));
    s.lights[0].position = {0.1f, 0.9f, 0.1f};
    Light spot = test::pointLight({1.2f, 1.4f, 0.6f}, 3.0f);
    spot.type = Light::Type::Spot;
    spot.direction = glm::normalize(glm::vec3(-1.2f, -1.4f, -0.6f));
    spot.outerAngleDeg = 50.0f;
    spot.innerAngleDeg = 30.0f;
    s.lights.push_back(spot);
    s.virtuals.push_back(
        placed(makeSphere(0.2f, 24), {0.1f, 0.25f, 0.0f}, diffuse({0.2f, 0.3f, 0.9f}), "ball"));
    return s;
}

const VolumeRegion kRegion{glm::vec3(-0.8f, -0.3f, -0.8f), 1.6f, 32};

void moveMesh(TriangleMesh& m, glm::vec3 offset) {
    for (glm::vec3& p : m.positions) p += offset;
}

// The same bits in every voxel of every level (the objects' volumes may be stored over other windows).
void expectSameVolume(const MipVolume& kept, const MipVolume& scratch, const char* name) {
    ASSERT_EQ(kept.levelCount(), scratch.levelCount()) << name;
    for (int l = 0; l < kept.levelCount(); ++l) {
        const PackedGrid3 &a = kept.level(l), &b = scratch.level(l);
        ASSERT_EQ(a.resolution(), b.resolution()) << name;
        const int n = a.resolution();
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const glm::vec4 u = a.at(x, y, z), v = b.at(x, y, z);
                    ASSERT_EQ(packVoxel(u), packVoxel(v))
                        << name << ": level " << l << ", voxel (" << x << ", " << y << ", " << z << "): ("
                        << u.x << ", " << u.y << ", " << u.z << ", " << u.w << ") instead of (" << v.x << ", "
                        << v.y << ", " << v.z << ", " << v.w << ")";
                }
    }
    // The occupied bounds may be larger than the scan's, never smaller.
    VoxelBox occupied = kept.occupiedBounds();
    occupied.extend(scratch.occupiedBounds());
    EXPECT_EQ(occupied.lo, kept.occupiedBounds().lo) << name;
    EXPECT_EQ(occupied.hi, kept.occupiedBounds().hi) << name;
}

// The real scene's share, computed once as the renderer keeps it.
struct RealScene {
    RayScene rays;
    VoxelGeometry geometry;
    std::vector<ReflectiveShadowMap> rsms;
    Grid3 light;
    uint64_t lightVersion = 0;
    explicit RealScene(const Scene& s, uint64_t version = 0)
        : rays(s, SceneContent::RealOnly), geometry(voxelize(s.real, kRegion)), lightVersion(version) {
        for (const Light& l : s.lights)
            rsms.push_back(renderReflectiveShadowMap(rays, l, kRegion, s.options.rsm.resolution));
        const VoxelGeometry* alone[] = {&geometry};
        light = injectLight(rsms, kRegion, alone);
    }
};

// One frame as the renderer runs it (stages 1-4 on the kept volumes), checked against everything computed
// from scratch. Returns the number of voxels injected.
size_t frameEqualsScratch(ObjectVolumes& kept, const RealScene& real, const Scene& s) {
    const RayScene all(s, SceneContent::VirtualOnly, &real.rays);
    Bounds3f objectBounds;
    for (const TriangleMesh& m : s.virtuals) objectBounds.extend(m.bounds());
    kept.voxelize(s.virtuals, kRegion);
    std::vector<RsmUpdate> updates;
    std::vector<ReflectiveShadowMap> withObjects;
    for (size_t l = 0; l < s.lights.size(); ++l) {
        updates.push_back(traceRsmUpdate(real.rsms[l], all, s.lights[l], kRegion, objectBounds));
        withObjects.push_back(applyRsmUpdate(real.rsms[l], updates.back()));
    }
    kept.inject({real.geometry, real.rsms, real.light, nullptr, real.lightVersion}, updates);
    kept.mipmap();

    // From scratch, as render() does (the updated maps are the maps rendered with the objects, texel for
    // texel: ReflectiveShadowMap.UpdateForTheObjectsEqualsAFullRender).
    VoxelGeometry objects = voxelize(s.virtuals, kRegion);
    const VoxelGeometry* geometry[] = {&real.geometry, &objects};
    Grid3 full = injectLight(withObjects, kRegion, geometry);
    PackedGrid3 delta = deltaVolume(full, real.light);
    Grid3 objectLight(kRegion.resolution);
    for (size_t i = 0; i < objectLight.size(); ++i)
        if (objects.visibility[i].x > 0.0f) objectLight[i] = full[i];
    expectSameVolume(kept.objectLight(), buildMipChain(kRegion, std::move(objectLight)), "object light");
    expectSameVolume(kept.objectVisibility(), buildMipChain(kRegion, std::move(objects.visibility)),
                     "object visibility");
    expectSameVolume(kept.fullLight(), buildMipChain(kRegion, std::move(full)), "full light");
    expectSameVolume(kept.deltaLight(), buildMipChain(kRegion, std::move(delta)), "delta light");
    return kept.injectedBox().count();
}

TEST(ObjectVolumes, MovingObjectFramesEqualVolumesFromScratch) {
    Scene s = floorWithBall();
    const RealScene real(s);
    ObjectVolumes kept;
    const size_t all = VoxelBox::all(kRegion.resolution).count();
    EXPECT_EQ(frameEqualsScratch(kept, real, s), all);  // the first frame computes everything
    const glm::vec3 path[] = {
        {0.05f, 0.0f, 0.03f},  // small moves: only the box around the ball and its shadows is injected
        {0.04f, 0.02f, -0.05f}, {0.55f, 0.0f, 0.0f},  // partly out of the region (x > 0.8)
        {0.6f, 0.0f, 0.0f},                           // all out: only its shadow on the floor is left
        {-1.3f, 0.0f, 0.25f},                         // back in, far away
        {0.0f, -0.1f, 0.0f},                          // into the floor
    };
    for (const glm::vec3& offset : path) {
        SCOPED_TRACE(testing::Message()
                     << "moved by (" << offset.x << ", " << offset.y << ", " << offset.z << ")");
        moveMesh(s.virtuals[0], offset);
        const size_t injected = frameEqualsScratch(kept, real, s);
        if (HasFatalFailure()) return;
        EXPECT_LT(injected, all / 4);
        // The objects' own volumes are stored over the ball's box and a margin only.
        EXPECT_LT(kept.objectVisibility().bytes(), kept.fullLight().bytes() / 2);
        EXPECT_LT(kept.objectLight().bytes(), kept.fullLight().bytes() / 2);
    }
}

TEST(ObjectVolumes, ChangesOfTheObjectsMaterialAndNumberEqualVolumesFromScratch) {
    Scene s = floorWithBall();
    const RealScene real(s);
    ObjectVolumes kept;
    int frame = 0;
    auto next = [&] {
        SCOPED_TRACE(testing::Message() << "frame " << frame++);
        return frameEqualsScratch(kept, real, s);
    };
    next();
    s.virtuals[0].material.albedo = {0.9f, 0.9f, 0.1f};  // other reflected flux: same texels, new values
    next();
    s.virtuals[0].material.emission = {2.0f, 1.0f, 0.5f};  // emissive: the objects' emission grid appears
    next();
    s.virtuals.push_back(
        placed(makeBox(glm::vec3(0.15f)), {-0.2f, 0.1f, 0.4f}, diffuse(glm::vec3(0.7f)), "cube"));
    next();
    s.virtuals[0].material.emission = glm::vec3(0.0f);  // and goes again
    moveMesh(s.virtuals[1], {0.1f, 0.0f, -0.1f});
    next();
    s.virtuals.erase(s.virtuals.begin());  // one object fewer
    const size_t injected = next();
    EXPECT_LT(injected, VoxelBox::all(kRegion.resolution).count() / 4);
}

// A live session's real light changes every frame (a light camera): the kept volumes start from each new
// light, and are still the volumes from scratch, while the objects move too and after a large jump.
TEST(ObjectVolumes, FramesOfAChangingLightEqualVolumesFromScratch) {
    Scene s = floorWithBall();
    ObjectVolumes kept;
    for (uint64_t version = 1; version <= 5; ++version) {
        SCOPED_TRACE(testing::Message() << "light " << version);
        s.lights[0].position += glm::vec3(0.04f, -0.02f, 0.03f);
        s.lights[1].intensity *= 1.1f;
        moveMesh(s.virtuals[0], {0.03f, 0.0f, -0.02f});
        const RealScene real(s, version);
        frameEqualsScratch(kept, real, s);
        if (HasFatalFailure()) return;
        moveMesh(s.virtuals[0], {0.02f, 0.0f, 0.02f});  // and a frame of the same light
        EXPECT_LT(frameEqualsScratch(kept, real, s), VoxelBox::all(kRegion.resolution).count() / 4);
        if (HasFatalFailure()) return;
    }
    s.virtuals[0] = placed(makeSphere(0.7f, 24), {0.0f, 0.4f, 0.0f}, diffuse(glm::vec3(0.5f)), "big");
    frameEqualsScratch(kept, RealScene(s, 6), s);
}

// A light camera's many directional lights: the ball's shadows fall apart on the floor in eight directions,
// and only the rows of voxels they and the ball change are injected again, not their bounding box (which
// holds most of the floor and everything up to the ball's top). Still the volumes from scratch.
TEST(ObjectVolumes, ManyLightsReinjectTheRowsTheyChangeAndEqualVolumesFromScratch) {
    Scene s = floorWithBall();
    s.lights.clear();
    for (int k = 0; k < 8; ++k) {
        const float azimuth = glm::radians(45.0f * static_cast<float>(k) + 10.0f),
                    elevation = glm::radians(25.0f);
        Light sun;
        sun.type = Light::Type::Directional;
        sun.direction = -glm::vec3(std::cos(elevation) * std::cos(azimuth), std::sin(elevation),
                                   std::cos(elevation) * std::sin(azimuth));
        sun.intensity = 0.3f;
        s.lights.push_back(sun);
    }
    ObjectVolumes kept;
    for (uint64_t version = 1; version <= 3; ++version) {
        SCOPED_TRACE(testing::Message() << "light " << version);
        for (Light& sun : s.lights) sun.intensity *= 1.1f;
        moveMesh(s.virtuals[0], {0.03f, 0.0f, -0.02f});
        const RealScene real(s, version);
        const size_t box = frameEqualsScratch(kept, real, s);
        if (HasFatalFailure()) return;
        if (version > 1) EXPECT_LT(2 * kept.reinjectedVoxels(), box);
    }
}

// A directional light's map is traced again whole when the objects reach beyond the real scene (its rays
// start further out); a large jump injects everything again. Both give the volumes from scratch too.
TEST(ObjectVolumes, WholeMapsRetracedAndLargeJumpsEqualVolumesFromScratch) {
    Scene s = floorWithBall();
    s.lights = {test::directionalLight({0.3f, -1.0f, 0.2f}, 1.5f)};
    const RealScene real(s);
    ObjectVolumes kept;
    frameEqualsScratch(kept, real, s);
    moveMesh(s.virtuals[0], {0.05f, 0.0f, 0.05f});
    frameEqualsScratch(kept, real, s);
    // A ball as large as the region.
    s.virtuals[0] = placed(makeSphere(0.7f, 24), {0.0f, 0.4f, 0.0f}, diffuse(glm::vec3(0.5f)), "big");
    EXPECT_EQ(frameEqualsScratch(kept, real, s), VoxelBox::all(kRegion.resolution).count());
    s.virtuals[0] = placed(makeSphere(0.1f, 24), {0.3f, 0.2f, 0.0f}, diffuse(glm::vec3(0.5f)), "small");
    frameEqualsScratch(kept, real, s);
    moveMesh(s.virtuals[0], {-0.05f, 0.0f, 0.0f});
    frameEqualsScratch(kept, real, s);
}

// A ball between a floor and a ceiling that a lamp just under it lights brightly: the ball hides the bright
// ceiling from the floor beneath it, so the floor there reflects less light than the room's own volumes say.
// roomChange() holds that change (negative under the ball), only near the ball, and the objects' rays read it
// with the full light volume (the floor under the ball darker); with no gather rays it is not made.
// The injection lists the voxels it may make non-zero (InjectedVoxels), so that the box around them is found
// without reading the whole grid (injectedBounds): the same box as the scan's, of the float light and of its
// packed level 0, before and after the further bounces; and the bounces the same with the listed voxels as
// without.
TEST(ObjectVolumes, InjectedBoundsAreTheScansOfTheWholeGrid) {
    const Scene s = floorWithBall();
    const RayScene rays(s, SceneContent::RealOnly);
    const VoxelGeometry geometry = voxelize(s.real, kRegion, true, true);
    std::vector<ReflectiveShadowMap> rsms;
    for (const Light& l : s.lights) rsms.push_back(renderReflectiveShadowMap(rays, l, kRegion, 96));
    // A texel off every surface, in the region's far corner (the injection's off-surface voxels are a texel's
    // position rounded into the voxel beside its surface): it widens the box.
    RsmTexel stray{};
    stray.position = glm::vec3(0.75f, 1.25f, 0.75f);
    stray.normal = glm::vec3(0.0f, 1.0f, 0.0f);
    stray.flux = glm::vec3(0.01f);
    stray.area = 1e-3f;
    rsms[0].texels.push_back(stray);
    const VoxelGeometry* alone[] = {&geometry};
    InjectedVoxels written;
    Grid3 light = injectLight(rsms, kRegion, alone, &written);
    ASSERT_TRUE(written.listed);
    // Every non-zero voxel is listed: a surface voxel, or one off the surfaces (the stray texel's).
    EXPECT_EQ(written.offSurface.size(), 1u);
    std::vector<char> listed(light.size(), 0);
    for (const uint32_t i : geometry.surfaceVoxels) listed[i] = 1;
    for (const uint32_t i : written.offSurface) listed[i] = 1;
    for (size_t i = 0; i < light.size(); ++i)
        if (light[i] != glm::vec4(0.0f)) ASSERT_TRUE(listed[i]) << "voxel " << i << " is not listed";
    const VoxelBox all = VoxelBox::all(kRegion.resolution);
    ASSERT_EQ(nonZeroBounds(light, all).hi, glm::ivec3(kRegion.resolution));  // the stray texel's voxel
    EXPECT_EQ(injectedBounds(light, alone, written), nonZeroBounds(light, all));
    const PackedGrid3 packed(light);
    EXPECT_EQ(injectedBounds(packed, alone, written), nonZeroBounds(packed, all));

    const MipVolume visibility = buildMipChain(kRegion, geometry.visibility.clone());
    const glm::vec3 viewpoint(0.0f, 0.5f, 1.5f);
    const SurfaceRadiance bounce =
        bounceLight(light, geometry, visibility, Options{}, 2, viewpoint, &rays, &written);
    const SurfaceRadiance scanned = bounceLight(light, geometry, visibility, Options{}, 2, viewpoint, &rays);
    ASSERT_EQ(bounce.size(), scanned.size());
    for (size_t k = 0; k < bounce.size(); ++k) ASSERT_EQ(bounce[k], scanned[k]) << "surface voxel " << k;
    addBounce(light, bounce, geometry);
    EXPECT_EQ(injectedBounds(light, alone, written), nonZeroBounds(light, all));
}

TEST(ObjectVolumes, TheRoomChangeUnderABallIsTheCeilingLightItHides) {
    const VolumeRegion region{glm::vec3(0.0f, -0.05f, 0.0f), 1.0f, 32};
    Scene s;
    s.real.push_back(placed(makeQuad({0.98f, 0.98f}), {0.5f, 0.0f, 0.5f}, diffuse(glm::vec3(0.5f))));
    TriangleMesh ceiling = makeQuad({0.98f, 0.98f});
    for (glm::uvec3& t : ceiling.triangles) std::swap(t.y, t.z);
    s.real.push_back(placed(std::move(ceiling), {0.5f, 0.8f, 0.5f}, diffuse(glm::vec3(0.8f))));
    s.virtuals.push_back(placed(makeSphere(0.12f, 32), {0.5f, 0.2f, 0.5f}, diffuse(glm::vec3(0.5f))));
    s.lights.push_back(test::pointLight({0.5f, 0.7f, 0.5f}, 0.3f));
    const RayScene realOnly(s, SceneContent::RealOnly);
    const RayScene all(s, SceneContent::VirtualOnly, &realOnly);
    const VoxelGeometry real = voxelize(s.real, region, true, true);
    std::vector<ReflectiveShadowMap> rsms = {renderReflectiveShadowMap(realOnly, s.lights[0], region, 128)};
    const VoxelGeometry* alone[] = {&real};
    Grid3 light = injectLight(rsms, region, alone);
    const MipVolume sceneVisibility = buildMipChain(region, real.visibility.clone());
    // The room's further bounce, as the renderer adds it: the floor under the ball gets the ceiling's light.
    Options options;
    const SurfaceRadiance bounce =
        bounceLight(light, real, sceneVisibility, options, 1, glm::vec3(0.5f, 0.4f, 0.1f), &realOnly);
    addBounce(light, bounce, real);
    Bounds3f objectBounds;
    for (const TriangleMesh& m : s.virtuals) objectBounds.extend(m.bounds());
    const std::vector<RsmUpdate> updates = {traceRsmUpdate(rsms[0], all, s.lights[0], region, objectBounds)};
    auto frame = [&](ObjectVolumes& volumes, const Options& options, bool unchanged = false) {
        volumes.voxelize(s.virtuals, region, true, true, unchanged);
        volumes.inject({real, rsms, light, &bounce, 0}, updates);
        const RoomChangeInputs room{
            real, ShadowRayScenes{&realOnly, &all, objectBounds, objectSphereRadius(s.virtuals)}};
        volumes.mipmap(&sceneVisibility, &options, &all, &room);
    };
    ObjectVolumes volumes;
    frame(volumes, options);
    const MipVolume& change = volumes.roomChange();
    ASSERT_FALSE(change.empty());
    // The floor's voxels (y = 1: the floor at y = 0 lies in it) under the ball, and far from it.
    const glm::vec4 under = change.level(0).at(16, 1, 16), far = change.level(0).at(1, 1, 1);
    EXPECT_LT(under.x, 0.0f);
    EXPECT_EQ(under.w, 0.0f);
    EXPECT_EQ(far, glm::vec4(0.0f));
    // What a ray down from the ball's underside reads there: less with the change.
    const RayLanding hit{0.2f - 0.12f, glm::vec3(0.5f, 0.0f, 0.5f), glm::vec3(0, 1, 0)};
    const glm::vec3 room = volumeRadianceAt(volumes.fullLight(), hit);
    const glm::vec3 changed = volumeRadianceWithChangeAt(volumes.fullLight(), change, hit);
    EXPECT_GT(room.x, 0.0f);
    EXPECT_LT(changed.x, 0.9f * room.x);
    EXPECT_GE(changed.x, 0.0f);
    // A frame whose objects and light are the last one's (a camera that moves alone) keeps it, the same as
    // made again.
    const MipVolume first =
        buildMipChain(region, PackedGrid3::fromEach(32, [&](size_t i) {
                          return change.level(0).at(static_cast<int>(i % 32), static_cast<int>(i / 32 % 32),
                                                    static_cast<int>(i / 1024));
                      }));
    frame(volumes, options, true);
    frame(volumes, options, false);
    ObjectVolumes again;
    frame(again, options);
    for (const MipVolume* v : {&volumes.roomChange(), &again.roomChange()})
        expectSameVolume(*v, first, "the room change");
    // Without the objects' gather rays nothing reads it: it is not made.
    options.diffuse.objectGatherRays = 0;
    ObjectVolumes withoutRays;
    frame(withoutRays, options);
    EXPECT_TRUE(withoutRays.roomChange().empty());
}

}  // namespace
}  // namespace deltagi
