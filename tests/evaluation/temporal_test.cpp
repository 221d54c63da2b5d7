// Temporal stability (include/deltagi/temporal.h): the instability measure on frames made by hand, and on
// rendered frames of a moving object.
#include <gtest/gtest.h>

#include <cmath>

#include "deltagi/error.h"
#include "deltagi/temporal.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

// A 4 x 2 frame: the left half real (delta = `real`), the right half covered by an object (composite =
// `object`).
RenderOutput frame(float real, float object) {
    RenderOutput out;
    out.composite = Image(4, 2, 3, object);
    out.delta = Image(4, 2, 3, real);
    out.objectMask = Image(4, 2, 1, 0.0f);
    for (int y = 0; y < 2; ++y)
        for (int x = 2; x < 4; ++x) {
            out.objectMask.at(x, y, 0) = 1.0f;
            for (int c = 0; c < 3; ++c) out.delta.at(x, y, c) = 0.0f;
        }
    return out;
}

TEST(TemporalInstability, ASteadyChangeIsStableAndAJumpingOneIsNot) {
    std::vector<RenderOutput> steady, jumping;
    for (int t = 0; t < 6; ++t) {
        steady.push_back(frame(0.1f * static_cast<float>(t), 1.0f - 0.05f * static_cast<float>(t)));
        // The same trend, with every other frame off by as much as a frame's change.
        const float off = t % 2 ? 0.1f : 0.0f;
        jumping.push_back(frame(0.1f * static_cast<float>(t) + off, 1.0f - 0.05f * static_cast<float>(t)));
    }
    const TemporalFigures s = temporalInstability(steady);
    EXPECT_NEAR(s.realInstability, 0.0, 1e-5);
    EXPECT_NEAR(s.objectInstability, 0.0, 1e-5);
    EXPECT_EQ(s.realSamples, 4u * 4u);  // 4 real pixels in each of the 4 triples
    EXPECT_EQ(s.objectSamples, 4u * 4u);
    ASSERT_EQ(s.meanDelta.size(), 6u);
    EXPECT_NEAR(s.meanDelta[3], 0.3, 1e-6);
    const TemporalFigures j = temporalInstability(jumping);
    // Second differences of +-0.2 against central differences of 0.1 (or 0.2): a ratio well above 1.
    EXPECT_GT(j.realInstability, 1.0);
    EXPECT_NEAR(j.objectInstability, 0.0, 1e-5);
}

TEST(TemporalInstability, NeedsThreeFramesOfOneSize) {
    std::vector<RenderOutput> two = {frame(0, 0), frame(0, 0)};
    EXPECT_THROW(temporalInstability(two), InputError);
    std::vector<RenderOutput> mixed = {frame(0, 0), frame(0, 0), frame(0, 0)};
    mixed[1].delta = Image(3, 2, 3);
    EXPECT_THROW(temporalInstability(mixed), InputError);
}

TEST(TemporalInstability, RenderMotionMovesTheObjectsAndPutsThemBack) {
    Scene s = test::floorScene();
    s.virtuals.push_back(
        test::placed(makeSphere(0.2f, 16), {0.0f, 0.3f, 0.0f}, test::diffuse(glm::vec3(0.8f)), "ball"));
    s.options.volume.center = glm::vec3(0.0f, 0.3f, 0.0f);
    s.options.volume.size = 1.6f;
    const std::vector<glm::vec3> before = s.virtuals[0].positions;
    const Camera camera = s.camera;
    MotionOptions motion;
    motion.frames = 3;
    motion.objectStepVoxels = 4.0f;  // 0.2 a frame at 32^3 over 1.6
    motion.cameraStepDeg = 1.0f;
    const std::vector<RenderOutput> frames = renderMotion(s, motion);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(s.virtuals[0].positions, before);
    EXPECT_EQ(s.camera.worldFromCamera, camera.worldFromCamera);
    // The ball's image moved to the right (+x) between the first and the last frame.
    auto centroid = [](const Image& mask) {
        double sum = 0.0, weight = 0.0;
        for (int y = 0; y < mask.height(); ++y)
            for (int x = 0; x < mask.width(); ++x) {
                sum += x * mask.at(x, y, 0);
                weight += mask.at(x, y, 0);
            }
        return sum / weight;
    };
    EXPECT_GT(centroid(frames[2].objectMask), centroid(frames[0].objectMask) + 1.0);
    const TemporalFigures f = temporalInstability(frames);
    EXPECT_TRUE(std::isfinite(f.realInstability));
    EXPECT_GT(f.realSamples, 0u);
    motion.frames = 2;
    EXPECT_THROW(renderMotion(s, motion), InputError);
}

}  // namespace
}  // namespace deltagi
