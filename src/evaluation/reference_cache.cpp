// The quality suite's cache of path-traced references (src/evaluation/quality_suite.h): a folder per
// reference, keyed by what the path tracer reads, so that a suite re-renders only what changed.
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <optional>
#include <set>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "evaluation/quality_suite.h"

namespace deltagi {

namespace fs = std::filesystem;

namespace {

// The images an evaluation reads (evaluate(): composite, background, object mask); with and without are
// not kept: a 640x480 reference takes 8.6 MiB instead of 22.
constexpr const char* kCompositeFile = "composite.exr";
constexpr const char* kBackgroundFile = "background.exr";
constexpr const char* kObjectMaskFile = "object_mask.exr";
// Written last: a folder without it holds an interrupted render and is rendered again.
constexpr const char* kMetaFile = "reference.json";

// FNV-1a, 64 bits: a cache key, not a defence against crafted collisions.
class Hasher {
  public:
    void add(std::string_view bytes) {
        for (const char c : bytes) {
            hash_ ^= static_cast<unsigned char>(c);
            hash_ *= 0x100000001b3ull;
        }
        // The length ends each piece, so that ("ab", "c") and ("a", "bc") differ.
        const uint64_t size = bytes.size();
        for (int i = 0; i < 8; ++i) {
            hash_ ^= (size >> (8 * i)) & 0xffu;
            hash_ *= 0x100000001b3ull;
        }
    }
    std::string hex() const { return fmt::format("{:016x}", hash_); }

  private:
    uint64_t hash_ = 0xcbf29ce484222325ull;
};

std::string readBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path.string(), "cannot read file");
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The material libraries an OBJ file names ("mtllib a.mtl b.mtl"), relative to its folder.
std::vector<fs::path> objMaterialFiles(const fs::path& obj, const std::string& text) {
    std::vector<fs::path> files;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
        std::istringstream words(line);
        std::string keyword, name;
        if (!(words >> keyword) || keyword != "mtllib") continue;
        while (words >> name) files.push_back(obj.parent_path() / name);
    }
    return files;
}

// The files a mesh or material file reads besides itself, relative to its folder: an OBJ's MTL libraries,
// an MTL's texture maps (the last word of map_*, bump, norm, disp and refl lines: the options come first),
// a glTF's buffers and images (those not embedded as data: URIs).
std::vector<fs::path> dependentFiles(const fs::path& file, const std::string& text) {
    std::string extension = file.extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (extension == ".obj") return objMaterialFiles(file, text);
    std::vector<fs::path> files;
    if (extension == ".mtl") {
        std::istringstream lines(text);
        std::string line;
        while (std::getline(lines, line)) {
            std::istringstream words(line);
            std::string keyword, word, last;
            if (!(words >> keyword)) continue;
            std::string lower = keyword;
            for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            if (lower.rfind("map_", 0) != 0 && lower != "bump" && lower != "norm" && lower != "disp" &&
                lower != "refl")
                continue;
            while (words >> word) last = word;
            if (!last.empty()) files.push_back(file.parent_path() / last);
        }
    } else if (extension == ".gltf") {
        const nlohmann::json document = nlohmann::json::parse(text, nullptr, false);
        if (!document.is_object()) return files;
        for (const char* key : {"buffers", "images"}) {
            const auto list = document.find(key);
            if (list == document.end() || !list->is_array()) continue;
            for (const auto& item : *list) {
                if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
                const std::string uri = item["uri"].get<std::string>();
                if (uri.rfind("data:", 0) != 0) files.push_back(file.parent_path() / uri);
            }
        }
    }
    return files;
}

// Adds `path` (named `name`) and, recursively, the files it reads.
void hashFileAndDependencies(const fs::path& path, const std::string& name, Hasher& hasher,
                             std::set<fs::path>& seen) {
    const std::string bytes = readBytes(path);
    hasher.add(name);
    hasher.add(bytes);
    std::error_code error;
    for (const fs::path& dependency : dependentFiles(path, bytes))
        if (fs::is_regular_file(dependency, error) && seen.insert(dependency.lexically_normal()).second)
            hashFileAndDependencies(dependency, dependency.filename().string(), hasher, seen);
}

