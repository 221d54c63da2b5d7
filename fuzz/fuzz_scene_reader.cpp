// libFuzzer target: the scene reader, from the JSON text to a Scene (parseJson + loadScene), as `deltagi
// info` reads a scene file. Bad input must end in InputError; anything else (a crash, a sanitizer finding,
// another exception) is a finding. Mesh and image files named by an input are looked up in an empty folder,
// so the reader itself is what runs.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "scene/json_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::filesystem::path kScene = [] {
        std::filesystem::path folder =
            std::filesystem::temp_directory_path() / ("deltagi-fuzz-scene-" + std::to_string(::getpid()));
        std::filesystem::create_directories(folder);
        return folder / "scene.json";
    }();
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const nlohmann::json document = deltagi::parseJson(text, kScene.string());
        (void)deltagi::loadScene(document, kScene);
    } catch (const deltagi::InputError&) {
        // the expected outcome of bad input
    }
    return 0;
}
