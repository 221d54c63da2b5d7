// Temporal reuse: the kept frames' values are found again where the same surface point is now (the real
// scene's points where they were, the objects' on their triangles), a still frame stays exactly itself, and
// a sequence whose objects stop is render()'s image within temporal_frames frames.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/ray_scene.h"
#include "deltagi/renderer.h"
#include "deltagi/transforms.h"
#include "evaluation/temporal.h"
#include "pipeline/gbuffer.h"
#include "pipeline/temporal_reuse.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

using test::diffuse;
using test::placed;

Scene ballOverFloor(int width = 64, int height = 48) {
    Scene s = test::floorScene();
    s.camera = test::lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, width, height, 60.0f);
    s.virtuals.push_back(
        placed(makeSphere(0.3f, 32), {0.1f, 0.3f, 0.0f}, diffuse({0.2f, 0.3f, 0.9f}), "ball"));
    s.options.volume.center = glm::vec3(0.0f, 0.3f, 0.0f);
    s.options.volume.size = 1.6f;
    return s;
}

// One frame's surfaces, rendered as the pipeline renders them.
struct Surfaces {
    std::unique_ptr<RayScene> real, all;
    SurfacePoints realPoints;
    GBuffer gbuffer;
    Surfaces(const Scene& s) {
        real = std::make_unique<RayScene>(s, SceneContent::RealOnly);
        all = std::make_unique<RayScene>(s, SceneContent::VirtualOnly, real.get());
        realPoints = renderRealSurfaces(s.camera, *real);
        Bounds3f objects;
        for (const TriangleMesh& m : s.virtuals) objects.extend(m.bounds());
        renderObjectSurfaces(s.camera, *all, objects, 1, gbuffer);
        for (size_t i = 0; i < realPoints.size(); ++i)
            if (gbuffer.coverage[i] >= 1.0f) realPoints[i] = SurfacePoint{};
    }
};

// A value that belongs to the surface: a smooth function of the real point's position, and of the ball's
// point in the ball's own frame (`ballCentre` follows it).
glm::vec3 realValue(glm::vec3 p) {
    return {0.3f + 0.2f * p.x, 0.1f * p.z, -0.2f + 0.05f * (p.x + p.z)};
}
glm::vec3 objectValue(glm::vec3 p, glm::vec3 ballCentre) {
    const glm::vec3 q = p - ballCentre;
    return {0.5f + q.x, 0.4f + q.y, 0.3f + q.z};
}

struct Values {
    std::vector<glm::vec3> object, shadow;
};
Values valuesOf(const Surfaces& f, glm::vec3 ballCentre, float realOffset = 0.0f) {
    Values v;
    v.object.assign(f.realPoints.size(), glm::vec3(0.0f));
    v.shadow.assign(f.realPoints.size(), glm::vec3(0.0f));
    for (size_t i = 0; i < f.realPoints.size(); ++i) {
        if (f.realPoints[i].valid()) {
            v.shadow[i] = realValue(f.realPoints[i].position) + glm::vec3(realOffset);
        }
        if (f.gbuffer.object[i].valid()) v.object[i] = objectValue(f.gbuffer.object[i].position, ballCentre);
    }
    return v;
}

TemporalStats applyTo(TemporalReuse& reuse, const Scene& s, const Surfaces& f, Values& v, int frames = 4) {
    return reuse.apply(frames, {&s.camera, s.virtuals, &f.gbuffer, f.realPoints}, {v.object, v.shadow});
}

float meanDifference(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    double sum = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < a.size(); ++i)
        if (a[i] != glm::vec3(0.0f) && b[i] != glm::vec3(0.0f)) sum += glm::length(a[i] - b[i]), ++n;
    return n ? static_cast<float>(sum / n) : 0.0f;
}

float maxDifference(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    float m = 0.0f;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, glm::length(a[i] - b[i]));
    return m;
}

TEST(TemporalReuse, AMovingCameraFindsTheRealSurfacesAgain) {
    Scene s = ballOverFloor();
    TemporalReuse reuse;
    const glm::vec3 centre(0.1f, 0.3f, 0.0f);
    Values previous;
    {
        Surfaces f(s);
        previous = valuesOf(f, centre);
        Values v = previous;
        applyTo(reuse, s, f, v);
    }
    s.camera = turnedCamera(s.camera, {0, 0, 0}, 3.0f);  // about 3 pixels
    Surfaces f(s);
    const Values before = valuesOf(f, centre);
    Values v = before;
    const TemporalStats stats = applyTo(reuse, s, f, v);
    // The kept frame's values, found where the same points are now, agree with this frame's (to the
    // bilinear interpolation): nothing moves. At the same pixel they would not.
    EXPECT_GT(stats.realAveraged, 0.9 * stats.realPixels);
    EXPECT_GT(stats.realPixels, 1000u);
    const float samePixel = meanDifference(previous.shadow, before.shadow);
    EXPECT_GT(samePixel, 5e-3f);
    EXPECT_LT(meanDifference(v.shadow, before.shadow), 0.05f * samePixel);
    EXPECT_LT(maxDifference(v.shadow, before.shadow), 0.01f);
}

