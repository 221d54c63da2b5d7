#include "live/marker_registration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>

#include "test_marker_capture.h"

namespace deltagi {
namespace {

using test::floorMarker;
using test::markerCamera;
using test::poseError;
using test::renderMarkerFrame;

float median(std::vector<float> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

// Camera positions around a marker at the origin: `count` of them at 0.7-1.1 units, 35-75 degrees above the
// floor, all around, each looking at a point near the marker (so that it is not always in the middle).
std::vector<std::pair<glm::vec3, glm::vec3>> viewsAround(int count) {
    std::vector<std::pair<glm::vec3, glm::vec3>> views;
    for (int i = 0; i < count; ++i) {
        const float t = (static_cast<float>(i) + 0.5f) / static_cast<float>(count);
        const float azimuth = 2.0f * std::numbers::pi_v<float> * t * 3.0f;
        const float elevation = glm::radians(35.0f + 40.0f * std::fmod(t * 7.0f, 1.0f));
        const float distance = 0.7f + 0.4f * std::fmod(t * 5.0f, 1.0f);
        const glm::vec3 position =
            distance * glm::vec3(std::cos(elevation) * std::cos(azimuth), std::sin(elevation),
                                 std::cos(elevation) * std::sin(azimuth));
        const glm::vec3 target(0.05f * std::cos(5.0f * azimuth), 0.0f, 0.05f * std::sin(3.0f * azimuth));
        views.emplace_back(position, target);
    }
    return views;
}

TEST(MarkerCells, AreTheTag36h11PatternWithItsBlackBorderAndWhiteRing) {
    const std::vector<bool> cells = markerCells(0);
    ASSERT_EQ(cells.size(), static_cast<size_t>(kMarkerCells * kMarkerCells));
    for (int i = 0; i < kMarkerCells; ++i) {
        EXPECT_FALSE(cells[i]) << "top white ring";
        EXPECT_FALSE(cells[static_cast<size_t>(i) * kMarkerCells]) << "left white ring";
        if (i >= 1 && i <= 8) {
            EXPECT_TRUE(cells[kMarkerCells + i]) << "top black border";
            EXPECT_TRUE(cells[static_cast<size_t>(i) * kMarkerCells + 1]) << "left black border";
        }
    }
    EXPECT_NE(markerCells(0), markerCells(1));
    EXPECT_TRUE(markerCells(587).empty());
    EXPECT_TRUE(markerCells(-1).empty());
}

// The case: a 12 cm marker about 1 m away covers about 40 pixels of a 320 x 240 image.
void expectRegistration(int width, int height, int views, float maxPositionMedian, float maxRotationMedian) {
    const std::vector<Marker> markers = {floorMarker(3, 0.12f, glm::vec3(0.0f))};
    std::vector<float> positionErrors, rotationErrors;
    int beyondThreeSigma = 0;
    MarkerDetector detector(markers);
    int seed = 0;
    for (const auto& [position, target] : viewsAround(views)) {
        const Camera camera = markerCamera(width, height, 40.0f, position, target);
        const Image frame = renderMarkerFrame(camera, markers, 1.5f, static_cast<uint64_t>(seed++));
        const MarkerDetector::Result found = detector.detect(frame);
        ASSERT_EQ(found.sightings.size(), 1u)
            << "camera at " << position.x << " " << position.y << " " << position.z;
        const std::optional<MarkerPose> pose = solveCameraPose(found.sightings, markers, camera);
        ASSERT_TRUE(pose);
        const test::PoseError e = poseError(pose->worldFromCamera, camera.worldFromCamera);
        positionErrors.push_back(e.position);
        rotationErrors.push_back(e.rotationDeg);
        EXPECT_LT(pose->reprojectionErrorPx, 0.5);
        // Seen from 35-75 degrees above the floor, one marker fixes the camera: a stream may start from it
        // (TrackingOptions::certainSigma), and its stated uncertainty bounds the error.
        EXPECT_FALSE(pose->ambiguous);
        EXPECT_LE(pose->positionSigma, 0.05 * pose->markerDistance);
        beyondThreeSigma += e.position > 3.0 * pose->positionSigma;
    }
    EXPECT_LE(beyondThreeSigma, views / 10);
    const float p = median(positionErrors), r = median(rotationErrors);
    testing::Test::RecordProperty("position_error_median_cm", std::to_string(100.0f * p));
    testing::Test::RecordProperty("rotation_error_median_deg", std::to_string(r));
    std::printf("%dx%d: position error median %.3f cm (max %.3f), rotation %.3f deg (max %.3f)\n", width,
                height, 100.0f * p, 100.0f * *std::max_element(positionErrors.begin(), positionErrors.end()),
                r, *std::max_element(rotationErrors.begin(), rotationErrors.end()));
    EXPECT_LE(p, maxPositionMedian);
    EXPECT_LE(r, maxRotationMedian);
}

TEST(MarkerRegistration, FindsTheCameraTo5MillimetresAndHalfADegreeAt320x240) {
    expectRegistration(320, 240, 24, 0.005f, 0.5f);
}

TEST(MarkerRegistration, FindsTheCameraTo5MillimetresAndHalfADegreeAt640x480) {
    expectRegistration(640, 480, 12, 0.005f, 0.5f);
}

TEST(MarkerRegistration, UsesEveryMarkerSeenThroughTheLensDistortion) {
    // Two markers, a lens with barrel distortion: the corners are undistorted before the pose is solved.
    const std::vector<Marker> markers = {floorMarker(3, 0.12f, glm::vec3(0.0f)),
                                         floorMarker(8, 0.1f, glm::vec3(-0.2f, 0.0f, 0.1f), 45.0f)};
    Camera camera =
        markerCamera(320, 240, 50.0f, {0.3f, 0.6f, 0.6f}, {0.15f, 0.0f, -0.1f});  // markers off-centre
    camera.distortion.model = LensDistortion::Model::OpenCV;
    camera.distortion.k1 = -0.2f;
    camera.distortion.k2 = 0.05f;
    const Image frame = renderMarkerFrame(camera, markers, 1.5f, 1);
    MarkerDetector detector(markers);
    const MarkerDetector::Result found = detector.detect(frame);
    ASSERT_EQ(found.sightings.size(), 2u);
    EXPECT_EQ(found.sightings[0].marker, 0);
    EXPECT_EQ(found.sightings[1].marker, 1);
    const std::optional<MarkerPose> pose = solveCameraPose(found.sightings, markers, camera);
    ASSERT_TRUE(pose);
    EXPECT_EQ(pose->markersSeen, 2);
    EXPECT_LT(pose->reprojectionErrorPx, 0.5);
    const test::PoseError e = poseError(pose->worldFromCamera, camera.worldFromCamera);
    EXPECT_LT(e.position, 0.01f);
    EXPECT_LT(e.rotationDeg, 0.5f);
    // The same corners taken as a pinhole camera's put it further off.
    Camera pinhole = camera;
    pinhole.distortion = {};
    const std::optional<MarkerPose> wrong = solveCameraPose(found.sightings, markers, pinhole);
    ASSERT_TRUE(wrong);
    const test::PoseError w = poseError(wrong->worldFromCamera, camera.worldFromCamera);
    std::printf("with the lens model %.2f cm, %.2f deg; without %.2f cm, %.2f deg\n", 100 * e.position,
                e.rotationDeg, 100 * w.position, w.rotationDeg);
    EXPECT_GT(w.position, 2.0f * e.position);
}

// The pixel where a point 5 cm above the marker (an object standing on it) appears.
glm::vec2 objectPixel(const Camera& intrinsics, const glm::mat4& worldFromCamera) {
    const glm::vec3 q(glm::inverse(worldFromCamera) * glm::vec4(0.0f, 0.05f, 0.0f, 1.0f));
    return intrinsics.imagePoint(q);
}

TEST(MarkerTracker, HoldsAStillCameraStillAndFollowsAMovingOne) {
    const std::vector<Marker> markers = {floorMarker(3, 0.12f, glm::vec3(0.0f))};
    // A still camera, 30 frames at 30 per second with a webcam's noise (4 levels): the object stays within
    // 0.1 px RMS of where it is on average (the jitter a viewer sees; the pose's constant error is another
    // matter).
    {
        const Camera camera = markerCamera(320, 240, 40.0f, {0.3f, 0.8f, 0.5f}, {0.0f, 0.0f, 0.0f});
        MarkerTracker tracker(markers, camera);
        MarkerDetector detector(markers);
        std::vector<glm::vec2> smoothed, raw;
        for (int i = 0; i < 30; ++i) {
            const Image frame = renderMarkerFrame(camera, markers, 4.0f, static_cast<uint64_t>(100 + i));
            const TrackedFrame t = tracker.track(frame, i / 30.0);
            ASSERT_EQ(t.state, TrackedFrame::State::Registered);
            if (i < 10) continue;  // once the filter has settled
            smoothed.push_back(objectPixel(camera, t.worldFromCamera));
            const std::optional<MarkerPose> pose =
                solveCameraPose(detector.detect(frame).sightings, markers, camera);
            raw.push_back(objectPixel(camera, pose->worldFromCamera));
        }
        auto jitter = [](const std::vector<glm::vec2>& p) {
            glm::vec2 mean(0.0f);
            for (glm::vec2 v : p) mean += v / static_cast<float>(p.size());
            float squared = 0.0f;
            for (glm::vec2 v : p) squared += glm::dot(v - mean, v - mean) / static_cast<float>(p.size());
            return std::sqrt(squared);
        };
        std::printf("still camera: the object jitters %.3f px RMS smoothed, %.3f px unsmoothed\n",
                    jitter(smoothed), jitter(raw));
        EXPECT_LT(jitter(smoothed), 0.1f);
        EXPECT_LT(jitter(smoothed), jitter(raw));
    }
    // A camera walking round the marker (about 40 degrees a second): the smoothed object lags under 1.5 px.
    {
        MarkerTracker tracker(markers, markerCamera(320, 240, 40.0f, {1, 1, 1}, {0, 0, 0}));
        std::vector<float> offsets;
        for (int i = 0; i < 30; ++i) {
            const float azimuth = glm::radians(20.0f + 1.3f * static_cast<float>(i));
            const Camera camera = markerCamera(
                320, 240, 40.0f, 0.9f * glm::vec3(0.6f * std::cos(azimuth), 0.8f, 0.6f * std::sin(azimuth)),
                {0.0f, 0.0f, 0.0f});
            const TrackedFrame t =
                tracker.track(renderMarkerFrame(camera, markers, 1.5f, static_cast<uint64_t>(i)), i / 30.0);
            ASSERT_EQ(t.state, TrackedFrame::State::Registered);
            if (i >= 10)
                offsets.push_back(glm::length(objectPixel(camera, t.worldFromCamera) -
                                              objectPixel(camera, camera.worldFromCamera)));
        }
        std::printf("moving camera: object %.3f px from the truth (median), %.3f px (max)\n", median(offsets),
                    *std::max_element(offsets.begin(), offsets.end()));
        EXPECT_LT(median(offsets), 1.5f);
    }
}

// One small marker seen head-on: a camera 3 degrees to its left and one 3 degrees to its right see mirror
// images of the same trapezoid, its corners under a tenth of a pixel apart (the planar ambiguity), while the
// cameras are 14 cm apart. Exact corners give the camera they were made from, with or without a last pose
// near the other (whose tilt is no minimum of their error: solveCameraPose takes the last pose's side only
// among minima that explain the corners about as well, as noisy corners have; docs/live.md measures it).
TEST(MarkerRegistration, SolvesTheExactCornersOfAMarkerSeenHeadOn) {
    Marker wall;
    wall.id = 3;
    wall.size = 0.12f;
    wall.worldFromMarker = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.4f, 0.0f));  // facing +z
    const std::vector<Marker> markers = {wall};
    auto orbit = [](float degrees) {
        const float a = glm::radians(degrees);
        return markerCamera(320, 240, 40.0f, glm::vec3(1.3f * std::sin(a), 0.4f, 1.3f * std::cos(a)),
                            {0.0f, 0.4f, 0.0f});
    };
    const Camera left = orbit(-3.0f), right = orbit(3.0f);
    // The exact corners seen from the right.
    MarkerSighting sighting;
    const std::array<glm::vec3, 4> corners = markerCorners(wall);
    for (int k = 0; k < 4; ++k) {
        const glm::vec3 q(glm::inverse(right.worldFromCamera) * wall.worldFromMarker *
                          glm::vec4(corners[k], 1.0f));
        sighting.corners[k] = glm::dvec2(right.imagePoint(q));
    }
    const std::vector<MarkerSighting> sightings = {sighting};
    const std::optional<MarkerPose> alone = solveCameraPose(sightings, markers, right);
    ASSERT_TRUE(alone);
    EXPECT_LT(poseError(alone->worldFromCamera, right.worldFromCamera).position, 0.01f);
    // Corners off by the noise of a real frame could as well be the other camera's: no certain pose.
    EXPECT_TRUE(alone->ambiguous || alone->positionSigma > 0.05 * alone->markerDistance);
    const std::optional<MarkerPose> afterLeft =
        solveCameraPose(sightings, markers, right, left.worldFromCamera);
    ASSERT_TRUE(afterLeft);
    EXPECT_LT(poseError(afterLeft->worldFromCamera, right.worldFromCamera).position, 0.01f);
    EXPECT_LT(afterLeft->reprojectionErrorPx, 0.01);
    EXPECT_GT(poseError(left.worldFromCamera, right.worldFromCamera).position, 0.13f);
}

TEST(MarkerTracker, HoldsTheLastPoseForAWhileThenSaysItIsLost) {
    const std::vector<Marker> markers = {floorMarker(3, 0.12f, glm::vec3(0.0f))};
    const Camera camera = markerCamera(320, 240, 40.0f, {0.3f, 0.8f, 0.5f}, {0.0f, 0.0f, 0.0f});
    TrackingOptions options;
    options.holdSeconds = 0.1;
    MarkerTracker tracker(markers, camera, options);
    const TrackedFrame seen = tracker.track(renderMarkerFrame(camera, markers), 0.0);
    ASSERT_EQ(seen.state, TrackedFrame::State::Registered);
    const Image empty = renderMarkerFrame(camera, {});
    const TrackedFrame held = tracker.track(empty, 0.05);
    EXPECT_EQ(held.state, TrackedFrame::State::Held);
    EXPECT_EQ(held.worldFromCamera, seen.worldFromCamera);
    EXPECT_EQ(tracker.track(empty, 0.2).state, TrackedFrame::State::Lost);
    // Other tags and tags too small to trust are counted, not used.
    std::vector<Marker> other = markers;
    other[0].id = 4;
    const TrackedFrame wrong = tracker.track(renderMarkerFrame(camera, other), 0.3);
    EXPECT_EQ(wrong.state, TrackedFrame::State::Lost);
    EXPECT_EQ(wrong.unknownTags, 1);
    const Camera far = markerCamera(320, 240, 40.0f, {0.6f, 2.3f, 1.0f}, {0.0f, 0.0f, 0.0f});  // 13-15 px
    const TrackedFrame tiny = tracker.track(renderMarkerFrame(far, markers), 0.4);
    EXPECT_EQ(tiny.state, TrackedFrame::State::Lost);
    EXPECT_EQ(tiny.tooSmall, 1);
}

// A pose that would move the camera faster than TrackingOptions::maxSpeed since the last registered frame is
// not trusted while the last pose is held; once the hold is over, the markers' pose is taken again.
TEST(MarkerTracker, HoldsThroughAPoseThatJumps) {
    const std::vector<Marker> markers = {floorMarker(3, 0.12f, glm::vec3(0.0f))};
    const Camera here = markerCamera(320, 240, 40.0f, {0.3f, 0.8f, 0.5f}, {0.0f, 0.0f, 0.0f});
    const Camera there = markerCamera(320, 240, 40.0f, {0.1f, 0.8f, 0.6f}, {0.0f, 0.0f, 0.0f});  // 22 cm
    TrackingOptions options;
    options.holdSeconds = 0.2;
    MarkerTracker tracker(markers, here, options);
    const TrackedFrame seen = tracker.track(renderMarkerFrame(here, markers), 0.0);
    ASSERT_EQ(seen.state, TrackedFrame::State::Registered);
    const Image far = renderMarkerFrame(there, markers);
    const TrackedFrame jumped = tracker.track(far, 1.0 / 30.0);
    EXPECT_EQ(jumped.state, TrackedFrame::State::Held);
    EXPECT_TRUE(jumped.jumped);
    EXPECT_EQ(jumped.markersSeen, 1);
    EXPECT_EQ(jumped.worldFromCamera, seen.worldFromCamera);
    // 0.1 s later 2 m/s allows 21 cm: still too far.
    EXPECT_EQ(tracker.track(far, 0.1).state, TrackedFrame::State::Held);
    // After the hold, the pose is taken.
    const TrackedFrame taken = tracker.track(far, 0.3);
    EXPECT_EQ(taken.state, TrackedFrame::State::Registered);
    EXPECT_FALSE(taken.jumped);
    EXPECT_LT(glm::distance(glm::vec3(taken.worldFromCamera[3]), there.position()), 0.01f);
    // More markers than the last frame saw are taken whatever the jump.
    const std::vector<Marker> two = {markers[0], floorMarker(4, 0.12f, glm::vec3(0.2f, 0.0f, 0.0f))};
    MarkerTracker more(two, here, options);
    ASSERT_EQ(more.track(renderMarkerFrame(here, markers), 0.0).state, TrackedFrame::State::Registered);
    EXPECT_EQ(more.track(renderMarkerFrame(there, two), 1.0 / 30.0).state, TrackedFrame::State::Registered);
    // With the gate off, a jump is taken at once.
    options.maxSpeed = 0.0;
    MarkerTracker open(markers, here, options);
    ASSERT_EQ(open.track(renderMarkerFrame(here, markers), 0.0).state, TrackedFrame::State::Registered);
    EXPECT_EQ(open.track(far, 1.0 / 30.0).state, TrackedFrame::State::Registered);
}

// One small marker seen from straight in front, 1.3 m away (30 pixels wide at 320x240), fits cameras tens of
// centimetres apart about as well: a stream does not start from it (the frame is Lost, `uncertain`) but from
// the first frame that also sees a second marker; after that the lone marker's pose near the last is taken
// while the camera cannot have gone far since.
TEST(MarkerTracker, StartsFromACertainPoseOnly) {
    Marker wall, side;
    wall.id = 3;
    wall.size = 0.12f;
    wall.worldFromMarker = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.4f, 0.0f));  // facing +z
    side.id = 4;
    side.size = 0.12f;
    side.worldFromMarker = glm::translate(glm::mat4(1.0f), glm::vec3(-0.3f, 0.3f, 0.1f)) *
                           glm::rotate(glm::mat4(1.0f), glm::radians(40.0f), glm::vec3(0, 1, 0));
    const Camera camera = markerCamera(320, 240, 40.0f, {0.02f, 0.42f, 1.3f}, {0.05f, 0.3f, 0.0f});
    const std::vector<Marker> both = {wall, side}, alone = {wall};
    MarkerTracker tracker(both, camera);
    const TrackedFrame first = tracker.track(renderMarkerFrame(camera, alone, 1.5f, 1), 0.0);
    EXPECT_EQ(first.state, TrackedFrame::State::Lost);
    EXPECT_TRUE(first.uncertain);
    EXPECT_EQ(first.markersSeen, 1);
    const TrackedFrame second = tracker.track(renderMarkerFrame(camera, both, 1.5f, 2), 1.0 / 30.0);
    EXPECT_EQ(second.markersSeen, 2);
    ASSERT_EQ(second.state, TrackedFrame::State::Registered);
    EXPECT_FALSE(second.uncertain);
    EXPECT_LT(poseError(second.worldFromCamera, camera.worldFromCamera).position, 0.01f);
    const TrackedFrame third = tracker.track(renderMarkerFrame(camera, alone, 1.5f, 3), 2.0 / 30.0);
    EXPECT_EQ(third.state, TrackedFrame::State::Registered);
    EXPECT_FALSE(third.uncertain);
    EXPECT_LT(poseError(third.worldFromCamera, camera.worldFromCamera).position, 0.03f);
    // A second later the camera may be anywhere within 2 m (TrackingOptions::maxSpeed): no pose again.
    const TrackedFrame late = tracker.track(renderMarkerFrame(camera, alone, 1.5f, 4), 2.0 / 30.0 + 1.0);
    EXPECT_EQ(late.state, TrackedFrame::State::Lost);
    EXPECT_TRUE(late.uncertain);
}

