#include "albedo_command.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <optional>
#include <stdexcept>

#include <fmt/core.h>
#include <tbb/global_control.h>
#include <nlohmann/json.hpp>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "io/ply_writer.h"
#include "messages.h"
#include "outputs.h"

namespace fs = std::filesystem;
using nlohmann::ordered_json;

namespace deltagi::cli {

namespace {

// Figures in the written scene file: 4 decimals, more than an 8-bit photo holds.
ordered_json rgb(glm::vec3 v) {
    return ordered_json::array({rounded(v.x, 1e4), rounded(v.y, 1e4), rounded(v.z, 1e4)});
}

// The largest diffuse albedo a material allows (albedo + specular <= 1, which the scene reader checks).
glm::vec3 largestAlbedo(const Material& material) {
    if (material.model != MaterialModel::Phong) return glm::vec3(1.0f);
    return glm::clamp(glm::vec3(1.0f) - material.specular, glm::vec3(0.0f), glm::vec3(1.0f));
}

// A path the scene file gave relative to its own folder, as the written file must give it: relative to its
// folder (absolute paths stay as they are).
std::string rebase(const std::string& text, const fs::path& fromFolder, const fs::path& toFolder) {
    const fs::path path(text);
    if (path.is_absolute() || text.empty()) return text;
    const fs::path target = fs::weakly_canonical(fs::absolute(fromFolder / path));
    const fs::path relative = target.lexically_relative(fs::weakly_canonical(fs::absolute(toFolder)));
    return relative.empty() ? target.generic_string() : relative.generic_string();
}

void rebaseKey(ordered_json& object, const char* key, const fs::path& fromFolder, const fs::path& toFolder) {
    if (object.is_object() && object.contains(key) && object[key].is_string())
        object[key] = rebase(object[key].get<std::string>(), fromFolder, toFolder);
}

// Every file the scene names, for a scene file written into another folder.
void rebasePaths(ordered_json& document, const fs::path& fromFolder, const fs::path& toFolder) {
    rebaseKey(document, "background", fromFolder, toFolder);
    if (document.contains("environment")) rebaseKey(document["environment"], "file", fromFolder, toFolder);
    if (document.contains("sequence")) rebaseKey(document["sequence"], "transforms", fromFolder, toFolder);
    for (const char* list : {"scene", "virtual"})
        if (document.contains(list) && document[list].is_array())
            for (ordered_json& entry : document[list]) rebaseKey(entry, "file", fromFolder, toFolder);
}

// The scene document as loadScene() read it: the file, with the --set overrides applied (whose keys then come
// in sorted order).
ordered_json sceneDocument(const AlbedoArgs& args) {
    std::ifstream in(args.scene, std::ios::binary);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (args.overrides.empty()) return ordered_json::parse(text);
    nlohmann::json document = nlohmann::json::parse(text);
    for (const std::string& override : args.overrides) applyOverride(document, override);
    return ordered_json::parse(document.dump());
}

// The meshes of each entry of the scene file's "scene" list.
std::vector<std::vector<size_t>> meshesByEntry(const Scene& scene, size_t entries) {
    if (scene.realEntries.size() != scene.real.size())
        throw std::logic_error("estimate-albedo: the loader did not record the real meshes' entries");
    std::vector<std::vector<size_t>> result(entries);
    for (size_t m = 0; m < scene.real.size(); ++m)
        result.at(static_cast<size_t>(scene.realEntries[m])).push_back(m);
    return result;
}

// Per mesh: each entry's "material.albedo" becomes the estimate (an entry of several meshes, a file with
// sub-meshes, gets their pooled ratio); entries no lit pixel shows stay as they were.
void writePerMesh(ordered_json& list, const Scene& scene, const AlbedoEstimate& estimate) {
    const auto groups = meshesByEntry(scene, list.size());
    for (size_t e = 0; e < groups.size(); ++e) {
        glm::dvec3 reflected(0.0), irradiance(0.0);
        glm::vec3 largest(1.0f);
        size_t used = 0;
        for (size_t m : groups[e]) {
            const MeshAlbedo& a = estimate.meshes[m];
            if (a.pixelsUsed == 0) continue;
            reflected += a.reflectedSum;
            irradiance += a.irradianceSum;
            largest = glm::min(largest, largestAlbedo(scene.real[m].material));
            used += a.pixelsUsed;
        }
        if (used == 0) continue;
        glm::vec3 albedo = estimate.meshes[groups[e].front()].albedo;
        if (groups[e].size() > 1)
            for (int c = 0; c < 3; ++c)
                if (irradiance[c] > 0.0)
                    albedo[c] =
                        std::clamp(static_cast<float>(reflected[c] / irradiance[c]), 0.0f, largest[c]);
        ordered_json& entry = list[e];
        if (!entry.contains("material") || !entry["material"].is_object())
            entry["material"] = ordered_json::object();
        entry["material"]["albedo"] = rgb(albedo);
    }
}

// Per vertex: each mesh becomes an entry of its own whose "file" is its PLY (world-space positions, so no
// "transform"), the albedo in its vertex colours and the material's albedo the largest the material allows
// (1, less a specular reflectance), which the colours multiply; the material's other values are written out,
// as the PLY has none.
ordered_json writePerVertex(const ordered_json& list, const Scene& scene, const AlbedoEstimate& estimate,
                            const std::vector<fs::path>& plyFiles,
                            std::vector<std::vector<glm::vec3>>& colours) {
    const auto groups = meshesByEntry(scene, list.size());
    ordered_json result = ordered_json::array();
    colours.assign(scene.real.size(), {});
    for (size_t e = 0; e < groups.size(); ++e)
        for (size_t m : groups[e]) {
            const Material& material = scene.real[m].material;
            const glm::vec3 scale = largestAlbedo(material);
            for (glm::vec3 albedo : estimate.meshes[m].vertexAlbedo)
                colours[m].push_back(glm::clamp(glm::vec3(scale.x > 0.0f ? albedo.x / scale.x : 0.0f,
                                                          scale.y > 0.0f ? albedo.y / scale.y : 0.0f,
                                                          scale.z > 0.0f ? albedo.z / scale.z : 0.0f),
                                                glm::vec3(0.0f), glm::vec3(1.0f)));
            ordered_json entry = list[e];
            entry.erase("shape");
            entry.erase("transform");
            entry["file"] = plyFiles[m].filename().generic_string();
            if (groups[e].size() > 1 || !entry.contains("name")) entry["name"] = scene.real[m].name;
            ordered_json out = ordered_json::object();
            out["albedo"] = rgb(scale);
            if (material.specular != glm::vec3(0.0f)) {
                out["specular"] = rgb(material.specular);
                out["roughness"] = material.roughness;
            }
            if (material.emits())
                out["emission"] =
                    ordered_json::array({material.emission.x, material.emission.y, material.emission.z});
            entry["material"] = out;
            result.push_back(std::move(entry));
        }
    return result;
}

// OUT.json's PLY for real mesh `index`: OUT.<index>-<name>.ply, the name reduced to letters, digits, - and _.
fs::path plyPath(const fs::path& output, size_t index, const std::string& name) {
    std::string safe;
    for (char c : name.substr(0, 40))
        safe += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
    return output.parent_path() / fmt::format("{}.{}-{}.ply", output.stem().string(), index, safe);
}

void printTable(const Scene& scene, const AlbedoEstimate& estimate, bool perVertex) {
    fmt::print("{:<24} {:>8}  {:<26} {:>8}{}\n", "mesh", "pixels", "albedo (linear RGB)", "clamped",
               perVertex ? "  vertices seen / clamped" : "");
    for (size_t m = 0; m < estimate.meshes.size(); ++m) {
        const MeshAlbedo& a = estimate.meshes[m];
        const std::string albedo =
            a.pixelsUsed > 0 ? fmt::format("{:.3f} {:.3f} {:.3f}", a.albedo.x, a.albedo.y, a.albedo.z)
                             : "- (as given)";
        const std::string vertices = perVertex
                                         ? fmt::format("  {} of {} / {}", a.verticesSeen,
                                                       scene.real[m].positions.size(), a.verticesClamped)
                                         : "";
        fmt::print("{:<24} {:>8}  {:<26} {:>8}{}\n", a.name.substr(0, 24), a.pixelsUsed, albedo,
                   a.pixelsClamped, vertices);
    }
    std::string changes;
    for (float change : estimate.changePerIteration) changes += fmt::format(" {:.4f}", change);
    fmt::print("largest change of an albedo per pass:{}\n", changes);
}

}  // namespace

CLI::App* addAlbedoCommand(CLI::App& app, AlbedoArgs& args, int maxThreads) {
    CLI::App* command = app.add_subcommand(
        "estimate-albedo",
        "Estimate the real surfaces' diffuse albedo from the photo, albedo = pi * L / E with E path traced "
        "in "
        "the real scene and iterated for the interreflections (after Debevec 1998, §6), and write a copy of "
        "the scene with it. Starts from the scene's materials; specular parts are kept as given.");
    command->add_option("scene", args.scene, "Scene file (JSON) with a background photo and real meshes")
        ->required();
    command
        ->add_option(
            "-o,--output", args.output,
            "The scene file to write (.json), the real meshes' material albedo replaced by the "
            "estimate; paths in it resolve from its folder. With --per vertex, beside it one PLY per "
            "real mesh (world-space positions, normals, the albedo as sRGB uchar red green blue) "
            "that it refers to instead of the mesh, with material albedo 1")
        ->required();
    command->add_option("--per", args.per, "mesh: one albedo per real mesh (default); vertex: one per vertex")
        ->check(CLI::IsMember({"mesh", "vertex"}));
    command
        ->add_option("--iterations", args.options.iterations,
                     "Passes, each lighting the surfaces with the previous pass's albedos (default 4)")
        ->check(CLI::Range(1, 1000));
    command
        ->add_option("--spp", args.options.samplesPerPixel,
                     "Irradiance paths per pixel and pass (default 64)")
        ->check(CLI::Range(1, 1 << 20));
    command->add_option("--seed", args.options.seed, "Random seed (default 0)");
    command->add_option("--set", args.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    command->add_option("--threads", args.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, maxThreads));
    command->add_flag("-q,--quiet", args.quiet, "Print nothing but warnings and errors");
    return command;
}

int runAlbedo(const AlbedoArgs& args) {
    std::optional<tbb::global_control> threadLimit;
    if (args.threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, args.threads);
    if (args.output.extension() != ".json")
        throw InputError(args.output.string(), "expected a .json file for the scene to write");
    checkOutputs({args.output}, {{args.scene, "the scene file"}});
    const Scene scene = loadScene(args.scene, args.overrides);
    for (const std::string& warning : scene.warnings) fmt::print(stderr, "deltagi: warning: {}\n", warning);
    noteFirstFrame(scene, "estimate-albedo");
    AlbedoOptions options = args.options;
    const bool perVertex = args.per == "vertex";
    options.granularity = perVertex ? AlbedoGranularity::PerVertex : AlbedoGranularity::PerMesh;
    std::vector<fs::path> plyFiles, outputs{args.output};
    if (perVertex)
        for (size_t m = 0; m < scene.real.size(); ++m) {
            plyFiles.push_back(plyPath(args.output, m, scene.real[m].name));
            outputs.push_back(plyFiles.back());
        }
    checkOutputs(outputs, sceneInputs(scene));

    const AlbedoEstimate estimate = estimateAlbedo(scene, options);
    if (!args.quiet) printTable(scene, estimate, perVertex);
    std::fflush(stdout);
    for (const std::string& warning : estimate.warnings)
        fmt::print(stderr, "deltagi: warning: {}\n", warning);

    ordered_json document = sceneDocument(args);
    rebasePaths(document, fs::absolute(args.scene).parent_path(), fs::absolute(args.output).parent_path());
    OutputFiles files;
    if (perVertex) {
        std::vector<std::vector<glm::vec3>> colours;
        document["scene"] = writePerVertex(document["scene"], scene, estimate, plyFiles, colours);
        for (size_t m = 0; m < scene.real.size(); ++m)
            files.bytes(
                encodePly(scene.real[m], colours[m],
                          "deltagi estimate-albedo: red green blue = the diffuse albedo (sRGB), times "
                          "the material's"),
                plyFiles[m]);
    } else {
        writePerMesh(document["scene"], scene, estimate);
    }
    files.json(document, args.output);
    files.commit();
    return 0;
}

}  // namespace deltagi::cli