// Adds every file the document names: any string that is the path of a file relative to the scene's folder
// (meshes, photo, environment map, textures), and the files those read (dependentFiles).
void hashReferencedFiles(const nlohmann::json& value, const fs::path& folder, Hasher& hasher,
                         std::set<fs::path>& seen) {
    if (value.is_object() || value.is_array()) {
        for (const auto& item : value) hashReferencedFiles(item, folder, hasher, seen);
        return;
    }
    if (!value.is_string() || value.get<std::string>().empty()) return;
    const fs::path path = folder / value.get<std::string>();
    std::error_code error;
    if (!fs::is_regular_file(path, error) || !seen.insert(path.lexically_normal()).second) return;
    hashFileAndDependencies(path, value.get<std::string>(), hasher, seen);
}

// A reference's limited-bounce version: references whose paths roulette ends long before their bounce limit
// (the default 256) are the same in every version.
int limitedVersion(const ReferenceOptions& options) {
    return options.maxBounces < ReferenceOptions{}.maxBounces ? kLimitedReferenceCacheVersion : 1;
}

bool sameSettings(const nlohmann::json& meta, const ReferenceOptions& options) {
    return meta.value("version", -1) == kReferenceCacheVersion &&
           meta.value("limited_version", 1) == limitedVersion(options) &&
           meta.value("spp", -1) == options.samplesPerPixel &&
           meta.value("seed", uint64_t{0}) == options.seed &&
           meta.value("max_bounces", -1) == options.maxBounces &&
           meta.value("roulette_start_bounce", -1) == options.rouletteStartBounce;
}

// The cached reference in `folder`, or nothing when there is none with these settings (or it is damaged).
std::optional<ReferenceOutput> readCached(const fs::path& folder, const ReferenceOptions& options,
                                          const Camera& camera) {
    std::error_code error;
    if (!fs::is_regular_file(folder / kMetaFile, error)) return std::nullopt;
    try {
        const nlohmann::json meta = nlohmann::json::parse(readBytes(folder / kMetaFile));
        if (!sameSettings(meta, options)) return std::nullopt;
        ReferenceOutput out;
        out.composite = readImage(folder / kCompositeFile);
        out.background = readImage(folder / kBackgroundFile);
        out.objectMask = readImage(folder / kObjectMaskFile);
        for (const Image* image : {&out.composite, &out.background, &out.objectMask})
            if (image->width() != camera.width || image->height() != camera.height) return std::nullopt;
        out.delta = out.composite;
        for (size_t i = 0; i < out.delta.data().size(); ++i) out.delta.data()[i] -= out.background.data()[i];
        out.samplesPerPixel = options.samplesPerPixel;
        out.totalMs = meta.value("ms", 0.0);
        return out;
    } catch (const std::exception&) {
        return std::nullopt;  // damaged: rendered again
    }
}

void writeText(const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out) throw InputError(path.string(), "cannot write file");
}

}  // namespace

std::string referenceContentKey(const fs::path& sceneFile, const std::vector<std::string>& overrides) {
    nlohmann::json document;
    try {
        document = nlohmann::json::parse(readBytes(sceneFile));
    } catch (const nlohmann::json::exception& e) {
        throw InputError(sceneFile.string(), std::string("not valid JSON: ") + e.what());
    }
    for (const std::string& override : overrides) applyOverride(document, override);
    if (document.is_object()) {
        document.erase("options");
        document.erase("description");
    }
    Hasher hasher;
    hasher.add(fmt::format("deltagi reference cache {}", kReferenceCacheVersion));
    hasher.add(document.dump());  // nlohmann::json sorts object keys: the same content, the same text
    std::set<fs::path> seen;
    hashReferencedFiles(document, sceneFile.parent_path(), hasher, seen);
    return hasher.hex();
}

