// `deltagi live`: a synthetic capture (test_marker_capture.h) of the tiny test scene's floor with markers
// on it, augmented frame by frame; a light camera's frames as the environment; frames replayed in real time.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "core/environment.h"
#include "test_cli.h"
#include "test_marker_capture.h"

namespace deltagi::test {
namespace {

constexpr int kWidth = 160, kHeight = 120, kFrames = 6;

Marker liveMarker() {
    return floorMarker(5, 0.3f, glm::vec3(0.0f, 0.0f, 0.45f));
}

Camera liveCamera(int i) {
    return markerCamera(kWidth, kHeight, 45.0f, glm::vec3(0.05f * static_cast<float>(i), 0.8f, 1.5f),
                        glm::vec3(0.0f, 0.1f, 0.0f));
}

class LiveTest : public CliTest {
  protected:
    fs::path liveScene(bool environment = false) const {
        json scene = tinyScene();
        scene["camera"]["width"] = kWidth;
        scene["camera"]["height"] = kHeight;
        const Marker m = liveMarker();
        json rows = json::array();
        for (int r = 0; r < 4; ++r)
            rows.push_back({m.worldFromMarker[0][r], m.worldFromMarker[1][r], m.worldFromMarker[2][r],
                            m.worldFromMarker[3][r]});
        scene["markers"] = json::array({{{"id", m.id}, {"size", m.size}, {"transform", rows}}});
        if (environment) {
            scene["environment"] = {{"file", (dir_ / "light" / "frame_0000.png").string()},
                                    {"projection", "fisheye"},
                                    {"intensity", 2.0}};
            scene["options"]["environment"] = {{"light_count", 2}};
        }
        return writeScene(scene);
    }
    // Frames [0, kFrames); the marker is seen in those before `markersUntil`.
    std::string writeCapture(int markersUntil = kFrames) const {
        fs::create_directories(dir_ / "in");
        const std::vector<Marker> markers = {liveMarker()};
        for (int i = 0; i < kFrames; ++i)
            writeImage(
                renderMarkerFrame(liveCamera(i), i < markersUntil ? std::span(markers) : std::span<Marker>(),
                                  1.5f, static_cast<uint64_t>(i)),
                dir_ / "in" / fmt::format("frame_{:04d}.png", i));
        return (dir_ / "in" / "frame_####.png").string();
    }
};

TEST_F(LiveTest, AugmentsEachFrameOverItselfAndReportsIt) {
    const std::string camera = writeCapture(4);
    const fs::path stats = dir_ / "stats.json";
    const CliResult r = run("live " + quote(liveScene().string()) + " --camera " + quote(camera) + " -o " +
                            quote((dir_ / "out" / "frame_####.png").string()) + " --json " +
                            quote(stats.string()) + " --hold 0.04");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("frame 0: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("no marker for 0.04 s: showing the camera image as it is"), std::string::npos)
        << r.err;
    const json s = json::parse(readText(stats));
    EXPECT_EQ(s["summary"]["frames"], kFrames);
    EXPECT_EQ(s["summary"]["dropped"], 0);
    EXPECT_EQ(s["summary"]["registered"], 4);
    EXPECT_EQ(s["summary"]["held"], 1);  // frame 4, 33 ms after the last sighting
    EXPECT_EQ(s["summary"]["lost"], 1);
    ASSERT_EQ(s["frames"].size(), static_cast<size_t>(kFrames));
    EXPECT_GT(s["frames"][0]["latency_ms"].get<double>(), 0.0);
    EXPECT_TRUE(s["frames"][0]["stages_ms"].contains("diffuse"));
    EXPECT_LT(s["frames"][0]["reprojection_error_px"].get<double>(), 0.5);
    // A registered frame has the box over the camera image; a lost one is the camera image as it is.
    const Image input0 = readImage(dir_ / "in" / "frame_0000.png"),
                output0 = readImage(dir_ / "out" / "frame_0000.png");
    const glm::vec3 centre = input0.rgb(kWidth / 2, kHeight / 2 + 10),
                    augmented = output0.rgb(kWidth / 2, kHeight / 2 + 10);
    EXPECT_GT(glm::length(augmented - centre), 0.05f) << "the box is not drawn over the frame";
    const Image input5 = readImage(dir_ / "in" / "frame_0005.png"),
                output5 = readImage(dir_ / "out" / "frame_0005.png");
    for (size_t i = 0; i < input5.data().size(); ++i) ASSERT_EQ(input5.data()[i], output5.data()[i]);
}

TEST_F(LiveTest, LightsTheSceneWithTheLightCamerasFrames) {
    const std::string camera = writeCapture();
    // A fish-eye light camera looking up at a sky that brightens from frame 3 on, to the camera's white.
    fs::create_directories(dir_ / "light");
    for (int i = 0; i < kFrames; ++i) {
        Image sky(64, 64, 3, 0.0f);
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x)
                if (glm::length(glm::vec2(x - 31.5f, y - 31.5f)) < 32.0f)
                    sky.setRgb(x, y, glm::vec3(i < 3 ? 0.2f : 1.0f));
        writeImage(sky, dir_ / "light" / fmt::format("frame_{:04d}.png", i));
    }
    const fs::path stats = dir_ / "stats.json";
    const CliResult r =
        run("live " + quote(liveScene(true).string()) + " --camera " + quote(camera) + " --light-camera " +
            quote((dir_ / "light" / "frame_####.png").string()) + " -o " +
            quote((dir_ / "out" / "frame_####.png").string()) + " --json " + quote(stats.string()) + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("frame 3: 78.8 % of the light camera's pixels are at its white"), std::string::npos)
        << r.err;
    EXPECT_EQ(lineCount(r.err), 2u) << r.err;  // and the loader's about the scene's own 8-bit probe
    const json s = json::parse(readText(stats));
    EXPECT_EQ(s["summary"]["light_frames"], kFrames);
    EXPECT_GT(s["frames"][0]["environment_ms"].get<double>(), 0.0);
    // The box brightens with the sky, over a few frames (the light camera's average).
    auto boxBrightness = [&](int i) {
        return luminance(
            readImage(dir_ / "out" / fmt::format("frame_{:04d}.png", i)).rgb(kWidth / 2, kHeight / 2 + 10));
    };
    EXPECT_NEAR(boxBrightness(1), boxBrightness(2), 0.02f);
    EXPECT_GT(boxBrightness(3), boxBrightness(2) + 0.02f);
    EXPECT_GT(boxBrightness(5), boxBrightness(3));
}

TEST_F(LiveTest, DropsWhatItCannotKeepUpWithInRealTime) {
    const std::string camera = writeCapture();
    // The capture played five times over: 30 frames in 30 ms, while the first frame alone renders for longer
    // (its volumes and maps are new), on a loaded machine too.
    constexpr int kPlayed = 5 * kFrames;
    for (int i = kFrames; i < kPlayed; ++i)
        fs::copy_file(dir_ / "in" / fmt::format("frame_{:04d}.png", i % kFrames),
                      dir_ / "in" / fmt::format("frame_{:04d}.png", i));
    const fs::path stats = dir_ / "stats.json";
    // 1000 frames a second: every frame but the newest is dropped while one renders.
    const CliResult r = run("live " + quote(liveScene().string()) + " --camera " + quote(camera) +
                            " --realtime --fps 1000 --json " + quote(stats.string()) + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const json s = json::parse(readText(stats));
    EXPECT_GT(s["summary"]["dropped"].get<int>(), 0);
    EXPECT_EQ(s["summary"]["frames"].get<int>() + s["summary"]["dropped"].get<int>(), kPlayed);
}

TEST_F(LiveTest, RefusesWhatItCannotRun) {
    const std::string camera = writeCapture();
    CliResult r = run("live " + quote(liveScene().string()) + " --camera " + quote(camera));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("nothing to write"), std::string::npos) << r.err;
    r = run("live " + quote(liveScene().string()) + " --camera " + quote(camera) + " --light-camera " +
            quote(camera) + " --json " + quote((dir_ / "s.json").string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("environment: missing: the light camera's frames become the environment"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    r = run("live " + quote(liveScene().string()) + " --camera " + quote((dir_ / "none_####.png").string()) +
            " --json " + quote((dir_ / "s.json").string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("no frame: neither"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "s.json"));
    // Light-camera frames that the scene's projection cannot take: an equirectangular map must be 2:1.
    fs::create_directories(dir_ / "light");
    writeImage(Image(32, 16, 3, 0.5f), dir_ / "light" / "frame_0000.png");
    for (int i = 0; i < 2; ++i)
        writeImage(Image(24, 24, 3, 0.5f), dir_ / "light" / fmt::format("frame_{:04d}.png", i));
    writeImage(Image(32, 16, 3, 0.5f), dir_ / "sky.png");
    json withSky = json::parse(readText(liveScene()));
    withSky["environment"] = {{"file", (dir_ / "sky.png").string()}};
    r = run("live " + quote(writeScene(withSky, "sky.json").string()) + " --camera " + quote(camera) +
            " --light-camera " + quote((dir_ / "light" / "frame_####.png").string()) + " --json " +
            quote((dir_ / "s.json").string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find(
                  "light/frame_####.png: expected an equirectangular image twice as wide as high, got 24x24"),
              std::string::npos)
        << r.err;
    // A frame of another size in the middle: the frames before it are written whole, then one line.
    writeImage(Image(80, 60, 3, 0.5f), dir_ / "in" / "frame_0003.png");
    r = run("live " + quote(liveScene().string()) + " --camera " + quote(camera) + " -o " +
            quote((dir_ / "out" / "frame_####.png").string()) + " -q");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("frame_0003.png: the frames changed size: 80x60, the first was 160x120"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    EXPECT_EQ(readImage(dir_ / "out" / "frame_0002.png").width(), kWidth);
    EXPECT_FALSE(fs::exists(dir_ / "out" / "frame_0003.png"));
    EXPECT_TRUE(temporaries().empty());
}

// `live --serve` refuses what it cannot run before it listens, and a camera that fails mid-run (a frame of
// another size, as a device that changes mode) ends it with one line naming the source and exit 1.
TEST_F(LiveTest, ServeRefusesWhatItCannotRun) {
    const std::string camera = writeCapture();
    const std::string live = "live " + quote(liveScene().string()) + " --camera " + quote(camera);
    CliResult r = run(live + " --serve --port 0 -o " + quote((dir_ / "f_####.png").string()));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("--serve shows the frames in the browser"), std::string::npos) << r.err;
    r = run(live + " --port 0 --json " + quote((dir_ / "s.json").string()));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.err.find("--port requires --serve"), std::string::npos) << r.err;
    json unmarked = json::parse(readText(liveScene()));
    unmarked.erase("markers");
    r = run("live " + quote(writeScene(unmarked, "unmarked.json").string()) + " --camera " + quote(camera) +
            " --serve --port 0");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("markers: the scene places no marker"), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("http://"), std::string::npos) << "listened: " << r.out;
    writeImage(Image(80, 60, 3, 0.5f), dir_ / "in" / "frame_0003.png");
    r = run(live + " --serve --port 0");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.err.find("frame_0003.png: the frames changed size: 80x60, the first was 160x120"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
}

}  // namespace
}  // namespace deltagi::test
