#include "pipeline/cone_jobs.h"

#include <gtest/gtest.h>

#include "test_scenes.h"

namespace deltagi {
namespace {

// The objects' diffuse light by rays with the options' "auto": a still (a single render) gathers at every
// pixel of a 640x480 image with kAutoStillObjectGatherRays rays, a session's frame at every 4th pixel of
// every 4th row with kAutoObjectGatherRays; a given stride or count holds for both, and 0 rays gives the
// cones their own stride back.
TEST(ConeJobs, AStillGathersTheObjectsLightAtEveryPixelWithMoreRays) {
    Scene scene = test::floorScene();
    scene.camera = test::lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, 640, 480, 60.0f);
    const RayScene all(scene, SceneContent::RealAndVirtual);
    ConeJob still{.mode = ShadowMode::Shaded, .rays = {&all, nullptr, {}}, .still = true};
    ConeJob frame = still;
    frame.still = false;
    const Options automatic;
    ASSERT_NE(still.diffuseRays(automatic), nullptr);
    EXPECT_EQ(still.gatherRays(automatic), kAutoStillObjectGatherRays);
    EXPECT_EQ(still.diffuseStride(automatic, scene.camera), 1);
    EXPECT_EQ(frame.gatherRays(automatic), kAutoObjectGatherRays);
    EXPECT_EQ(frame.diffuseStride(automatic, scene.camera), kAutoDiffuseRayStride);
    EXPECT_GT(kAutoStillObjectGatherRays, kAutoObjectGatherRays);

    Options given;
    given.diffuse.objectGatherRays = 16;
    given.diffuse.pixelStride = 2;
    for (const ConeJob& job : {still, frame}) {
        EXPECT_EQ(job.gatherRays(given), 16);
        EXPECT_EQ(job.diffuseStride(given, scene.camera), 2);
    }
    Options cones;
    cones.diffuse.objectGatherRays = 0;
    for (const ConeJob& job : {still, frame}) {
        EXPECT_EQ(job.diffuseRays(cones), nullptr);
        EXPECT_EQ(job.diffuseStride(cones, scene.camera), kAutoDiffuseStride);
    }
    // Relit real surfaces never gather by these rays.
    ConeJob relit = still;
    relit.mode = ShadowMode::DeltaShadow;
    EXPECT_EQ(relit.diffuseRays(automatic), nullptr);
}

}  // namespace
}  // namespace deltagi