namespace {

// Removes the folder's record first: a render or a write cut short leaves no cache entry behind.
void prepareFolder(const fs::path& folder) {
    std::error_code error;
    fs::remove(folder / kMetaFile, error);
    fs::create_directories(folder, error);
    if (error) throw InputError(folder.string(), "cannot create folder: " + error.message());
}

// The sums a reference's images are made from (ReferenceSums), so that a render with more samples can go on
// from them: a header (magic, width, height, samples, values per pixel) and the values, native doubles.
constexpr const char* kSumsFile = "sums.bin";
constexpr char kSumsMagic[8] = {'d', 'g', 's', 'u', 'm', 's', '0', '1'};

void writeSums(const ReferenceSums& sums, const fs::path& path) {
    std::ofstream out(path, std::ios::binary);
    const int32_t header[4] = {sums.width, sums.height, sums.samples, ReferenceSums::kValuesPerPixel};
    out.write(kSumsMagic, sizeof kSumsMagic);
    out.write(reinterpret_cast<const char*>(header), sizeof header);
    out.write(reinterpret_cast<const char*>(sums.values.data()),
              static_cast<std::streamsize>(sums.values.size() * sizeof(double)));
    if (!out) throw InputError(path.string(), "cannot write file");
}

// The sums in `folder` if they are those of `samples` samples over the camera's image; else nothing.
std::optional<ReferenceSums> readSums(const fs::path& folder, int samples, const Camera& camera) {
    std::ifstream in(folder / kSumsFile, std::ios::binary);
    char magic[sizeof kSumsMagic];
    int32_t header[4];
    if (!in.read(magic, sizeof magic) || !std::equal(magic, magic + sizeof magic, kSumsMagic) ||
        !in.read(reinterpret_cast<char*>(header), sizeof header))
        return std::nullopt;
    ReferenceSums sums;
    sums.width = header[0];
    sums.height = header[1];
    sums.samples = header[2];
    if (header[3] != ReferenceSums::kValuesPerPixel || sums.samples != samples ||
        sums.width != camera.width || sums.height != camera.height)
        return std::nullopt;
    sums.values.resize(static_cast<size_t>(sums.width) * sums.height * ReferenceSums::kValuesPerPixel);
    if (!in.read(reinterpret_cast<char*>(sums.values.data()),
                 static_cast<std::streamsize>(sums.values.size() * sizeof(double))))
        return std::nullopt;
    return sums;
}

// `ms`: the time of all its samples (output.totalMs, plus an earlier render's when it went on from one).
// `checkpoint`: a render's checkpoint (ReferenceOptions::checkpointSeconds), removed when the render it
// was made for is stored.
void storeReference(const fs::path& folder, const Scene& scene, const ReferenceOptions& options,
                    const ReferenceOutput& output, double ms, bool checkpoint = false) {
    prepareFolder(folder);
    if (output.sums.samples == options.samplesPerPixel && output.sums.fits(scene.camera))
        writeSums(output.sums, folder / kSumsFile);
    writeImage(output.composite, folder / kCompositeFile);
    writeImage(output.background, folder / kBackgroundFile);
    writeImage(output.objectMask, folder / kObjectMaskFile);
    nlohmann::ordered_json meta;
    meta["version"] = kReferenceCacheVersion;
    meta["limited_version"] = limitedVersion(options);
    meta["scene"] = scene.file.string();
    meta["spp"] = options.samplesPerPixel;
    meta["seed"] = options.seed;
    meta["max_bounces"] = options.maxBounces;
    meta["roulette_start_bounce"] = options.rouletteStartBounce;
    meta["ms"] = ms;
    if (checkpoint) meta["checkpoint"] = true;
    writeText(folder / kMetaFile, meta.dump(2) + "\n");
}

// Whether `folder` holds a checkpoint (storeReference's `checkpoint`).
bool isCheckpoint(const fs::path& folder) {
    try {
        return nlohmann::json::parse(readBytes(folder / kMetaFile)).value("checkpoint", false);
    } catch (const std::exception&) {
        return false;
    }
}

}  // namespace

