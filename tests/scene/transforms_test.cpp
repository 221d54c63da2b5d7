// What an application sets in code between frames: the objects' transforms, the camera's pose and the photo
// (deltagi/transforms.h, checkFrame in deltagi/renderer.h).
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "deltagi/shapes.h"
#include "deltagi/transforms.h"
#include "test_errors.h"
#include "test_scene_json.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

using test::expectContains;
using test::inputErrorOf;

glm::mat4 translation(glm::vec3 t) {
    return glm::translate(glm::mat4(1.0f), t);
}

void expectSameMesh(const TriangleMesh& a, const TriangleMesh& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    for (size_t i = 0; i < a.positions.size(); ++i) {
        ASSERT_EQ(a.positions[i], b.positions[i]) << "vertex " << i;
        ASSERT_EQ(a.normals[i], b.normals[i]) << "normal " << i;
    }
    for (size_t i = 0; i < a.triangles.size(); ++i) ASSERT_EQ(a.triangles[i], b.triangles[i]);
}

// A loaded object moved to its own transform, or away and back, is the loaded one bit for bit: frames of an
// application that moves objects equal the CLI's frames of the scene file with the same transforms.
TEST(SetTransform, AnObjectPlacedAtTheScenesTransformIsTheLoadedOneBitForBit) {
    nlohmann::json document = test::tinySceneJson(32, 24, {0.2, 0.3, 0.8});
    document["virtual"][0]["transform"] = {{"translate", {0.1, 0.15, -0.05}}, {"rotate_deg", {0, 30, 10}}};
    const Scene loaded = loadScene(document, "tiny.json");
    ASSERT_TRUE(loaded.virtuals[0].objectSpace);
    EXPECT_FALSE(loaded.real[0].objectSpace);  // the real scene does not move: no copy kept

    TriangleMesh moved = loaded.virtuals[0];
    setTransform(moved, translation({0.5f, 0.0f, 0.0f}));
    EXPECT_NEAR(moved.bounds().center().x, 0.5f, 1e-5f);
    setTransform(moved, loaded.virtuals[0].worldFromObject);
    expectSameMesh(moved, loaded.virtuals[0]);
    EXPECT_EQ(moved.name, "box");
    EXPECT_EQ(moved.material.albedo, loaded.virtuals[0].material.albedo);
}

