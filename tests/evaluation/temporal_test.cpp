// Temporal stability (src/evaluation/temporal.h): the instability measure on frames made by hand, and on
// rendered frames of a moving object.
#include <gtest/gtest.h>

#include <cmath>

#include "deltagi/error.h"
#include "evaluation/temporal.h"
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

// Frames of a real wall at distance 2 (the plane z = -2) seen by a camera sliding 2 pixels a frame along x
// (whole pixels: bilinear lookups are exact); the delta on the wall is a wave fixed to it, 5 pixels long,
// growing steadily from frame to frame, plus `jump` every other frame. The right quarter of the image is an
// object (mask 1, a constant composite).
MotionFrames slidingCamera(float jump) {
    MotionFrames motion;
    constexpr int kWidth = 48, kHeight = 12;
    for (int t = 0; t < 6; ++t) {
        Camera camera;
        camera.width = kWidth;
        camera.height = kHeight;
        camera.fx = camera.fy = 20.0f;
        camera.cx = 0.5f * kWidth;
        camera.cy = 0.5f * kHeight;
        const float shift = 2.0f / camera.fx * 2.0f;  // world units for 2 pixels at distance 2
        camera.worldFromCamera[3] = glm::vec4(shift * static_cast<float>(t), 0.0f, 0.0f, 1.0f);
        RenderOutput out;
        out.composite = Image(kWidth, kHeight, 3, 0.5f);
        out.delta = Image(kWidth, kHeight, 3, 0.0f);
        out.objectMask = Image(kWidth, kHeight, 1, 0.0f);
        out.depth = Image(kWidth, kHeight, 1, 2.0f);
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                if (x >= 3 * kWidth / 4) {
                    out.objectMask.at(x, y, 0) = 1.0f;
                    continue;
                }
                const float worldX =
                    camera.position().x + (static_cast<float>(x) + 0.5f - camera.cx) / camera.fx * 2.0f;
                const float wave = (0.1f + 0.02f * static_cast<float>(t)) *
                                   std::sin(worldX * camera.fx / 2.0f * 6.2832f / 5.0f);
                for (int c = 0; c < 3; ++c) out.delta.at(x, y, c) = wave + (t % 2 ? jump : 0.0f);
            }
        motion.frames.push_back(std::move(out));
        motion.cameras.push_back(camera);
    }
    return motion;
}

TEST(TemporalInstability, UnderAMovingCameraTheMeasureFollowsTheSurfaces) {
    const MotionFrames steady = slidingCamera(0.0f);
    // Pixel by pixel the wave slides under each pixel by 2/5 of its length a frame: large second differences.
    const TemporalFigures fixedPixels = temporalInstability(std::span<const RenderOutput>(steady.frames));
    EXPECT_GT(fixedPixels.realInstability, 1.0);
    // Along the wall's points the delta grows steadily: no second difference.
    const TemporalFigures followed = temporalInstability(steady);
    EXPECT_TRUE(followed.followsSurfaces);
    EXPECT_LT(followed.realInstability, 1e-3);
    // A lookup reads 4 x 4 pixels: of each middle frame's 36 real columns, those whose points the frame
    // before shows within 2 columns of the object (2 columns on) or the frame after within 1 of its left edge
    // (2 columns back) are not counted: columns 3 to 31, in rows 1 to 9 (a column more or less as the
    // projections round), in 4 triples.
    EXPECT_GE(followed.realSamples, 4u * 9u * 28u);
    EXPECT_LE(followed.realSamples, 4u * 9u * 30u);
    EXPECT_EQ(followed.objectInstability, 0.0);  // its composite does not change
    // A jump every other frame, a tenth of the wave, is flicker along the surfaces too.
    const TemporalFigures jumping = temporalInstability(slidingCamera(0.01f));
    EXPECT_GT(jumping.realInstability, 0.5);
    MotionFrames noDepth = slidingCamera(0.0f);
    noDepth.frames[1].depth = Image();
    EXPECT_THROW(temporalInstability(noDepth), InputError);
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
    const MotionFrames motionFrames = renderMotion(s, motion);
    const std::vector<RenderOutput>& frames = motionFrames.frames;
    ASSERT_EQ(frames.size(), 3u);
    ASSERT_EQ(motionFrames.cameras.size(), 3u);
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