CachedReference cachedReference(const Scene& scene, const ReferenceOptions& options, const fs::path& folder,
                                const ReferenceProgress& onPass,
                                const std::vector<std::pair<int, fs::path>>& snapshots,
                                const std::vector<std::pair<int, fs::path>>& earlier,
                                const std::function<fs::path(int samples)>& checkpointFolder) {
    if (options.timeLimitSeconds > 0.0)
        throw InputError(folder.string(), "a cached reference cannot have a time limit");
    CachedReference cached;
    cached.folder = folder;
    if (std::optional<ReferenceOutput> out = readCached(folder, options, scene.camera)) {
        cached.output = std::move(*out);
        cached.hit = true;
        return cached;
    }
    // The snapshots not in the cache yet come from this render's first samples.
    ReferenceOptions settings = options;
    settings.snapshotSamples.clear();
    auto withSamples = [&options](int n) {
        ReferenceOptions o = options;
        o.samplesPerPixel = n;
        o.snapshotSamples.clear();
        return o;
    };
    std::vector<std::pair<int, fs::path>> wanted;
    for (const auto& [n, snapshotFolder] : snapshots) {
        if (n <= 0 || n >= options.samplesPerPixel ||
            readCached(snapshotFolder, withSamples(n), scene.camera))
            continue;
        wanted.emplace_back(n, snapshotFolder);
        settings.snapshotSamples.push_back(n);
    }
    // The earlier reference with the most samples that kept its sums, to go on from.
    std::optional<ReferenceSums> from;
    double earlierMs = 0.0;  // the time its samples took, which this reference's samples include
    for (const auto& [n, earlierFolder] : earlier) {
        if (n <= 0 || n >= options.samplesPerPixel || (from && from->samples >= n)) continue;
        // The sums first: most earlier folders (the fit's) have none, and their images are not read then.
        std::optional<ReferenceSums> sums = readSums(earlierFolder, n, scene.camera);
        if (!sums) continue;
        const std::optional<ReferenceOutput> earlierOutput =
            readCached(earlierFolder, withSamples(n), scene.camera);
        if (!earlierOutput) continue;
        from = std::move(sums);
        earlierMs = earlierOutput->totalMs;
        cached.resumedFrom = earlierFolder;
    }
    std::erase_if(wanted, [&](const auto& w) { return from && w.first <= from->samples; });
    std::erase_if(settings.snapshotSamples, [&](int n) { return from && n <= from->samples; });
    if (!checkpointFolder) settings.checkpointSeconds = 0.0;
    prepareFolder(folder);
    fs::path lastCheckpoint;  // the newest checkpoint of this render
    auto removeFolder = [](const fs::path& f) {
        std::error_code error;
        fs::remove(f / kMetaFile, error);  // first: what is left of it is never read as a reference
        fs::remove_all(f, error);
    };
    cached.output = renderReference(
        scene, settings, onPass,
        [&](const ReferenceOutput& soFar) {
            const int n = soFar.samplesPerPixel;
            const double ms = soFar.totalMs + earlierMs;
            bool snapshot = false;
            for (const auto& [samples, snapshotFolder] : wanted)
                if (samples == n) {
                    storeReference(snapshotFolder, scene, withSamples(n), soFar, ms);
                    snapshot = true;
                }
            if (soFar.sums.samples != n || snapshot) return;
            // A checkpoint: where a render cut short goes on from (as from an earlier reference); never over
            // a reference already there.
            const fs::path checkpoint = checkpointFolder(n);
            std::error_code error;
            if (checkpoint.empty() || fs::exists(checkpoint / kMetaFile, error)) return;
            storeReference(checkpoint, scene, withSamples(n), soFar, ms, true);
            if (!lastCheckpoint.empty()) removeFolder(lastCheckpoint);
            lastCheckpoint = checkpoint;
        },
        from ? &*from : nullptr);
    // A reference's time is that of all its samples, the earlier render's included: what rendering them at
    // once would have taken (the suite's path tracing time per sample comes from it).
    cached.output.totalMs += earlierMs;
    cached.resumedMs = earlierMs;
    storeReference(folder, scene, options, cached.output, cached.output.totalMs);
    cached.snapshotsStored = wanted.size();
    // The checkpoints served their purpose: this render's, and the earlier ones (the one it went on from, and
    // any an interruption left between writing a checkpoint and removing the one before).
    if (!lastCheckpoint.empty()) removeFolder(lastCheckpoint);
    for (const auto& [n, earlierFolder] : earlier)
        if (n < options.samplesPerPixel && isCheckpoint(earlierFolder)) removeFolder(earlierFolder);
    return cached;
}

}  // namespace deltagi
