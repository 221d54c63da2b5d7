#include "messages.h"

#include "deltagi/error.h"
#include "deltagi/scene_io.h"

namespace deltagi::cli {

namespace {

constexpr size_t kMaxMessageChars = 1000;

}  // namespace

std::string oneLine(const std::string& message) {
    std::string out;
    bool lineBreak = false;
    for (char c : message) {
        if (c == '\n' || c == '\r') {
            lineBreak = !out.empty();
            continue;
        }
        if (lineBreak) out += "; ";
        lineBreak = false;
        out += c;
    }
    if (out.size() > kMaxMessageChars) out = out.substr(0, kMaxMessageChars - 3) + "...";
    return out;
}

Scene loadAndWarn(const std::filesystem::path& file, const std::vector<std::string>& overrides,
                  const std::string& frames, const std::string& framesOption) {
    nlohmann::json document = readSceneDocument(file, overrides);
    if (!frames.empty()) {
        parseFrameRange(frames, framesOption);
        auto sequence = document.is_object() ? document.find("sequence") : document.end();
        if (!document.is_object() || sequence == document.end())
            throw InputError(framesOption, "the scene has no \"sequence\" to take frames from");
        if (sequence->is_object()) (*sequence)["frames"] = frames;  // anything else fails as the scene's own
    }
    Scene scene = loadScene(document, file);
    for (const std::string& warning : scene.warnings) note("deltagi: warning: {}\n", oneLine(warning));
    return scene;
}

void noteFirstFrame(const Scene& scene, const char* command) {
    if (scene.sequence.empty()) return;
    const int index = scene.sequence.front().index;
    note(
        "deltagi: {} takes one image: the sequence's first frame, frame {} of {} "
        "(--set sequence.frames={}:{} picks frame {})\n",
        command, index, scene.sequenceFile.string(), index + 1, index + 2, index + 1);
}

std::string plural(size_t count, const char* one, const char* many) {
    return fmt::format("{} {}", count, count == 1 ? one : many);
}

}  // namespace deltagi::cli