// Three frames of the ball, changed by `change` after each, then a fourth: the third frame's values (at the
// same pixels), the fourth's own and what reuse makes of them. `values` gives a frame's values of its
// surfaces.
struct Followed {
    Values previous, before, after;
    TemporalStats stats;
};
template <typename ValuesOf, typename Change>
Followed followBall(Scene& s, ValuesOf&& values, Change&& change) {
    TemporalReuse reuse;
    Followed out;
    for (int frame = 0; frame < 3; ++frame) {
        Surfaces f(s);
        out.previous = values(f);
        Values v = out.previous;
        applyTo(reuse, s, f, v);
        change();
    }
    Surfaces f(s);
    out.before = values(f);
    out.after = out.before;
    out.stats = applyTo(reuse, s, f, out.after);
    return out;
}

TEST(TemporalReuse, AMovingObjectIsFollowedOnItsTriangles) {
    Scene s = ballOverFloor();
    glm::vec3 centre(0.1f, 0.3f, 0.0f);
    const Followed ball = followBall(
        s, [&](const Surfaces& f) { return valuesOf(f, centre); },
        [&] {
            for (glm::vec3& p : s.virtuals[0].positions) p += glm::vec3(0.02f, 0.0f, 0.01f);
            centre += glm::vec3(0.02f, 0.0f, 0.01f);
        });
    EXPECT_GT(ball.stats.objectAveraged, 0.8 * ball.stats.objectPixels);
    EXPECT_GT(ball.stats.objectPixels, 100u);
    // The ball's values move with it: its kept values are this frame's, to the bilinear interpolation over
    // a curved surface; at the same pixel they would not be.
    const float samePixel = meanDifference(ball.previous.object, ball.before.object);
    EXPECT_LT(meanDifference(ball.after.object, ball.before.object), 0.25f * samePixel);
}

// An object that does not only move (it grows here) is followed on its triangles, at the kept frames'
// vertices.
TEST(TemporalReuse, AGrowingObjectIsFollowedOnItsTriangles) {
    Scene s = ballOverFloor();
    const glm::vec3 centre(0.1f, 0.3f, 0.0f);
    float scale = 1.0f;
    const Followed ball = followBall(
        s,
        [&](const Surfaces& f) {
            Values v = valuesOf(f, centre);
            for (size_t i = 0; i < v.object.size(); ++i)
                if (f.gbuffer.object[i].valid())
                    v.object[i] =
                        objectValue(centre + (f.gbuffer.object[i].position - centre) / scale, centre);
            return v;
        },
        [&] {
            for (glm::vec3& p : s.virtuals[0].positions) p = centre + 1.04f * (p - centre);
            scale *= 1.04f;
        });
    EXPECT_GT(ball.stats.objectAveraged, 0.8 * ball.stats.objectPixels);
    const float samePixel = meanDifference(ball.previous.object, ball.before.object);
    EXPECT_LT(meanDifference(ball.after.object, ball.before.object), 0.25f * samePixel);
}

TEST(TemporalReuse, AveragesWhatChangesFromFrameToFrameAndKeepsAStillFrameExactly) {
    Scene s = ballOverFloor();
    TemporalReuse reuse;
    const glm::vec3 centre(0.1f, 0.3f, 0.0f);
    Surfaces f(s);
    // A value that jumps back and forth by 0.001 from frame to frame (inside its neighbourhood's range, which
    // the gradient spans): the mean of 4 frames is the middle.
    Values last;
    for (int frame = 0; frame < 4; ++frame) {
        last = valuesOf(f, centre, frame % 2 ? 0.0005f : -0.0005f);
        applyTo(reuse, s, f, last);
    }
    const Values middle = valuesOf(f, centre);
    size_t middled = 0, real = 0;
    for (size_t i = 0; i < middle.shadow.size(); ++i) {
        if (!f.realPoints[i].valid()) continue;
        ++real;
        middled += glm::length(last.shadow[i] - middle.shadow[i]) < 1e-5f;
    }
    EXPECT_GT(middled, real / 2);
    // Four frames of the same values: exactly those values.
    TemporalReuse still;
    Values v;
    for (int frame = 0; frame < 4; ++frame) {
        v = valuesOf(f, centre);
        applyTo(still, s, f, v);
    }
    EXPECT_EQ(maxDifference(v.shadow, middle.shadow), 0.0f);
    EXPECT_EQ(maxDifference(v.object, middle.object), 0.0f);
    // frames = 1: nothing kept, nothing changed.
    Values once = valuesOf(f, centre, 0.3f);
    applyTo(still, s, f, once, 1);
    EXPECT_EQ(still.keptFrames(), 0u);
    EXPECT_EQ(maxDifference(once.shadow, valuesOf(f, centre, 0.3f).shadow), 0.0f);
}