// A mesh built in code is its own object-space mesh: transforms replace each other, they do not compound.
TEST(SetTransform, AMeshBuiltInCodeIsPlacedFromItsObjectSpaceEveryTime) {
    TriangleMesh ball = makeSphere(0.5f, 16);
    ball.name = "ball";
    setTransform(ball, translation({1.0f, 0.0f, 0.0f}));
    setTransform(ball, translation({0.0f, 2.0f, 0.0f}));
    EXPECT_NEAR(ball.bounds().center().x, 0.0f, 1e-5f);
    EXPECT_NEAR(ball.bounds().center().y, 2.0f, 1e-5f);
    setTransform(ball, glm::scale(glm::mat4(1.0f), glm::vec3(2.0f)));
    EXPECT_NEAR(ball.bounds().maxExtent(), 2.0f, 1e-4f);
    for (glm::vec3 n : ball.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
}

TEST(SetTransform, RefusesASingularOrNonAffineOrNonFiniteTransformNamingTheMesh) {
    TriangleMesh box = makeBox(glm::vec3(1.0f));
    box.name = "crate";
    expectContains(inputErrorOf([&] { setTransform(box, glm::mat4(0.0f) + glm::mat4(0.0f)); }),
                   {"mesh 'crate': transform", "last row"});
    glm::mat4 flat = glm::scale(glm::mat4(1.0f), {1.0f, 0.0f, 1.0f});
    expectContains(inputErrorOf([&] { setTransform(box, flat); }), {"mesh 'crate'", "singular"});
    glm::mat4 nan = translation({std::nanf(""), 0.0f, 0.0f});
    expectContains(inputErrorOf([&] { setTransform(box, nan); }), "expected finite numbers");
    // A failed call leaves the mesh as it was.
    EXPECT_NEAR(box.bounds().center().x, 0.0f, 1e-6f);
    EXPECT_FALSE(box.objectSpace);
}

TEST(CameraPose, LookAtPoseIsTheSceneReadersPose) {
    nlohmann::json document = test::tinySceneJson(32, 24, {0.2, 0.3, 0.8});
    const Scene loaded = loadScene(document, "tiny.json");
    EXPECT_EQ(lookAtPose({0, 0.8f, 2}, {0, 0.1f, 0}, {0, 1, 0}), loaded.camera.worldFromCamera);
    expectContains(inputErrorOf([] {
                       lookAtPose({1, 2, 3}, {1, 2, 3});
                   }),
                   "look_at: expected a point different");
    expectContains(inputErrorOf([] {
                       lookAtPose({0, 0, 0}, {0, 1, 0}, {0, 2, 0});
                   }),
                   "up: expected a direction");
}

TEST(CameraPose, RefusesScaleAndReflection) {
    expectContains(inputErrorOf([] { checkCameraPose(glm::scale(glm::mat4(1.0f), glm::vec3(2.0f))); }),
                   "world_from_camera: expected an orthonormal rotation");
    expectContains(inputErrorOf([] {
                       checkCameraPose(glm::scale(glm::mat4(1.0f), {-1.0f, 1.0f, 1.0f}));
                   }),
                   "reflection");
    checkCameraPose(lookAtPose({0, 1, 2}, {0, 0, 0}));  // no throw
}

TEST(CheckFrame, RefusesAPhotoOfTheWrongSizeOrWithNaNAndABadPose) {
    Scene s = test::floorScene();
    s.background = Image(s.camera.width + 1, s.camera.height, 3, 0.5f);
    expectContains(inputErrorOf([&] { render(s); }), {"background", "camera's size 64x48", "65x48"});
    s.background = Image(s.camera.width, s.camera.height, 3, 0.5f);
    s.background->at(3, 2, 1) = std::numeric_limits<float>::quiet_NaN();
    FrameRenderer frames;
    expectContains(inputErrorOf([&] { frames.render(s); }), "background: pixel (3, 2) is not finite");
    s.background.reset();
    s.camera.worldFromCamera[0] *= 2.0f;
    expectContains(inputErrorOf([&] { frames.render(s); }), "camera.world_from_camera");
    s.camera.worldFromCamera[0] *= 0.5f;
    s.camera.fx = 0.0f;
    expectContains(inputErrorOf([&] { frames.render(s); }), "camera: expected finite intrinsics");
}

// Objects moved by setTransform() from frame to frame: the kept work is reused and the frames are render()'s,
// to rounding: a refit BVH may meet the other triangle of a shared edge (renderer.h; 7e-9 at x = 0.2 here).
TEST(CheckFrame, FramesOfObjectsMovedBySetTransformAreRendersFromScratch) {
    Scene s = test::floorScene();
    s.options.volume.center = glm::vec3(0.0f, 0.3f, 0.0f);
    s.options.volume.size = 1.6f;
    s.options.render.temporalFrames = 1;  // the kept work alone (temporal reuse averages on purpose)
    s.options.diffuse.objectGatherRays = kAutoObjectGatherRays;  // "auto" is finer for a still (render())
    TriangleMesh ball = makeSphere(0.2f, 16);
    ball.name = "ball";
    s.virtuals.push_back(ball);
    FrameRenderer frames;
    for (float x : {0.0f, 0.1f, 0.2f}) {
        setTransform(s.virtuals[0], translation({x, 0.25f, 0.0f}));
        const RenderOutput a = frames.render(s), b = render(s);
        ASSERT_EQ(a.composite.data().size(), b.composite.data().size());
        for (size_t i = 0; i < a.composite.data().size(); ++i)
            ASSERT_NEAR(a.composite.data()[i], b.composite.data()[i], 1e-6f) << "x " << x << ", value " << i;
    }
}

}  // namespace
}  // namespace deltagi