// A 640x480 stream is searched at half resolution but for every eighth frame (its first among them): the
// markers and their refined corners (within a tenth of a pixel) are those of the full resolution, also a 3 cm
// marker about 22 pixels wide.
TEST(MarkerDetector, FindsTheSameCornersAtHalfResolution) {
    const std::vector<Marker> markers = {floorMarker(3, 0.12f, glm::vec3(0.0f)),
                                         floorMarker(8, 0.03f, glm::vec3(0.16f, 0.0f, 0.02f))};
    const Camera camera = markerCamera(640, 480, 40.0f, {0.05f, 0.75f, 0.55f}, {0.06f, 0.0f, 0.0f});
    const Image frame = renderMarkerFrame(camera, markers, 1.5f, 1);
    MarkerDetector detector(markers);
    const MarkerDetector::Result full = detector.detect(frame);
    ASSERT_EQ(full.sightings.size(), 2u);
    EXPECT_LT(glm::length(full.sightings[1].corners[1] - full.sightings[1].corners[0]), 32.0);
    for (int frameIndex = 1; frameIndex < 8; ++frameIndex) {
        const MarkerDetector::Result half = detector.detect(frame);
        ASSERT_EQ(half.sightings.size(), 2u) << "frame " << frameIndex;
        for (size_t m = 0; m < 2; ++m) {
            EXPECT_EQ(half.sightings[m].marker, full.sightings[m].marker);
            for (int k = 0; k < 4; ++k)
                EXPECT_LT(glm::length(half.sightings[m].corners[k] - full.sightings[m].corners[k]), 0.1)
                    << "frame " << frameIndex << ", marker " << m << ", corner " << k;
        }
    }
}

TEST(MarkerRegistration, RefusesNothingToSolveFrom) {
    const std::vector<Marker> markers = {floorMarker(3, 0.12f, glm::vec3(0.0f))};
    Camera camera = markerCamera(320, 240, 40.0f, {0.3f, 0.8f, 0.5f}, {0.0f, 0.0f, 0.0f});
    EXPECT_FALSE(solveCameraPose({}, markers, camera));
    MarkerDetector detector(markers);
    EXPECT_TRUE(detector.detect(Image()).sightings.empty());
    Image nan(320, 240, 3, std::numeric_limits<float>::quiet_NaN());
    EXPECT_TRUE(detector.detect(nan).sightings.empty());
    camera.fx = 0.0f;
    const MarkerDetector::Result found = detector.detect(
        renderMarkerFrame(markerCamera(320, 240, 40.0f, {0.3f, 0.8f, 0.5f}, {0, 0, 0}), markers));
    ASSERT_EQ(found.sightings.size(), 1u);
    EXPECT_FALSE(solveCameraPose(found.sightings, markers, camera));
}

}  // namespace
}  // namespace deltagi
