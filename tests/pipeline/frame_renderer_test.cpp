// FrameRenderer keeps the real scene's share of the work between frames: its frames must be exactly
// render()'s.
#include <gtest/gtest.h>

#include <cmath>

#include "deltagi/environment.h"
#include "deltagi/renderer.h"
#include "evaluation/benchmark.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

using test::diffuse;
using test::placed;

Scene ballOverFloor() {
    Scene s = test::floorScene();
    s.real.push_back(
        placed(makeBox({0.3f, 0.6f, 0.3f}), {-0.6f, 0.3f, -0.3f}, diffuse({0.8f, 0.2f, 0.2f}), "box"));
    s.virtuals.push_back(
        placed(makeSphere(0.2f, 24), {0.1f, 0.3f, 0.0f}, diffuse({0.2f, 0.3f, 0.9f}), "ball"));
    s.options.volume.center = glm::vec3(0.0f, 0.3f, 0.0f);  // fixed: the real scene's voxels can be kept
    s.options.volume.size = 1.6f;
    // What is kept must give render()'s image exactly: temporal reuse, which averages frames on purpose, is
    // tested on its own (temporal_reuse_test.cpp).
    s.options.render.temporalFrames = 1;
    // Given rather than "auto", which a still (render()) resolves finer than a frame.
    s.options.diffuse.objectGatherRays = kAutoObjectGatherRays;
    return s;
}

void moveVirtuals(Scene& s, glm::vec3 offset) {
    for (TriangleMesh& m : s.virtuals)
        for (glm::vec3& p : m.positions) p += offset;
}

void expectSameImages(const RenderOutput& a, const RenderOutput& b) {
    ASSERT_EQ(a.composite.data().size(), b.composite.data().size());
    for (size_t i = 0; i < a.composite.data().size(); ++i)
        ASSERT_EQ(a.composite.data()[i], b.composite.data()[i]);
    for (size_t i = 0; i < a.background.data().size(); ++i)
        ASSERT_EQ(a.background.data()[i], b.background.data()[i]);
    for (size_t i = 0; i < a.objectMask.data().size(); ++i)
        ASSERT_EQ(a.objectMask.data()[i], b.objectMask.data()[i]);
}

TEST(FrameRenderer, MovingObjectFramesAreExactlyRendersFromScratch) {
    Scene s = ballOverFloor();
    FrameRenderer frames;
    const RenderOutput first = frames.render(s);
    expectSameImages(first, render(s));
    moveVirtuals(s, {0.05f, 0.0f, 0.03f});
    const RenderOutput second = frames.render(s);
    expectSameImages(second, render(s));
    // The frame did change: the object moved.
    double change = 0.0;
    for (size_t i = 0; i < first.composite.data().size(); ++i)
        change += std::abs(first.composite.data()[i] - second.composite.data()[i]);
    EXPECT_GT(change, 1.0);
}

// The volumes the cones read: three stored whole in bfloat16 (8 bytes a voxel over the mip chain), the
// objects' own two over the ball's box.
// With the options' "auto", a still (render()) gathers the objects' light finer than a session's frame: the
// frames differ from render() on the objects, and renderStill() between them is render()'s image bit for bit,
// with the kept work.
TEST(FrameRenderer, AStillIsRendersImageAndAFrameIsNot) {
    Scene s = ballOverFloor();
    s.options.diffuse.objectGatherRays = -1;  // "auto"
    FrameRenderer frames;
    const RenderOutput frame = frames.render(s);
    const RenderOutput still = render(s);
    ASSERT_EQ(frame.composite.data().size(), still.composite.data().size());
    size_t differing = 0;
    for (size_t i = 0; i < frame.composite.data().size(); ++i)
        differing += frame.composite.data()[i] != still.composite.data()[i];
    EXPECT_GT(differing, 0u);
    expectSameImages(frames.renderStill(s), still);
    EXPECT_TRUE(frames.lastFrameKept().world);
    moveVirtuals(s, {0.05f, 0.0f, 0.0f});
    expectSameImages(frames.renderStill(s), render(s));
}

TEST(FrameRenderer, ReportsTheBytesOfItsVolumes) {
    Scene s = ballOverFloor();
    FrameRenderer frames;
    EXPECT_EQ(frames.volumeBytes(), 0u);
    frames.render(s);
    const size_t n = static_cast<size_t>(s.options.volume.resolution);
    size_t whole = 0;
    for (size_t r = n; r >= 1; r /= 2) whole += r * r * r * 8;
    EXPECT_GT(frames.volumeBytes(), 3 * whole);
    EXPECT_LT(frames.volumeBytes(), 3 * whole + whole / 2);
}

