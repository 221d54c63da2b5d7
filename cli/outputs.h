// The CLI's outputs: checked before any work (not one of the run's inputs, a folder that takes files),
// written atomically (io/atomic_file.h), and cleaned up when SIGINT or SIGTERM stops the run.
#pragma once

#include <cmath>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/image.h"
#include "deltagi/renderer.h"
#include "deltagi/scene.h"
#include "io/atomic_file.h"

namespace deltagi::cli {

// Exit statuses: 0 done, 1 bad input or an output that cannot be written, 2 a command-line usage error,
// 128 + the signal (130 SIGINT, 143 SIGTERM) when interrupted.
constexpr int kExitInputError = 1;
constexpr int kExitUsageError = 2;
constexpr int kExitSignalBase = 128;

// SIGINT and SIGTERM (unless ignored when the run started): remove this run's temporary files and the output
// folders it created that are still empty, print one line, exit 128 + signal. No output is left half written;
// with OutputFiles, none is replaced unless the signal comes during the renames. For tests,
// DELTAGI_TEST_SIGNAL_BEFORE_RENAME=N raises signal N when an output is complete but not yet renamed into
// place.
void installInterruptHandlers();

// A file the run reads, and what it is to the run ("the scene file").
struct RunInput {
    std::filesystem::path path;
    std::string what;
};

// The scene file and every file it names that the loader read: background photo, environment map, meshes,
// and a sequence's transforms file and every frame's photo.
std::vector<RunInput> sceneInputs(const Scene& scene);

// Throws InputError "OUT: is an input of this run (WHAT); choose another output" when an output is one of the
// inputs (the same file, by any path or link).
void refuseInputs(const std::vector<std::filesystem::path>& outputs, const std::vector<RunInput>& inputs);

// refuseInputs, then checkWritable for each output: before the work, so that a bad path costs nothing.
void checkOutputs(const std::vector<std::filesystem::path>& outputs, const std::vector<RunInput>& inputs);

// Writes JSON (2-space indent) atomically; the folder must exist.
void writeJson(const nlohmann::ordered_json& json, const std::filesystem::path& path);

// Each stage's milliseconds in pipeline order, a stage run more than once (per light, say) summed; with a
// `scale`, rounded to 1 / scale.
nlohmann::ordered_json stageTimesJson(const RenderOutput& output, double scale = 0.0);

// A figure for a JSON output, rounded to 1 / scale (1e3: timings in ms to the microsecond).
inline double rounded(double value, double scale) {
    return std::round(value * scale) / scale;
}

// A file name with the place of a frame's number: a run of '#' (frame_####.png) or a printf-style %d / %0Nd
// (frame_%04d.png), replaced by the number, padded to its width (with zeros, or spaces for %Nd). Throws
// InputError naming the pattern when it has neither.
struct FramePattern {
    std::string prefix, suffix;  // around the number
    int width = 0;
    bool zeros = true;
    std::filesystem::path path(int index) const;
};
FramePattern parseFramePattern(const std::filesystem::path& pattern);
// parseFramePattern(pattern).path(index).
std::filesystem::path framePath(const std::filesystem::path& pattern, int index);

// A run's outputs, each written whole to its temporary as it comes, all renamed into place by commit(): a
// failure or a signal before then replaces none of them (the temporaries go, the previous files stay).
// Folders are created when their first file is written.
class OutputFiles {
  public:
    void image(const Image& image, const std::filesystem::path& path);
    void layers(std::span<const ImageLayer> layers, const std::filesystem::path& path);
    void json(const nlohmann::ordered_json& json, const std::filesystem::path& path);
    void bytes(std::string_view bytes, const std::filesystem::path& path);
    void commit();

  private:
    AtomicFile& add(const std::filesystem::path& path);
    std::vector<std::unique_ptr<AtomicFile>> files_;
};

}  // namespace deltagi::cli
