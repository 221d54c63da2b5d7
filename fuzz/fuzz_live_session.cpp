// libFuzzer target: the live session's message handler (src/live/live_session.h), as `deltagi serve` calls it
// for each WebSocket message (raw bytes; those starting with 0xFF also as a camera frame's JPEG). Every input
// must end in a reply or a change; an exception that escapes handle(), a crash or a sanitizer finding is a
// finding. The session is the tiny scene of tests/test_scene_json.h, written once to a temporary folder;
// after each message the scene must still be one the renderer takes.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>

#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "live/live_session.h"

namespace {

const char* kScene = R"({
  "camera": {"width": 64, "height": 48, "fov_y_deg": 45, "position": [0, 0.8, 2], "look_at": [0, 0.1, 0]},
  "scene": [{"name": "floor", "shape": {"type": "triangles",
             "positions": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], "indices": [[0, 2, 1], [0, 3, 2]]},
             "material": {"albedo": [0.7, 0.7, 0.7]}}],
  "virtual": [{"name": "box", "shape": {"type": "box", "size": [0.3, 0.3, 0.3]},
               "transform": {"translate": [0, 0.15, 0]}},
              {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "transform": {"translate": [0.4, 0.1, 0]}}],
  "lights": [{"type": "point", "position": [0.5, 1.5, 0.5], "intensity": 3},
             {"type": "directional", "direction": [0, -1, 0.2], "intensity": 1}],
  "options": {"volume": {"resolution": 16}, "rsm": {"resolution": 64}}
})";

deltagi::live::Session& session() {
    static std::unique_ptr<deltagi::live::Session> s = [] {
        const std::filesystem::path folder =
            std::filesystem::temp_directory_path() / ("deltagi-fuzz-live-" + std::to_string(::getpid()));
        std::filesystem::create_directories(folder);
        std::ofstream(folder / "scene.json") << kScene;
        return std::make_unique<deltagi::live::Session>(folder / "scene.json", std::vector<std::string>{});
    }();
    return *s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    // A binary message: a camera frame (a JPEG of the camera's size), decoded or refused with InputError.
    if (size > 0 && data[0] == 0xFF) {
        try {
            (void)deltagi::live::decodeCameraFrame(
                std::string_view(reinterpret_cast<const char*>(data), size), 64, 48);
        } catch (const deltagi::InputError&) {
        }
    }
    deltagi::live::Session& s = session();
    const deltagi::live::MessageResult result =
        s.handle(std::string_view(reinterpret_cast<const char*>(data), size), 1);
    if (!result.changed && !result.reply.is_object()) std::abort();  // neither a reply nor a change
    deltagi::checkFrame(s.scene());  // throws (a finding) if a message left a scene the renderer refuses
    // What the server sends: text that is not UTF-8 in a message must not make these throw.
    (void)deltagi::live::jsonText(result.reply);
    (void)deltagi::live::jsonText(s.state());
    (void)deltagi::live::jsonText(s.document(), 2);
    return 0;
}
