// `deltagi track`: synthetic captures of markers (test_marker_capture.h) as numbered PNGs and as an MP4,
// registered into a transforms file that the sequence reader (and so `render`) takes.
#include <gtest/gtest.h>

#include <numbers>

#include <fmt/format.h>

#include "deltagi/scene_io.h"
#include "test_cli.h"
#include "test_marker_capture.h"

namespace deltagi::test {
namespace {

constexpr int kWidth = 320, kHeight = 240, kFrames = 12;
constexpr float kFovDeg = 40.0f;

std::vector<Marker> trackMarkers() {
    return {floorMarker(3, 0.12f, glm::vec3(0.0f)),
            floorMarker(7, 0.12f, glm::vec3(0.25f, 0.0f, -0.1f), 30.0f)};
}

// The camera of frame i: on an arc about 0.9 units from the markers, 2 degrees a frame (1 degree of arc a
// frame at 30 frames per second is a slow walk around the table).
Camera trackCamera(int i) {
    const float azimuth = glm::radians(60.0f + 2.0f * static_cast<float>(i));
    const glm::vec3 position = glm::vec3(0.12f, 0.0f, -0.05f) +
                               0.9f * glm::vec3(0.6f * std::cos(azimuth), 0.8f, 0.6f * std::sin(azimuth));
    return markerCamera(kWidth, kHeight, kFovDeg, position, glm::vec3(0.12f, 0.0f, -0.05f));
}

class TrackTest : public CliTest {
  protected:
    // The scene: the tiny test scene with the capture's camera intrinsics and markers.
    fs::path trackScene(bool withMarkers = true) const {
        json scene = tinyScene();
        scene["camera"]["width"] = kWidth;
        scene["camera"]["height"] = kHeight;
        scene["camera"]["fov_y_deg"] = kFovDeg;
        if (withMarkers) {
            scene["markers"] = json::array();
            for (const Marker& m : trackMarkers()) {
                json rows = json::array();
                for (int r = 0; r < 4; ++r)
                    rows.push_back({m.worldFromMarker[0][r], m.worldFromMarker[1][r], m.worldFromMarker[2][r],
                                    m.worldFromMarker[3][r]});
                scene["markers"].push_back({{"id", m.id}, {"size", m.size}, {"transform", rows}});
            }
        }
        return writeScene(scene);
    }
    // The capture as numbered PNGs in dir/in.
    std::string writeCapture(std::span<const Marker> markers) const {
        fs::create_directories(dir_ / "in");
        for (int i = 0; i < kFrames; ++i)
            writeImage(renderMarkerFrame(trackCamera(i), markers, 1.5f, static_cast<uint64_t>(i)),
                       dir_ / "in" / fmt::format("frame_{:04d}.png", i));
        return (dir_ / "in" / "frame_####.png").string();
    }
    // Checks the transforms file against the true poses.
    void expectTruePoses(const fs::path& transforms, float maxPosition, float maxRotationDeg) const {
        const std::vector<SequenceFrame> frames = readTransforms(transforms, {});
        ASSERT_EQ(frames.size(), static_cast<size_t>(kFrames));
        for (int i = 0; i < kFrames; ++i) {
            const Camera truth = trackCamera(i);
            EXPECT_EQ(frames[i].camera.width, kWidth);
            EXPECT_NEAR(frames[i].camera.fy, truth.fy, 1e-3f);
            const PoseError e = poseError(frames[i].camera.worldFromCamera, truth.worldFromCamera);
            EXPECT_LT(e.position, maxPosition) << "frame " << i;
            EXPECT_LT(e.rotationDeg, maxRotationDeg) << "frame " << i;
            EXPECT_TRUE(fs::is_regular_file(frames[i].photo)) << frames[i].photo;
        }
    }
};

TEST_F(TrackTest, RegistersNumberedImagesIntoASequence) {
    const std::string pattern = writeCapture(trackMarkers());
    const fs::path out = dir_ / "out" / "transforms.json";
    const CliResult r = run("track " + quote(pattern) + " --scene " + quote(trackScene().string()) + " -o " +
                            quote(out.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("12 registered by markers"), std::string::npos) << r.err;
    // The One-Euro filter follows a camera moving 2 degrees a frame within a centimetre.
    expectTruePoses(out, 0.01f, 1.0f);
    const json transforms = json::parse(readText(out));
    EXPECT_EQ(transforms["frames"][0]["file_path"], "frames/frame_0000.png");
    EXPECT_EQ(transforms["frames"][0]["markers_seen"], 2);
    EXPECT_LT(transforms["frames"][0]["reprojection_error_px"].get<double>(), 0.5);
}

TEST_F(TrackTest, RegistersAnMp4) {
    const std::string pattern = writeCapture(trackMarkers());
    const fs::path video = dir_ / "capture.mp4";
    const CliResult encoded = run("encode " + quote(pattern) + " -o " + quote(video.string()) + " -q");
    ASSERT_EQ(encoded.exitCode, 0) << encoded.err;
    const fs::path out = dir_ / "out" / "transforms.json";
    const CliResult r = run("track " + quote(video.string()) + " --scene " + quote(trackScene().string()) +
                            " -o " + quote(out.string()) + " --no-smoothing -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    expectTruePoses(out, 0.01f, 1.0f);
    const json transforms = json::parse(readText(out));
    EXPECT_NEAR(transforms["fps"].get<double>(), 30.0, 1e-6);
    EXPECT_NEAR(transforms["frames"][1]["time"].get<double>() - transforms["frames"][0]["time"].get<double>(),
                1.0 / 30.0, 1e-6);
}

TEST_F(TrackTest, RefusesWhatCannotBeRegistered) {
    const fs::path out = dir_ / "out" / "transforms.json";
    const std::string pattern = writeCapture(trackMarkers());
    // A scene without markers.
    CliResult r = run("track " + quote(pattern) + " --scene " + quote(trackScene(false).string()) + " -o " +
                      quote(out.string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("markers: the scene places no marker"), std::string::npos) << r.err;
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    // A source that is not there.
    r = run("track " + quote((dir_ / "missing.mp4").string()) + " --scene " + quote(trackScene().string()) +
            " -o " + quote(out.string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("missing.mp4: file not found"), std::string::npos) << r.err;
    // A file that is no video.
    writeText(dir_ / "notes.mp4", "not a video");
    r = run("track " + quote((dir_ / "notes.mp4").string()) + " --scene " + quote(trackScene().string()) +
            " -o " + quote(out.string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("notes.mp4: cannot open"), std::string::npos) << r.err;
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    // Frames of another size than the scene's camera.
    json small = tinyScene();
    small["markers"] =
        json::array({{{"id", 3}, {"size", 0.12}, {"transform", {{"rotate_deg", {-90, 0, 0}}}}}});
    r = run("track " + quote(pattern) + " --scene " + quote(writeScene(small, "small.json").string()) +
            " -o " + quote(out.string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("frames of 320x240, the scene's camera"), std::string::npos) << r.err;
    // Frames in which no marker of the scene is seen: other tags only.
    std::vector<Marker> others = trackMarkers();
    others[0].id = 11, others[1].id = 12;
    fs::remove_all(dir_ / "in");
    writeCapture(others);
    r = run("track " + quote(pattern) + " --scene " + quote(trackScene().string()) + " -o " +
            quote(out.string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(
        r.err.find("no frame registered: none of the scene's markers (tag36h11, ids 3, 7) was seen in 12 "
                   "frames; tags of other ids were"),
        std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(temporaries().empty());
}

}  // namespace
}  // namespace deltagi::test