// The objects' volumes are kept from frame to frame and redone only where the objects change them
// (ObjectVolumes): whatever the objects do between frames, the images are render()'s.
TEST(FrameRenderer, FramesOfObjectsThatMoveLeaveTheRegionAndChangeAreExactlyRendersFromScratch) {
    Scene s = ballOverFloor();
    FrameRenderer frames;
    int frame = 0;
    auto sameAsScratch = [&] {
        SCOPED_TRACE(testing::Message() << "frame " << frame++);
        expectSameImages(frames.render(s), render(s));
    };
    sameAsScratch();
    for (int i = 0; i < 3; ++i) {  // small moves
        moveVirtuals(s, {0.03f, 0.01f * static_cast<float>(i), -0.02f});
        sameAsScratch();
    }
    moveVirtuals(s, {0.6f, 0.0f, 0.0f});  // partly out of the region (x > 0.8)
    sameAsScratch();
    moveVirtuals(s, {-0.9f, 0.0f, 0.2f});  // back
    sameAsScratch();
    s.virtuals[0].material.albedo = {0.9f, 0.8f, 0.1f};  // the object's material
    sameAsScratch();
    s.virtuals.push_back(
        placed(makeBox(glm::vec3(0.2f)), {0.4f, 0.1f, 0.3f}, diffuse(glm::vec3(0.8f)), "cube"));
    sameAsScratch();  // one object more
    moveVirtuals(s, {0.02f, 0.0f, 0.02f});
    sameAsScratch();
    for (glm::vec3& p : s.virtuals[0].positions) p.y = 0.3f + 1.2f * (p.y - 0.3f);  // deformed: refit
    sameAsScratch();
    s.virtuals[1].triangles[0] = s.virtuals[1].triangles[1];  // other triangles, as many: built again
    sameAsScratch();
    const std::vector<TriangleMesh> objects = s.virtuals;
    s.virtuals.clear();  // none: the photo
    sameAsScratch();
    s.virtuals = {objects[1]};  // one object fewer than before
    sameAsScratch();
    s.lights[0].intensity *= 1.5f;  // a new light: nothing kept is used
    sameAsScratch();
    moveVirtuals(s, {-0.03f, 0.0f, 0.01f});
    sameAsScratch();
    s.real[0].material.albedo = glm::vec3(0.3f, 0.6f, 0.3f);  // the real scene's material: all redone
    sameAsScratch();
    moveVirtuals(s, {0.0f, 0.02f, 0.0f});
    sameAsScratch();
}

// Without a fixed volume, the region follows the objects: every move gives a new region, and what was kept
// over the old one (the scene's voxels, light and shadow cones) must not be used.
TEST(FrameRenderer, ARegionThatFollowsTheObjectsIsNotMistakenForTheOldOne) {
    Scene s = ballOverFloor();
    s.options.volume.center.reset();
    s.options.volume.size.reset();
    // A real shelf between the light and the ball: the scene shadows part of the ball's shadow.
    s.real.push_back(
        placed(makeBox({0.25f, 0.03f, 0.25f}), {0.2f, 0.6f, 0.05f}, diffuse(glm::vec3(0.5f)), "shelf"));
    FrameRenderer frames;
    expectSameImages(frames.render(s), render(s));
    moveVirtuals(s, {0.04f, 0.0f, -0.03f});
    expectSameImages(frames.render(s), render(s));
    moveVirtuals(s, {-0.02f, 0.01f, 0.05f});
    expectSameImages(frames.render(s), render(s));
}

TEST(FrameRenderer, ChangesToTheRealSceneAreNotMissed) {
    Scene s = ballOverFloor();
    FrameRenderer frames;
    frames.render(s);
    s.lights[0].intensity *= 2.0f;
    expectSameImages(frames.render(s), render(s));
    s.real[1].material.albedo = glm::vec3(0.1f, 0.9f, 0.1f);
    expectSameImages(frames.render(s), render(s));
    for (glm::vec3& p : s.real[1].positions) p.x += 0.1f;
    expectSameImages(frames.render(s), render(s));
    s.options.volume.size = 1.2f;  // a new region: the real scene's voxels are redone
    expectSameImages(frames.render(s), render(s));
}

