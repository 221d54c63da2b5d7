#include "info_command.h"

#include <algorithm>
#include <fstream>
#include <iterator>

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "messages.h"
#include "scene/scene_info.h"

namespace deltagi::cli {

namespace {

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

std::string lensText(const LensDistortion& d) {
    switch (d.model) {
        case LensDistortion::Model::None:
            return "none";
        case LensDistortion::Model::OpenCV:
            return fmt::format("opencv (k1 {:.4g}, k2 {:.4g}, k3 {:.4g}, p1 {:.4g}, p2 {:.4g})", d.k1, d.k2,
                               d.k3, d.p1, d.p2);
        case LensDistortion::Model::Fisheye:
            return fmt::format("fisheye (k1 {:.4g}, k2 {:.4g}, k3 {:.4g}, k4 {:.4g})", d.k1, d.k2, d.k3,
                               d.k4);
    }
    return "?";
}

// A sequence's frames, file, rate, lenses and moving objects (nothing without a sequence).
nlohmann::json sequenceJson(const Scene& scene) {
    if (scene.sequence.empty()) return nullptr;
    const std::vector<SequenceFrame>& frames = scene.sequence;
    std::vector<std::string> lenses;  // the distinct lenses, in order of their first frame
    bool sizeVaries = false;
    for (const SequenceFrame& frame : frames) {
        const std::string lens = lensText(frame.camera.distortion);
        if (std::find(lenses.begin(), lenses.end(), lens) == lenses.end()) lenses.push_back(lens);
        sizeVaries = sizeVaries || frame.camera.width != frames.front().camera.width ||
                     frame.camera.height != frames.front().camera.height;
    }
    double path = 0.0;  // the camera's way from the first frame to the last
    for (size_t i = 1; i < frames.size(); ++i)
        path += glm::distance(frames[i].camera.position(), frames[i - 1].camera.position());
    return {{"transforms", scene.sequenceFile.string()},
            {"frames", frames.size()},
            {"range", fmt::format("{}:{}", frames.front().index, frames.back().index + 1)},
            {"fps", scene.frameRate},
            {"lens", lenses},
            {"sizes_vary", sizeVaries},
            {"camera_path", path},
            {"photos", !frames.front().photo.empty()},
            {"keyframed_objects", scene.animations.size()}};
}

void printInfoTable(const Scene& scene, const SceneInfo& info) {
    const VolumeRegion& region = info.region;
    fmt::print("{:<16} {}\n", "scene", scene.file.string());
    fmt::print("{:<16} {}x{}, lens {}{}\n", "camera", scene.camera.width, scene.camera.height,
               lensText(scene.camera.distortion), scene.sequence.empty() ? "" : " (the first frame's)");
    if (const nlohmann::json sequence = sequenceJson(scene); !sequence.is_null()) {
        fmt::print("{:<16} {} frames {} of {}, {:.4g} fps{}{}\n", "sequence",
                   sequence["frames"].get<size_t>(), sequence["range"].get<std::string>(),
                   sequence["transforms"].get<std::string>(), scene.frameRate,
                   sequence["sizes_vary"].get<bool>() ? ", frames of several sizes" : "",
                   sequence["photos"].get<bool>() ? "" : ", no photos (the real scene is rendered)");
        const auto lenses = sequence["lens"].get<std::vector<std::string>>();
        fmt::print("{:<16} the camera's path {:.4g} long, {} keyframed{}\n", "",
                   sequence["camera_path"].get<double>(),
                   plural(scene.animations.size(), "object", "objects"),
                   lenses.size() > 1 ? fmt::format("; lenses {}", fmt::join(lenses, " / ")) : "");
    }
    fmt::print("{:<16} {} real ({}), {} virtual ({})\n", "triangles", info.realTriangles,
               plural(info.realMeshes, "mesh", "meshes"), info.virtualTriangles,
               plural(info.virtualMeshes, "mesh", "meshes"));
    fmt::print("{:<16} {}\n", "lights", info.lights);
    fmt::print("{:<16} {}\n", "real bounds", formatBounds(info.realBounds));
    fmt::print("{:<16} {}\n", "virtual bounds", formatBounds(info.virtualBounds));
    fmt::print("{:<16} origin {}, size {:.4g}\n", "volume region", formatVec(region.origin), region.size);
    fmt::print("{:<16} {}^3, voxel size {:.4g}, {} mip levels\n", "resolution", region.resolution,
               region.voxelSize(), info.mipLevels);
    fmt::print("{:<16} {} per volume, {} for all five (the objects' two over their box: {})\n", "memory",
               formatBytes(info.bytesPerVolume), formatBytes(info.bytesAllVolumes),
               formatBytes(info.bytesObjectVolumes));
    fmt::print(
        "{:<16} about {} at its peak (the memory guard's estimate: volumes, shadow maps, images, meshes)\n",
        "render memory", formatBytes(info.renderBytes));
    fmt::print("options\n");
    printOptions(optionsToJson(scene.options), "");
}

}  // namespace

CLI::App* addInfoCommand(CLI::App& app, InfoArgs& args) {
    CLI::App* command =
        app.add_subcommand("info", "Print a scene's size, volume region and effective options");
    CLI::Option* scene = command->add_option("scene", args.scene, "Scene file (JSON)");
    CLI::Option* set =
        command->add_option("--set", args.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    CLI::Option* json = command->add_flag("--json", args.json, "Print JSON on stdout instead of a table");
    command
        ->add_option(
            "--options-markdown", args.optionsMarkdown,
            "Print the options tables of docs/scene-format.md, made from src/scene/option_table.cpp; "
            "given a markdown file, print it with its tables made anew (scripts/update-options-doc.sh)")
        ->expected(0, 1)
        ->excludes(scene)
        ->excludes(set)
        ->excludes(json);
    return command;
}

int runInfo(const InfoArgs& args) {
    if (args.optionsMarkdown) {
        const std::string& file = *args.optionsMarkdown;
        if (file.empty()) {
            fmt::print("{}", optionTablesMarkdown());
            return 0;
        }
        std::ifstream in(file, std::ios::binary);
        if (!in) throw InputError(file, "cannot open the markdown file");
        const std::string markdown{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
        fmt::print("{}", withOptionTables(markdown, file));
        return 0;
    }
    const Scene scene = loadAndWarn(args.scene, args.overrides);
    const SceneInfo info = sceneInfo(scene);
    if (args.json) {
        nlohmann::json json = toJson(info);
        json["scene"] = scene.file.string();
        json["camera"] = {{"width", scene.camera.width},
                          {"height", scene.camera.height},
                          {"lens", lensText(scene.camera.distortion)}};
        json["sequence"] = sequenceJson(scene);
        json["options"] = optionsToJson(scene.options);
        fmt::print("{}\n", json.dump(2));
    } else {
        printInfoTable(scene, info);
    }
    return 0;
}

}  // namespace deltagi::cli