// A frame of another size starts over: the kept frames are dropped, nothing is averaged.
TEST(TemporalReuse, AnotherImageSizeStartsOver) {
    Scene s = ballOverFloor();
    TemporalReuse reuse;
    const glm::vec3 centre(0.1f, 0.3f, 0.0f);
    for (int frame = 0; frame < 2; ++frame) {
        Surfaces f(s);
        Values v = valuesOf(f, centre, 0.01f * static_cast<float>(frame));
        applyTo(reuse, s, f, v);
    }
    EXPECT_EQ(reuse.keptFrames(), 2u);
    s.camera = test::lookAtCamera({0.0f, 1.6f, 1.6f}, {0, 0, 0}, 48, 36, 60.0f);
    Surfaces f(s);
    const Values before = valuesOf(f, centre, 0.5f);
    Values v = before;
    const TemporalStats stats = applyTo(reuse, s, f, v);
    EXPECT_EQ(stats.realAveraged + stats.objectAveraged, 0u);
    EXPECT_EQ(maxDifference(v.shadow, before.shadow), 0.0f);
    EXPECT_EQ(reuse.keptFrames(), 1u);
}

TEST(TemporalReuse, WhenTheObjectsStopTheFramesAreTheStillRenderWithinTemporalFrames) {
    Scene s = ballOverFloor();
    ASSERT_EQ(s.options.render.temporalFrames, 4);
    FrameRenderer frames;
    for (int frame = 0; frame < 5; ++frame) {
        frames.render(s);
        for (glm::vec3& p : s.virtuals[0].positions) p += glm::vec3(0.01f, 0.0f, 0.0f);
    }
    // A frame without reuse (a fresh renderer's first one; render() is a still, which spends more).
    const RenderOutput still = FrameRenderer().render(s);
    auto rmse = [&](const RenderOutput& a) {
        double sum = 0.0;
        for (size_t i = 0; i < a.composite.data().size(); ++i)
            sum += std::pow(a.composite.data()[i] - still.composite.data()[i], 2.0);
        return std::sqrt(sum / static_cast<double>(a.composite.data().size()));
    };
    // The first still frame still averages the moving ones; the fourth is the frame without reuse.
    const RenderOutput first = frames.render(s);
    EXPECT_GT(rmse(first), 1e-5);
    frames.render(s);
    frames.render(s);
    const RenderOutput fourth = frames.render(s);
    EXPECT_EQ(rmse(fourth), 0.0);
    // clearHistory(): the next frame is the frame without reuse at once.
    for (glm::vec3& p : s.virtuals[0].positions) p += glm::vec3(0.02f, 0.0f, 0.0f);
    frames.render(s);
    for (glm::vec3& p : s.virtuals[0].positions) p += glm::vec3(0.02f, 0.0f, 0.0f);
    frames.clearHistory();
    const RenderOutput cleared = frames.render(s);
    const RenderOutput again = FrameRenderer().render(s);
    for (size_t i = 0; i < cleared.composite.data().size(); ++i)
        ASSERT_EQ(cleared.composite.data()[i], again.composite.data()[i]);
}

TEST(TemporalReuse, SteadyMotionFlickersLess) {
    Scene s = ballOverFloor(96, 72);
    MotionOptions motion;
    motion.frames = 8;
    s.options.render.temporalFrames = 1;
    const TemporalFigures alone = temporalInstability(renderMotion(s, motion).frames);
    s.options.render.temporalFrames = 4;
    const TemporalFigures reused = temporalInstability(renderMotion(s, motion).frames);
    EXPECT_GT(alone.realInstability, 0.2);
    EXPECT_LT(reused.realInstability, 0.75 * alone.realInstability);
    EXPECT_LT(reused.objectInstability, alone.objectInstability);
}

// Under a turning camera the measure follows the surface points (temporalInstability of MotionFrames); the
// reuse finds them again in the kept frames, so it still smooths what a frame's own sampling adds.
TEST(TemporalReuse, SteadyMotionUnderATurningCameraFlickersLess) {
    Scene s = ballOverFloor(96, 72);
    MotionOptions motion;
    motion.frames = 8;
    motion.cameraStepDeg = 0.5f;
    s.options.render.temporalFrames = 1;
    const TemporalFigures alone = temporalInstability(renderMotion(s, motion));
    s.options.render.temporalFrames = 4;
    const TemporalFigures reused = temporalInstability(renderMotion(s, motion));
    ASSERT_TRUE(alone.followsSurfaces);
    std::printf("turning camera: real %.3f -> %.3f, object %.3f -> %.3f\n", alone.realInstability,
                reused.realInstability, alone.objectInstability, reused.objectInstability);
    EXPECT_GT(alone.realSamples, 6000u);   // of about 12,000 (the floor's pixels in 6 triples)
    EXPECT_GT(alone.objectSamples, 500u);  // of about 1,500 (the ball's, away from its silhouette)
    EXPECT_LT(reused.realInstability, 0.75 * alone.realInstability);
    EXPECT_LT(reused.objectInstability, alone.objectInstability);
}

}  // namespace
}  // namespace deltagi