// The camera moves too, as in a real session: the world-space work is kept, the camera-space work redone.
TEST(FrameRenderer, FramesOfAMovingCameraAreExactlyRendersFromScratchAndKeepTheWorldSpaceWork) {
    Scene s = ballOverFloor();
    FrameRenderer frames;
    expectSameImages(frames.render(s), render(s));
    EXPECT_FALSE(frames.lastFrameKept().world);
    EXPECT_FALSE(frames.lastFrameKept().light);
    for (int f = 1; f <= 3; ++f) {
        SCOPED_TRACE(testing::Message() << "frame " << f);
        const float angle = 0.05f * static_cast<float>(f);  // round the ball, above the floor and the box
        s.camera = test::lookAtCamera({1.6f * std::sin(angle), 1.6f, 1.6f * std::cos(angle)},
                                      {0.1f, 0.3f, 0.0f}, 64, 48, 60.0f);
        moveVirtuals(s, {0.01f, 0.0f, 0.0f});
        expectSameImages(frames.render(s), render(s));
        EXPECT_TRUE(frames.lastFrameKept().world);
        EXPECT_TRUE(frames.lastFrameKept().light);
        EXPECT_FALSE(frames.lastFrameKept().camera);
    }
    moveVirtuals(s, {0.01f, 0.0f, 0.0f});  // the camera still
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().world);
    EXPECT_TRUE(frames.lastFrameKept().camera);
}

// The same with a photo, as a session has: a moving camera's real surfaces are rendered straight into the
// relit ones, and a camera that stops makes the whole real G-buffer again.
TEST(FrameRenderer, FramesOfAMovingCameraOverAPhotoAreExactlyRendersFromScratch) {
    Scene s = ballOverFloor();
    s.background = Image(s.camera.width, s.camera.height, 3, 0.3f);
    FrameRenderer frames;
    expectSameImages(frames.render(s), render(s));
    for (int f = 1; f <= 4; ++f) {
        SCOPED_TRACE(testing::Message() << "frame " << f);
        if (f != 3) {  // frame 3: the camera stays where it was
            const float angle = 0.05f * static_cast<float>(f);
            s.camera = test::lookAtCamera({1.6f * std::sin(angle), 1.6f, 1.6f * std::cos(angle)},
                                          {0.1f, 0.3f, 0.0f}, 64, 48, 60.0f);
        }
        moveVirtuals(s, {0.02f, 0.0f, 0.0f});
        expectSameImages(frames.render(s), render(s));
    }
}

// A camera that crosses the plane of a real surface sees its other side: the RSMs and the bounces, which keep
// the camera's side of the real surfaces, are redone.
TEST(FrameRenderer, ACameraThatCrossesARealSurfacesPlaneRedoesTheWorldSpaceWork) {
    Scene s = ballOverFloor();
    // The box's face at x = -0.45 faces the camera at x = -0.3, and the camera at x = -0.6 sees its plane
    // from the other side (from above the box's top, at y = 1.6).
    FrameRenderer frames;
    s.camera = test::lookAtCamera({-0.3f, 1.6f, 1.6f}, {0.0f, 0.3f, 0.0f}, 64, 48, 60.0f);
    expectSameImages(frames.render(s), render(s));
    s.camera = test::lookAtCamera({-0.6f, 1.6f, 1.6f}, {0.0f, 0.3f, 0.0f}, 64, 48, 60.0f);
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().world);  // the geometry does not depend on the side
    EXPECT_FALSE(frames.lastFrameKept().light);
    s.camera = test::lookAtCamera({-0.65f, 1.6f, 1.6f}, {0.0f, 0.3f, 0.0f}, 64, 48, 60.0f);
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().world);
    EXPECT_TRUE(frames.lastFrameKept().light);
}

