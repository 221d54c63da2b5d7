#include "outputs.h"

#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <regex>
#include <system_error>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "io/atomic_file.h"
#include "io/image_output.h"

namespace fs = std::filesystem;

namespace deltagi::cli {

namespace {

volatile std::sig_atomic_t gTestSignal = 0;  // DELTAGI_TEST_SIGNAL_BEFORE_RENAME

// Async-signal-safe only: unlink, rmdir, write, _exit.
void onInterrupt(int signal) {
    removeTemporaryOutputs();
    const char* message =
        signal == SIGINT ? "deltagi: interrupted (SIGINT)\n" : "deltagi: interrupted (SIGTERM)\n";
    [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, message, std::strlen(message));
    ::_exit(kExitSignalBase + signal);
}

void raiseTestSignal(const char*) {
    std::raise(gTestSignal);
}

}  // namespace

void installInterruptHandlers() {
    struct sigaction action {};
    action.sa_handler = onInterrupt;
    sigemptyset(&action.sa_mask);
    sigaddset(&action.sa_mask, SIGINT);  // one handler at a time in a thread
    sigaddset(&action.sa_mask, SIGTERM);
    for (int signal : {SIGINT, SIGTERM}) {
        struct sigaction previous {};
        sigaction(signal, nullptr, &previous);
        // A signal ignored by whoever started the run stays ignored (SIGINT of a shell's background job).
        if (previous.sa_handler != SIG_IGN) sigaction(signal, &action, nullptr);
    }
    if (const char* value = std::getenv("DELTAGI_TEST_SIGNAL_BEFORE_RENAME")) {
        gTestSignal = std::atoi(value);
        if (gTestSignal > 0) testing::setBeforeRenameHook(raiseTestSignal);
    }
}

std::vector<RunInput> sceneInputs(const Scene& scene) {
    std::vector<RunInput> inputs{{scene.file, "the scene file"}};
    if (!scene.backgroundFile.empty()) inputs.push_back({scene.backgroundFile, "the background photo"});
    if (scene.environment) inputs.push_back({scene.environment->file, "the environment map"});
    for (const fs::path& mesh : scene.meshFiles) inputs.push_back({mesh, "a mesh file of the scene"});
    // A sequence: the transforms file and every frame's photo, not only the first frame's.
    if (!scene.sequence.empty()) inputs.push_back({scene.sequenceFile, "the sequence's transforms file"});
    for (const SequenceFrame& frame : scene.sequence)
        if (!frame.photo.empty())
            inputs.push_back({frame.photo, fmt::format("the photo of frame {}", frame.index)});
    return inputs;
}

void refuseInputs(const std::vector<fs::path>& outputs, const std::vector<RunInput>& inputs) {
    for (const fs::path& output : outputs)
        for (const RunInput& input : inputs) {
            std::error_code error;  // false when either does not exist: a new file is no input
            if (fs::equivalent(output, input.path, error))
                throw InputError(output.string(),
                                 "is an input of this run (" + input.what + "); choose another output");
        }
}

// Two outputs of one run that are one file (`-o X --layers X`, `-o D/background.exr --aov D`, one pattern
// twice): one would overwrite the other.
void refuseDuplicates(const std::vector<fs::path>& outputs) {
    std::vector<fs::path> seen;
    for (const fs::path& output : outputs) {
        std::error_code error;
        fs::path key = fs::weakly_canonical(fs::absolute(output, error), error);
        if (error) key = fs::absolute(output).lexically_normal();
        for (size_t i = 0; i < seen.size(); ++i)
            if (seen[i] == key)
                throw InputError(
                    output.string(),
                    fmt::format("is given twice as an output of this run (also as '{}'): one would "
                                "overwrite the other",
                                outputs[i].string()));
        seen.push_back(std::move(key));
    }
}

void checkOutputs(const std::vector<fs::path>& outputs, const std::vector<RunInput>& inputs) {
    refuseDuplicates(outputs);
    refuseInputs(outputs, inputs);
    for (const fs::path& output : outputs) checkWritable(output);
}

void writeJson(const nlohmann::ordered_json& json, const fs::path& path) {
    writeFileAtomically(path, json.dump(2) + '\n');
}

FramePattern parseFramePattern(const fs::path& pattern) {
    const std::string text = pattern.string();
    const size_t hash = text.find('#');
    if (hash != std::string::npos) {
        size_t end = hash;
        while (end < text.size() && text[end] == '#') ++end;
        return {text.substr(0, hash), text.substr(end), static_cast<int>(end - hash), true};
    }
    static const std::regex printfNumber("%(0?)([0-9]?)d");
    std::smatch match;
    if (std::regex_search(text, match, printfNumber))
        return {match.prefix().str(), match.suffix().str(),
                match[2].length() > 0 ? std::stoi(match[2].str()) : 0, match[1].length() > 0};
    throw InputError(text,
                     "a sequence writes one file per frame: give the frame number's place, "
                     "e.g. frame_####.png or frame_%04d.png");
}

fs::path FramePattern::path(int index) const {
    return prefix + (zeros ? fmt::format("{:0{}d}", index, width) : fmt::format("{:{}d}", index, width)) +
           suffix;
}

fs::path framePath(const fs::path& pattern, int index) {
    return parseFramePattern(pattern).path(index);
}

AtomicFile& OutputFiles::add(const fs::path& path) {
    createOutputFolder(path.parent_path());
    files_.push_back(std::make_unique<AtomicFile>(path));
    return *files_.back();
}

void OutputFiles::image(const Image& image, const fs::path& path) {
    writeImage(image, add(path));
}

void OutputFiles::layers(std::span<const ImageLayer> layers, const fs::path& path) {
    writeLayers(layers, add(path));
}

void OutputFiles::json(const nlohmann::ordered_json& json, const fs::path& path) {
    AtomicFile& file = add(path);
    file.write(json.dump(2) + '\n');
    file.close();
}

void OutputFiles::bytes(std::string_view bytes, const fs::path& path) {
    AtomicFile& file = add(path);
    file.write(bytes);
    file.close();
}

void OutputFiles::commit() {
    for (const std::unique_ptr<AtomicFile>& file : files_) file->commit();
    files_.clear();
}

nlohmann::ordered_json stageTimesJson(const RenderOutput& output, double scale) {
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (const StageTiming& stage : output.timings)
        stages[stage.name] = stages.value(stage.name, 0.0) + stage.ms;
    if (scale > 0.0)
        for (auto& ms : stages) ms = rounded(ms.get<double>(), scale);
    return stages;
}

}  // namespace deltagi::cli
