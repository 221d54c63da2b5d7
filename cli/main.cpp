// The `deltagi` command: `render` a scene file to an image (and its AOVs), or print `info` about a scene.
//
// Errors: bad input (InputError) and any other exception become one line `deltagi: error: <message>` on
// stderr and exit code 1; command-line usage errors exit with code 2.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <fmt/core.h>
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_info.h"
#include "deltagi/scene_io.h"

namespace fs = std::filesystem;
using namespace deltagi;

namespace {

constexpr int kExitInputError = 1;
constexpr int kExitUsageError = 2;
constexpr int kMaxThreads = 4096;  // a sanity bound for --threads, far above any machine this runs on

struct RenderArgs {
    fs::path scene;
    fs::path output;
    fs::path aovDir;
    std::vector<std::string> overrides;
    int threads = 0;  // 0: not given, TBB's default (all cores)
    bool quiet = false;
};

struct InfoArgs {
    fs::path scene;
    std::vector<std::string> overrides;
    bool json = false;
};

// Progress and errors go to stderr; stdout holds only what `info` was asked for.
template <typename... Args>
void note(fmt::format_string<Args...> format, Args&&... args) {
    fmt::print(stderr, format, std::forward<Args>(args)...);
    std::fflush(stderr);
}

// One line, whatever the message holds: the lines of a multi-line message are joined with "; ".
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
    return out;
}

int reportError(const std::string& message, int exitCode) {
    note("deltagi: error: {}\n", oneLine(message));
    return exitCode;
}

std::string plural(size_t count, const char* one, const char* many) {
    return fmt::format("{} {}", count, count == 1 ? one : many);
}

std::string lowerExtension(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

// Checked before rendering, so that a typo does not cost a whole render.
void checkOutputPath(const fs::path& output) {
    const std::string ext = lowerExtension(output);
    if (ext != ".png" && ext != ".exr" && ext != ".hdr") {
        const std::string found = ext.empty() ? "no file extension" : "unknown image type '" + ext + "'";
        throw InputError(output.string(), found + ": expected .png (8-bit sRGB), .exr or .hdr (linear)");
    }
    if (fs::is_directory(output))
        throw InputError(output.string(), "is a folder, expected an image file name");
}

void createFolder(const fs::path& folder) {
    if (folder.empty()) return;
    std::error_code error;
    fs::create_directories(folder, error);
    if (error) throw InputError(folder.string(), "cannot create folder: " + error.message());
}

void writeJson(const nlohmann::ordered_json& json, const fs::path& path) {
    std::ofstream out(path);
    out << json.dump(2) << '\n';
    if (!out) throw InputError(path.string(), "cannot write file");
}

// timings.json: the stages in pipeline order (a stage run more than once, e.g. per light, is summed); the
// scene loading is not a pipeline stage and is reported beside them.
nlohmann::ordered_json timingsJson(const RenderOutput& output, const Scene& scene, int threads,
                                   double loadMs) {
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (const StageTiming& stage : output.timings)
        stages[stage.name] = stages.value(stage.name, 0.0) + stage.ms;
    nlohmann::ordered_json json;
    json["stages"] = std::move(stages);
    json["total_ms"] = output.totalMs;
    json["load_ms"] = loadMs;
    json["threads"] = threads;
    json["width"] = scene.camera.width;
    json["height"] = scene.camera.height;
    json["volume_resolution"] = volumeRegion(scene).resolution;
    return json;
}

void writeAovs(const RenderOutput& output, const Scene& scene, int threads, double loadMs,
               const fs::path& folder) {
    writeImage(output.background, folder / "background.exr");
    writeImage(output.composite, folder / "composite.exr");
    writeImage(output.objectMask, folder / "object_mask.exr");
    writeImage(output.delta, folder / "delta.exr");
    writeJson(timingsJson(output, scene, threads, loadMs), folder / "timings.json");
}

int runRender(const RenderArgs& args) {
    // Limits TBB for as long as it lives, i.e. for the whole render.
    std::optional<tbb::global_control> threadLimit;
    if (args.threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, args.threads);
    const int threads =
        static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

    // On a terminal, one line per step as it finishes; in a log, only the summary.
    const bool progress = !args.quiet && isatty(STDERR_FILENO);
    auto printStep = [](const std::string& name, double ms) { note("  {:<12} {:>9.1f} ms\n", name, ms); };

    // Bad paths fail before the render, not after it.
    checkOutputPath(args.output);
    createFolder(args.output.parent_path());
    if (!args.aovDir.empty()) createFolder(args.aovDir);

    const auto loadStart = std::chrono::steady_clock::now();
    const Scene scene = loadScene(args.scene, args.overrides);
    const double loadMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - loadStart).count();
    if (progress) printStep("load", loadMs);

    StageCallback onStage;
    if (progress) onStage = [&](const StageTiming& stage) { printStep(stage.name, stage.ms); };
    const RenderOutput output = render(scene, onStage);

    writeImage(output.composite, args.output);
    if (!args.aovDir.empty()) writeAovs(output, scene, threads, loadMs, args.aovDir);

    if (progress) printStep("total", output.totalMs);
    if (!args.quiet) {
        note("deltagi: wrote {} ({}x{}, {:.1f} ms, {}){}\n", args.output.string(), scene.camera.width,
             scene.camera.height, output.totalMs, plural(threads, "thread", "threads"),
             args.aovDir.empty() ? "" : fmt::format(", AOVs in {}", args.aovDir.string()));
    }
    return 0;
}