// The real light changes every frame, as under a light camera: the geometry and the camera's view are kept,
// the light's work redone, and every frame is render()'s.
TEST(FrameRenderer, FramesOfAMovingLightKeepTheGeometryAndTheViewAndAreExactlyRendersFromScratch) {
    Scene s = ballOverFloor();
    FrameRenderer frames;
    expectSameImages(frames.render(s), render(s));
    for (int f = 1; f <= 3; ++f) {
        SCOPED_TRACE(testing::Message() << "frame " << f);
        s.lights[0].position += glm::vec3(0.1f, -0.05f, 0.05f);
        s.lights[0].intensity *= 1.1f;
        if (f == 2) moveVirtuals(s, {0.02f, 0.0f, 0.0f});
        expectSameImages(frames.render(s), render(s));
        EXPECT_TRUE(frames.lastFrameKept().world);
        EXPECT_FALSE(frames.lastFrameKept().light);
        EXPECT_TRUE(frames.lastFrameKept().camera);
    }
    moveVirtuals(s, {0.01f, 0.0f, 0.0f});  // the light still: all kept
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().light);
    // Light, camera and objects at once, over a photo, as in a live session.
    s.background = Image(s.camera.width, s.camera.height, 3, 0.3f);
    expectSameImages(frames.render(s), render(s));
    for (int f = 1; f <= 2; ++f) {
        SCOPED_TRACE(testing::Message() << "live frame " << f);
        s.lights[0].position += glm::vec3(-0.05f, 0.0f, 0.1f);
        const float angle = 0.04f * static_cast<float>(f);
        s.camera = test::lookAtCamera({1.6f * std::sin(angle), 1.6f, 1.6f * std::cos(angle)},
                                      {0.1f, 0.3f, 0.0f}, 64, 48, 60.0f);
        moveVirtuals(s, {0.0f, 0.0f, 0.02f});
        expectSameImages(frames.render(s), render(s));
        EXPECT_TRUE(frames.lastFrameKept().world);
        EXPECT_FALSE(frames.lastFrameKept().light);
        EXPECT_FALSE(frames.lastFrameKept().camera);
    }
}

// A light that does not change keeps its reflective shadow map while another one changes (a lamp beside a
// light camera's environment), also when the camera moves: the frames are still exactly render()'s.
TEST(FrameRenderer, ALightThatDoesNotChangeKeepsItsMapWhileAnotherChanges) {
    Scene s = ballOverFloor();
    s.lights.push_back(test::directionalLight({0.3f, -1.0f, 0.2f}, 0.5f));
    FrameRenderer frames;
    expectSameImages(frames.render(s), render(s));
    for (int f = 1; f <= 2; ++f) {
        SCOPED_TRACE(testing::Message() << "frame " << f);
        s.lights[1].direction = glm::normalize(s.lights[1].direction + glm::vec3(0.1f, 0.0f, 0.0f));
        moveVirtuals(s, {0.02f, 0.0f, 0.0f});
        if (f == 2) s.camera = test::lookAtCamera({0.1f, 1.6f, 1.6f}, {0.1f, 0.3f, 0.0f}, 64, 48, 60.0f);
        expectSameImages(frames.render(s), render(s));
        EXPECT_FALSE(frames.lastFrameKept().light);
        EXPECT_EQ(frames.lastFrameKept().lightMapsKept, 1);
    }
    s.lights[0].position += glm::vec3(0.05f, 0.0f, 0.0f);  // both change: none is kept
    s.lights[1].intensity *= 2.0f;
    expectSameImages(frames.render(s), render(s));
    EXPECT_EQ(frames.lastFrameKept().lightMapsKept, 0);
    s.lights[1].intensity *= 2.0f;  // the lamp's map is the last frame's again
    expectSameImages(frames.render(s), render(s));
    EXPECT_EQ(frames.lastFrameKept().lightMapsKept, 1);
    moveVirtuals(s, {0.01f, 0.0f, 0.0f});  // the light kept whole
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().light);
    EXPECT_EQ(frames.lastFrameKept().lightMapsKept, 0);
}

// Objects that stay where they were keep their BVH and voxels while the light and the camera change (a live
// frame with a still object): the frames are still exactly render()'s, and the objects' work is redone when
// they move or their material changes.
TEST(FrameRenderer, ObjectsThatDoNotChangeKeepTheirWorkWhileTheLightAndCameraChange) {
    Scene s = ballOverFloor();
    FrameRenderer frames;
    expectSameImages(frames.render(s), render(s));
    EXPECT_FALSE(frames.lastFrameKept().objects);
    s.lights[0].position += glm::vec3(0.05f, 0.0f, 0.0f);
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().objects);
    EXPECT_FALSE(frames.lastFrameKept().light);
    s.camera = test::lookAtCamera({0.1f, 1.6f, 1.6f}, {0.1f, 0.3f, 0.0f}, 64, 48, 60.0f);
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().objects);
    moveVirtuals(s, {0.02f, 0.0f, 0.0f});
    expectSameImages(frames.render(s), render(s));
    EXPECT_FALSE(frames.lastFrameKept().objects);
    s.virtuals[0].material.albedo = glm::vec3(0.2f, 0.6f, 0.2f);
    expectSameImages(frames.render(s), render(s));
    EXPECT_FALSE(frames.lastFrameKept().objects);
    expectSameImages(frames.render(s), render(s));
    EXPECT_TRUE(frames.lastFrameKept().objects);
}

