// The light camera (src/live/light_camera.h): each frame becomes the environment through the scene file's
// "environment", its projection's conversion made once for frames of one size and made again for another.
#include "live/light_camera.h"

#include <unistd.h>

#include <filesystem>

#include <gtest/gtest.h>

#include "scene/environment_io.h"
#include "scene/json_reader.h"
#include "test_files.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;

// A fish-eye frame whose pixels all differ (a gradient and a bright spot off its centre).
Image fisheyeFrame(int size, float spot) {
    Image frame(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float u = static_cast<float>(x) / static_cast<float>(size),
                        v = static_cast<float>(y) / static_cast<float>(size);
            const bool bright = std::abs(u - 0.3f) < 0.08f && std::abs(v - 0.6f) < 0.08f;
            frame.setRgb(x, y, {u, v, bright ? spot : 0.1f});
        }
    return frame;
}

// Each frame's environment is the one the scene loader would make of that image alone (a frame that is not
// later than the one before starts the time average afresh), whether the frames before had its size or
// another: the conversion kept from a frame of another size is not used.
TEST(LightCamera, EachFramesEnvironmentIsItsImagesThroughTheProjection) {
    const fs::path dir = fs::temp_directory_path() / ("deltagi_light_camera_" + std::to_string(getpid()));
    fs::create_directories(dir);
    const nlohmann::json environment = {{"file", "light.png"}, {"projection", "fisheye"}, {"intensity", 2}};
    test::writeText(dir / "scene.json", nlohmann::json{{"environment", environment}}.dump());
    LightCamera camera(dir / "scene.json", {});
    const JsonNode node(environment, "scene.json", "environment");
    int frame = 0;
    for (const auto [size, spot] :
         {std::pair{32, 5.0f}, std::pair{32, 9.0f}, std::pair{48, 5.0f}, std::pair{32, 7.0f}}) {
        const Image image = fisheyeFrame(size, spot);
        const Environment made = camera.environment(Image(image), 0.0, "frame");
        const Environment alone = environmentFromImage(node, Image(image), "frame");
        ASSERT_EQ(made.radiance.width(), alone.radiance.width()) << frame;
        ASSERT_EQ(made.radiance.height(), alone.radiance.height()) << frame;
        for (size_t i = 0; i < made.radiance.data().size(); ++i)
            ASSERT_EQ(made.radiance.data()[i], alone.radiance.data()[i])
                << "frame " << frame << " value " << i;
        ++frame;
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace deltagi