std::string formatVec(glm::vec3 v) {
    return fmt::format("({:.4g}, {:.4g}, {:.4g})", v.x, v.y, v.z);
}

std::string formatBounds(const Bounds3f& bounds) {
    if (bounds.empty()) return "empty";
    return fmt::format("{} - {}, size {}", formatVec(bounds.min), formatVec(bounds.max),
                       formatVec(bounds.diagonal()));
}

std::string formatBytes(size_t bytes) {
    constexpr double kMiB = 1024.0 * 1024.0;
    return fmt::format("{:.1f} MiB", static_cast<double>(bytes) / kMiB);
}

// A value of the options for the table: floats with the digits a float has ("0.98", not
// "0.9800000190734863").
std::string formatOptionValue(const nlohmann::json& value) {
    if (value.is_number_float()) return fmt::format("{:.6g}", value.get<double>());
    if (value.is_null()) return "(not set)";
    if (!value.is_array()) return value.dump();
    std::string items;
    for (const nlohmann::json& item : value) items += (items.empty() ? "" : ", ") + formatOptionValue(item);
    return "[" + items + "]";
}

// Options as "volume.resolution  128", one per line, in the order optionsToJson gives them.
void printOptions(const nlohmann::json& json, const std::string& prefix) {
    for (const auto& [key, value] : json.items()) {
        const std::string name = prefix.empty() ? key : prefix + "." + key;
        if (value.is_object())
            printOptions(value, name);
        else
            fmt::print("  {:<30} {}\n", name, formatOptionValue(value));
    }
}

void printInfoTable(const Scene& scene, const SceneInfo& info) {
    const VolumeRegion& region = info.region;
    fmt::print("{:<16} {}\n", "scene", scene.file.string());
    fmt::print("{:<16} {}x{}\n", "camera", scene.camera.width, scene.camera.height);
    fmt::print("{:<16} {} real ({}), {} virtual ({})\n", "triangles", info.realTriangles,
               plural(info.realMeshes, "mesh", "meshes"), info.virtualTriangles,
               plural(info.virtualMeshes, "mesh", "meshes"));
    fmt::print("{:<16} {}\n", "lights", info.lights);
    fmt::print("{:<16} {}\n", "real bounds", formatBounds(info.realBounds));
    fmt::print("{:<16} {}\n", "virtual bounds", formatBounds(info.virtualBounds));
    fmt::print("{:<16} origin {}, size {:.4g}\n", "volume region", formatVec(region.origin), region.size);
    fmt::print("{:<16} {}^3, voxel size {:.4g}, {} mip levels\n", "resolution", region.resolution,
               region.voxelSize(), info.mipLevels);
    fmt::print("{:<16} {} per volume, {} for all four\n", "memory", formatBytes(info.bytesPerVolume),
               formatBytes(info.bytesAllVolumes));
    fmt::print("options\n");
    printOptions(optionsToJson(scene.options), "");
}

int runInfo(const InfoArgs& args) {
    const Scene scene = loadScene(args.scene, args.overrides);
    const SceneInfo info = sceneInfo(scene);
    if (args.json) {
        nlohmann::json json = toJson(info);
        json["scene"] = scene.file.string();
        json["camera"] = {{"width", scene.camera.width}, {"height", scene.camera.height}};
        json["options"] = optionsToJson(scene.options);
        fmt::print("{}\n", json.dump(2));
    } else {
        printInfoTable(scene, info);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "deltagi: Delta Global Illumination, virtual objects in real images (voxel cone tracing + "
        "differential rendering)"};
    app.require_subcommand(1);

    RenderArgs renderArgs;
    CLI::App* renderCommand = app.add_subcommand("render", "Render a scene file to an image");
    renderCommand->add_option("scene", renderArgs.scene, "Scene file (JSON, see docs/scene-format.md)")
        ->required();
    renderCommand
        ->add_option("-o,--output", renderArgs.output,
                     "Output image: .png (8-bit sRGB), .exr or .hdr (linear)")
        ->required();
    renderCommand->add_option(
        "--aov", renderArgs.aovDir,
        "Also write background, composite, object_mask, delta (.exr) and timings.json here");
    renderCommand->add_option("--set", renderArgs.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    renderCommand->add_option("--threads", renderArgs.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, kMaxThreads));
    renderCommand->add_flag("-q,--quiet", renderArgs.quiet, "Print nothing but errors");

    InfoArgs infoArgs;
    CLI::App* infoCommand =
        app.add_subcommand("info", "Print a scene's size, volume region and effective options");
    infoCommand->add_option("scene", infoArgs.scene, "Scene file (JSON)")->required();
    infoCommand->add_option("--set", infoArgs.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    infoCommand->add_flag("--json", infoArgs.json, "Print JSON on stdout instead of a table");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        if (error.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))
            return app.exit(error);  // --help
        if (app.get_subcommands().empty() && argc > 1 && argv[1][0] != '-')
            return reportError(
                fmt::format("unknown command '{}': expected 'render' or 'info' (see deltagi --help)",
                            argv[1]),
                kExitUsageError);
        return reportError(fmt::format("{} (see deltagi --help)", error.what()), kExitUsageError);
    }

    try {
        return *renderCommand ? runRender(renderArgs) : runInfo(infoArgs);
    } catch (const std::exception& error) {  // InputError and everything else: one line
        return reportError(error.what(), kExitInputError);
    } catch (...) {
        return reportError("unexpected error", kExitInputError);
    }
}