TEST(Benchmark, ReportsEveryRowAndPutsTheObjectsBack) {
    Scene s = ballOverFloor();
    const std::vector<glm::vec3> before = s.virtuals[0].positions;
    BenchOptions o;
    o.frames = 3;
    o.warmup = 1;
    const BenchResult r = runBenchmark(s, o);
    EXPECT_EQ(s.virtuals[0].positions, before);
    ASSERT_EQ(r.frames.size(), 3u);
    const nlohmann::ordered_json json = benchToJson(r);
    for (const char* key : {"voxelize_ms", "rsm_ms", "inject_ms", "mipmap_ms", "diffuse_ms", "specular_ms",
                            "shadow_ms", "gbuffer_ms", "composite_ms", "total_ms"}) {
        ASSERT_TRUE(json.contains(key)) << key;
        EXPECT_GE(json[key]["max"].get<double>(), json[key]["median"].get<double>()) << key;
        EXPECT_GE(json[key]["median"].get<double>(), 0.0) << key;
    }
    EXPECT_GT(json["total_ms"]["median"].get<double>(), json["diffuse_ms"]["median"].get<double>());
    EXPECT_EQ(json["triangles"]["virtual"].get<size_t>(), s.virtuals[0].triangleCount());
    EXPECT_EQ(json["volume_resolution"].get<int>(), 32);
}

// With a moving camera each frame has its photo and keeps the real scene's world-space work; the scene's
// camera, photo and options are put back.
TEST(Benchmark, AMovingCameraKeepsTheWorldSpaceWorkAndPutsTheCameraBack) {
    Scene s = ballOverFloor();
    const Camera camera = s.camera;
    BenchOptions o;
    o.frames = 3;
    o.warmup = 1;
    o.cameraDegrees = 3.0f;
    const BenchResult r = runBenchmark(s, o);
    EXPECT_EQ(r.worldKeptFrames, 3);
    EXPECT_EQ(s.camera.worldFromCamera, camera.worldFromCamera);
    EXPECT_FALSE(s.background.has_value());
    EXPECT_FALSE(s.options.volume.viewpoint.has_value());
    const nlohmann::ordered_json json = benchToJson(r);
    EXPECT_EQ(json["camera_motion_deg"].get<float>(), 3.0f);
    EXPECT_EQ(json["world_kept_frames"].get<int>(), 3);
    // The frames used their photos: nothing was rendered for the background.
    EXPECT_LT(json["background_ms"]["max"].get<double>(), json["total_ms"]["median"].get<double>());
}

// The live frame changes the real light every frame (a point light moves, an environment map turns and its
// lights are extracted again) and swings the camera; the scene's lights and environment are put back.
TEST(Benchmark, TheLiveFrameChangesTheRealLightAndPutsItBack) {
    Scene s = ballOverFloor();
    Environment environment;
    environment.radiance = Image(32, 16, 3, 0.2f);
    environment.radiance.setRgb(5, 3, glm::vec3(400.0f));  // a sun
    s.options.environment.lightCount = 2;
    setEnvironment(s, environment);
    const std::vector<Light> lights = s.lights;
    ASSERT_GE(lights.size(), 2u);
    BenchOptions o;
    o.frames = 3;
    o.warmup = 1;
    o.live = true;
    const BenchResult r = runBenchmark(s, o);
    EXPECT_EQ(r.lightKeptFrames, 0);
    EXPECT_EQ(r.worldKeptFrames, 3);
    EXPECT_EQ(r.cameraDegrees, kLiveCameraDegrees);
    ASSERT_EQ(s.lights.size(), lights.size());
    for (size_t l = 0; l < lights.size(); ++l) {
        EXPECT_EQ(s.lights[l].position, lights[l].position);
        EXPECT_EQ(s.lights[l].direction, lights[l].direction);
    }
    ASSERT_TRUE(s.environment.has_value());
    EXPECT_EQ(s.environment->worldFromEnvironment, glm::mat3(1.0f));
    EXPECT_FALSE(s.background.has_value());
    const nlohmann::ordered_json json = benchToJson(r);
    EXPECT_TRUE(json["live"].get<bool>());
    EXPECT_EQ(json["light_kept_frames"].get<int>(), 0);
    EXPECT_GT(json["environment_ms"]["max"].get<double>(), 0.0);
    EXPECT_LT(json["background_ms"]["max"].get<double>(), json["total_ms"]["median"].get<double>());
    // Without it, the same frames keep the light.
    o.live = false;
    o.cameraDegrees = kLiveCameraDegrees;
    EXPECT_EQ(runBenchmark(s, o).lightKeptFrames, 3);
}

}  // namespace
}  // namespace deltagi
