// The quality suite (src/evaluation/quality_suite.h): the suite file, one scene's figures against its
// cached references, and the table (JSON and Markdown). Definitions: docs/ground-truth.md#the-quality-suite.
#include "evaluation/quality_suite.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "scene/json_reader.h"

namespace deltagi {

namespace fs = std::filesystem;

namespace {

constexpr int kMaxSuiteSamples = 1 << 20;  // as `deltagi reference --spp`
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

SuiteScene readSuiteScene(const JsonNode& node, const fs::path& folder) {
    node.requireObject();
    node.allowKeys({"name", "scene", "spp", "direct_spp", "set"});
    SuiteScene entry;
    entry.file = inputFile(node.child("scene"), folder);
    entry.name = entry.file.stem().string();
    if (auto n = node.find("name")) entry.name = n->string();
    if (auto n = node.find("spp")) entry.samplesPerPixel = n->integer(1, kMaxSuiteSamples);
    if (auto n = node.find("direct_spp")) entry.directSamplesPerPixel = n->integer(1, entry.samplesPerPixel);
    if (auto n = node.find("set")) {
        n->requireArray();
        for (size_t i = 0; i < n->size(); ++i) {
            const JsonNode item = n->element(i);
            std::string text = item.string();
            if (text.find('=') == std::string::npos)
                item.fail("expected \"KEY=VALUE\" (as --set), e.g. \"options.volume.resolution=64\"");
            entry.overrides.push_back(std::move(text));
        }
    }
    return entry;
}

QualitySuite readSuiteFile(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file.string(), "cannot open suite file");
    nlohmann::json document;
    try {
        document = nlohmann::json::parse(in);
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(file.string(), std::string("not valid JSON: ") + e.what());
    }
    const JsonNode root(document, file.string());
    root.requireObject();
    root.allowKeys({"description", "seed", "fit_spp", "scenes"});
    QualitySuite suite;
    suite.file = file;
    if (auto n = root.find("description")) n->string();
    if (auto n = root.find("seed")) {
        const int64_t seed = n->integer64();
        if (seed < 0) n->fail(fmt::format("expected an integer >= 0, got {}", seed));
        suite.seed = static_cast<uint64_t>(seed);
    }
    if (auto n = root.find("fit_spp")) {
        n->requireArray();
        suite.fitSamples.clear();
        for (size_t i = 0; i < n->size(); ++i)
            suite.fitSamples.push_back(n->element(i).integer(1, kMaxSuiteSamples));
        if (suite.fitSamples.empty()) n->fail("expected at least one number of samples, e.g. [1, 4, 16]");
    }
    const JsonNode scenes = root.child("scenes");
    scenes.requireArray();
    if (scenes.size() == 0) scenes.fail("expected at least one scene");
    for (size_t i = 0; i < scenes.size(); ++i)
        suite.scenes.push_back(readSuiteScene(scenes.element(i), file.parent_path()));
    return suite;
}

// The pixels whose change the delta figures judge.
bool isReal(PixelClass c) {
    return c == PixelClass::RealLit || c == PixelClass::RealShadowed;
}

// The change of a composite over the background it was made on, at pixel (x, y).
glm::dvec3 change(const Image& composite, const Image& background, int x, int y) {
    return glm::dvec3(composite.rgb(x, y)) - glm::dvec3(background.rgb(x, y));
}

std::string settingsFolder(const char* kind, int samples, uint64_t seed) {
    return fmt::format("{}-{}spp-seed{}", kind, samples, seed);
}

// The cache's folders of references of this kind and seed with fewer samples than `samples`: (samples,
// folder), the ones a new reference may go on from.
std::vector<std::pair<int, fs::path>> earlierFolders(const fs::path& cache, const char* kind, int samples,
                                                     uint64_t seed) {
    std::vector<std::pair<int, fs::path>> found;
    std::error_code error;
    if (!fs::is_directory(cache, error)) return found;
    const std::string prefix = std::string(kind) + "-", suffix = fmt::format("spp-seed{}", seed);
    for (const fs::directory_entry& entry : fs::directory_iterator(cache, error)) {
        const std::string name = entry.path().filename().string();
        if (name.size() <= prefix.size() + suffix.size() || !name.starts_with(prefix) ||
            !name.ends_with(suffix))
            continue;
        const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
        if (digits.empty() || digits.size() > 9 ||
            !std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); }))
            continue;
        const int n = std::stoi(digits);
        if (n > 0 && n < samples && settingsFolder(kind, n, seed) == name)
            found.emplace_back(n, entry.path());
    }
    return found;
}

void log(const SuiteRunOptions& options, const std::string& line) {
    if (options.log) options.log(line);
}

}  // namespace

Image onBackground(const ReferenceOutput& reference, const Image& background) {
    Image out = reference.composite;
    for (int y = 0; y < out.height(); ++y)
        for (int x = 0; x < out.width(); ++x) {
            const float real = 1.0f - reference.objectMask.at(x, y, 0);
            out.setRgb(x, y, out.rgb(x, y) + real * (background.rgb(x, y) - reference.background.rgb(x, y)));
        }
    return out;
}

namespace {

double ratioOrZero(double a, double b) {
    if (b > 0.0) return std::sqrt(a / b);
    return a > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
}

}  // namespace

DeltaSplit splitDeltaError(const Evaluation& e, const ReferenceOutput& direct) {
    const Image& background = e.reference.background;
    double shadow = 0.0, indirect = 0.0, reference = 0.0, referenceShadow = 0.0, referenceIndirect = 0.0;
    for (int y = 0; y < background.height(); ++y)
        for (int x = 0; x < background.width(); ++x) {
            if (!isReal(e.classes.classes[static_cast<size_t>(y) * background.width() + x])) continue;
            const glm::dvec3 dgi = change(e.dgiRender.composite, background, x, y);
            const glm::dvec3 dgiShadow = change(e.shadowOnlyComposite, background, x, y);
            const glm::dvec3 ref = change(e.reference.composite, background, x, y);
            const glm::dvec3 refShadow = change(direct.composite, direct.background, x, y);
            const glm::dvec3 shadowError = dgiShadow - refShadow;
            const glm::dvec3 indirectError = (dgi - dgiShadow) - (ref - refShadow);
            shadow += glm::dot(shadowError, shadowError);
            indirect += glm::dot(indirectError, indirectError);
            reference += glm::dot(ref, ref);
            referenceShadow += glm::dot(refShadow, refShadow);
            referenceIndirect += glm::dot(ref - refShadow, ref - refShadow);
        }
    return {ratioOrZero(shadow, reference), ratioOrZero(indirect, reference),
            ratioOrZero(referenceShadow, reference), ratioOrZero(referenceIndirect, reference)};
}

QualitySuite loadSuite(const fs::path& fileOrFolder) {
    std::error_code error;
    if (!fs::is_directory(fileOrFolder, error)) {
        if (!fs::exists(fileOrFolder, error))
            throw InputError(fileOrFolder.string(),
                             "suite not found: expected a suite file (.json) or a folder of scene files");
        return readSuiteFile(fileOrFolder);
    }
    QualitySuite suite;
    suite.file = fileOrFolder;
    std::vector<fs::path> files;
    for (const fs::directory_entry& entry : fs::directory_iterator(fileOrFolder, error))
        if (entry.is_regular_file() && entry.path().extension() == ".json") files.push_back(entry.path());
    if (error) throw InputError(fileOrFolder.string(), "cannot read folder: " + error.message());
    std::sort(files.begin(), files.end());
    if (files.empty()) throw InputError(fileOrFolder.string(), "no scene files (*.json) in the suite folder");
    for (const fs::path& file : files) {
        SuiteScene entry;
        entry.file = file;
        entry.name = file.stem().string();
        suite.scenes.push_back(std::move(entry));
    }
    return suite;
}

// How far a point's c may lie above the one used before the suite says the noise is not well behaved.
constexpr double kNoiseConstantSpread = 1.5;

std::vector<double> pointNoiseConstants(std::span<const int> samples, std::span<const double> errors,
                                        int referenceSpp) {
    std::vector<double> c;
    for (size_t i = 0; i < std::min(samples.size(), errors.size()); ++i) {
        const double n = samples[i], e = errors[i];
        const bool usable = n < referenceSpp && n >= 1.0 && std::isfinite(e) && e > 0.0;
        c.push_back(usable ? e / std::sqrt(1.0 / n - 1.0 / referenceSpp) : kNaN);
    }
    return c;
}

namespace {

// The c of the usable point with the most samples, from the points' c (pointNoiseConstants()).
double constantOfMostSamples(std::span<const int> samples, std::span<const double> c) {
    double best = kNaN;
    int most = 0;
    for (size_t i = 0; i < c.size(); ++i)
        if (!std::isnan(c[i]) && samples[i] > most) {
            most = samples[i];
            best = c[i];
        }
    return best;
}

}  // namespace

double noiseConstantOf(std::span<const int> samples, std::span<const double> errors, int referenceSpp) {
    return constantOfMostSamples(samples, pointNoiseConstants(samples, errors, referenceSpp));
}

std::optional<size_t> overstatingPoint(std::span<const int> samples, std::span<const double> errors,
                                       int referenceSpp) {
    const std::vector<double> points = pointNoiseConstants(samples, errors, referenceSpp);
    const double c = constantOfMostSamples(samples, points);
    for (size_t i = 0; i < points.size(); ++i)
        if (c > 0.0 && points[i] > kNoiseConstantSpread * c) return i;
    return std::nullopt;
}

double equalErrorSamples(double c, double error, double referenceNoise) {
    if (!std::isfinite(c) || !(c > 0.0) || !std::isfinite(error)) return kNaN;
    const double ownSquare =
        error * error - (std::isfinite(referenceNoise) ? referenceNoise * referenceNoise : 0.0);
    if (!(ownSquare > 0.0)) return std::numeric_limits<double>::infinity();
    return c * c / ownSquare;
}

double referenceNoiseOf(double apart) {
    return 0.5 * apart;
}

ReferenceOutput meanOfReferences(const ReferenceOutput& a, const ReferenceOutput& b) {
    // with and without are not kept in the cache (cachedReference()): empty unless both have them. A cached
    // image is read with the channels of its file (a mask as RGB): the mean keeps the fewer, channel by
    // channel.
    const auto mean = [](const Image& x, const Image& y) {
        if (x.empty() || y.empty()) return Image();
        if (x.width() != y.width() || x.height() != y.height())
            throw std::invalid_argument("meanOfReferences: the references' images differ in size");
        const int channels = std::min(x.channels(), y.channels());
        Image out(x.width(), x.height(), channels);
        for (int py = 0; py < x.height(); ++py)
            for (int px = 0; px < x.width(); ++px)
                for (int c = 0; c < channels; ++c)
                    out.at(px, py, c) = 0.5f * (x.at(px, py, c) + y.at(px, py, c));
        return out;
    };
    ReferenceOutput out;
    out.composite = mean(a.composite, b.composite);
    out.with = mean(a.with, b.with);
    out.without = mean(a.without, b.without);
    out.background = mean(a.background, b.background);
    out.objectMask = mean(a.objectMask, b.objectMask);
    out.delta = mean(a.delta, b.delta);
    out.samplesPerPixel = a.samplesPerPixel + b.samplesPerPixel;
    out.totalMs = a.totalMs + b.totalMs;
    return out;
}

namespace {

// The overrides of a suite entry: its own, then the run's.
std::vector<std::string> entryOverrides(const SuiteScene& entry, const SuiteRunOptions& options) {
    std::vector<std::string> overrides = entry.overrides;
    overrides.insert(overrides.end(), options.overrides.begin(), options.overrides.end());
    return overrides;
}

// evaluateSuiteScene for `scene` as it is shown (a sequence at one of its frames), named `name`, its
// references cached under `key`.
SceneQuality evaluateShownScene(const QualitySuite& suite, const SuiteScene& entry,
                                const SuiteRunOptions& options, const Scene& scene, std::string name,
                                std::string key) {
    SceneQuality q;
    q.name = std::move(name);
    q.file = entry.file;
    q.overrides = entryOverrides(entry, options);
    q.warnings = scene.warnings;
    q.key = std::move(key);
    const fs::path cache = options.cacheFolder / q.key;
    const uint64_t suiteSeed = options.seed.value_or(suite.seed);
    q.referenceSpp = options.samplesPerPixel.value_or(entry.samplesPerPixel);
    q.directSpp = options.samplesPerPixel || entry.directSamplesPerPixel == 0
                      ? std::max(q.referenceSpp / kDirectSamplesDivisor, 1)
                      : std::min(entry.directSamplesPerPixel, q.referenceSpp);

    // `snapshots`: sample counts of the same kind whose references this one's first samples give (the fit's).
    auto reference = [&](const char* kind, int samples, int maxBounces,
                         const std::vector<int>& snapshots = {}, uint64_t seedOffset = 0) {
        const uint64_t seed = suiteSeed + seedOffset;
        ReferenceOptions settings;
        settings.samplesPerPixel = samples;
        settings.seed = seed;
        settings.checkpointSeconds = 60.0 * std::max(options.checkpointMinutes, 0.0);
        if (maxBounces > 0) settings.maxBounces = maxBounces;
        const fs::path folder = cache / settingsFolder(kind, samples, seed);
        std::error_code error;
        if (!fs::exists(folder / "reference.json", error))
            log(options, fmt::format("  {}: rendering the {} reference, {} spp", q.name, kind, samples));
        std::vector<std::pair<int, fs::path>> snapshotFolders;
        for (const int n : snapshots) snapshotFolders.emplace_back(n, cache / settingsFolder(kind, n, seed));
        CachedReference r = cachedReference(scene, settings, folder, options.onPass, snapshotFolders,
                                            earlierFolders(cache, kind, samples, seed),
                                            [&](int n) { return cache / settingsFolder(kind, n, seed); });
        if (!r.resumedFrom.empty())
            log(options, fmt::format("  {}: went on from the samples of {}", q.name, r.resumedFrom.string()));
        if (r.snapshotsStored > 0)
            log(options, fmt::format("  {}: {} of the fit's references stored from its first samples", q.name,
                                     r.snapshotsStored));
        log(options, fmt::format("  {}: {} reference, {} spp: {} {}", q.name, kind, samples,
                                 r.hit ? "cache hit"
                                 : r.resumedFrom.empty()
                                     ? fmt::format("rendered in {:.1f} s,", r.output.totalMs / 1000.0)
                                     : fmt::format("rendered in {:.1f} s ({:.1f} s of them before),",
                                                   r.output.totalMs / 1000.0, r.resumedMs / 1000.0),
                                 r.hit ? r.folder.string() : "stored in " + r.folder.string()));
        ++(r.hit ? q.cacheHits : q.cacheMisses);
        return std::move(r.output);
    };

    // The full reference: the mean of two renders from independent random sequences (seeds s and s + 1),
    // whose difference measures its noise below. DGI and its baselines against it (evaluate()).
    const ReferenceOutput first = reference("full", q.referenceSpp, 0, suite.fitSamples);
    const ReferenceOutput second = reference("full", q.referenceSpp, 0, {}, 1);
    const Evaluation e = evaluate(scene, meanOfReferences(first, second));
    q.dgi = e.dgi;
    q.shadowOnly = e.shadowOnly;
    q.noRelight = e.noRelight;
    q.dgiMs = e.dgiMs;
    q.referenceMs = e.referenceMs;
    log(options, fmt::format("  {}: DGI {:.0f} ms, delta_rel_error {:.4f}, object_rel_rmse {:.4f}", q.name,
                             q.dgiMs, q.dgi.deltaRelError, q.dgi.objectRelRmse));

    // Direct light only (the first vertex of the same paths, the first directSpp of each render's): the
    // object's shadow in the reference.
    const DeltaSplit split = splitDeltaError(
        e, meanOfReferences(reference("direct", q.directSpp, 1), reference("direct", q.directSpp, 1, {}, 1)));
    q.shadowPart = split.shadowPart;
    q.indirectPart = split.indirectPart;
    q.referenceShadowShare = split.referenceShadowShare;
    q.referenceIndirectShare = split.referenceIndirectShare;

    // The path tracer's noise, from its first n samples against all of them; its time per sample, from the
    // largest of them.
    int timedFit = 0;  // samples of the largest fit reference with a time, and its time
    double timedFitMs = 0.0;
    for (const int n : suite.fitSamples) {
        if (n >= q.referenceSpp) continue;
        const ReferenceOutput low = reference("full", n, 0);
        if (low.totalMs > 0.0 && n > timedFit) timedFit = n, timedFitMs = low.totalMs;
        const DeltaFigures f = deltaFigures(onBackground(low, e.reference.background), e.reference.composite,
                                            e.reference.background, e.classes);
        q.fitSamples.push_back(n);
        q.fitDeltaErrors.push_back(f.deltaRelError);
        q.fitObjectErrors.push_back(f.objectRelRmse);
    }
    // The fit's references are the first's first samples: against the mean of 2 spp samples, as against a
    // reference of 2 spp samples of which they are the first (noiseConstantOf()).
    const int meanSpp = 2 * q.referenceSpp;
    q.noiseConstant = noiseConstantOf(q.fitSamples, q.fitDeltaErrors, meanSpp);
    q.objectNoiseConstant = noiseConstantOf(q.fitSamples, q.fitObjectErrors, meanSpp);
    // The mean's own noise, from the two renders' difference (referenceNoiseOf()).
    const DeltaFigures apart =
        deltaFigures(onBackground(first, second.background), second.composite, second.background, e.classes);
    q.referenceNoise = referenceNoiseOf(apart.deltaRelError);
    q.objectReferenceNoise = referenceNoiseOf(apart.objectRelRmse);
    q.equalErrorSpp = equalErrorSamples(q.noiseConstant, q.dgi.deltaRelError, q.referenceNoise);
    q.timedSpp = timedFit > 0 ? timedFit : meanSpp;
    q.pathTracerMsPerSpp = (timedFit > 0 ? timedFitMs : q.referenceMs) / q.timedSpp;
    q.equalErrorMs = q.equalErrorSpp * q.pathTracerMsPerSpp;

    const auto checkNoise = [&](const char* what, double noise, double figure) {
        if (std::isfinite(noise) && noise > kMaxReferenceNoiseShare * figure)
            q.warnings.push_back(fmt::format(
                "{}: the reference's noise in {} is {:.4f}, {:.1f} % of DGI's {:.4f} (more than {:.0f} %): "
                "give the scene more samples (\"spp\", now {}; the noise falls as 1/sqrt(spp))",
                entry.file.string(), what, noise, 100.0 * noise / figure, figure,
                100.0 * kMaxReferenceNoiseShare, q.referenceSpp));
    };
    if (std::isnan(q.noiseConstant))
        q.warnings.push_back(
            fmt::format("{}: no reference noise estimate: every fit_spp is at least the "
                        "scene's spp ({})",
                        entry.file.string(), q.referenceSpp));
    // Points that disagree: the noise of a few samples is not the reference's (noiseConstantOf()).
    if (const auto i = overstatingPoint(q.fitSamples, q.fitDeltaErrors, meanSpp))
        q.warnings.push_back(fmt::format(
            "{}: the path tracer's error falls faster than 1/sqrt(spp) (c {:.2f} from {} spp, {:.2f} from "
            "the largest fit_spp): rare bright paths (caustics) dominate the figures of few samples, so the "
            "noise and the equal-error figures come from the largest",
            entry.file.string(), pointNoiseConstants(q.fitSamples, q.fitDeltaErrors, meanSpp)[*i],
            q.fitSamples[*i], q.noiseConstant));
    checkNoise("delta_rel_error", q.referenceNoise, q.dgi.deltaRelError);
    checkNoise("object_rel_rmse", q.objectReferenceNoise, q.dgi.objectRelRmse);
    return q;
}

}  // namespace

SceneQuality evaluateSuiteScene(const QualitySuite& suite, const SuiteScene& entry,
                                const SuiteRunOptions& options) {
    const std::vector<std::string> overrides = entryOverrides(entry, options);
    const Scene scene = loadScene(entry.file, overrides);
    return evaluateShownScene(suite, entry, options, scene, entry.name,
                              referenceContentKey(entry.file, overrides));
}

std::vector<SceneQuality> evaluateSuiteEntry(const QualitySuite& suite, const SuiteScene& entry,
                                             const SuiteRunOptions& options) {
    const std::vector<std::string> overrides = entryOverrides(entry, options);
    Scene scene = loadScene(entry.file, overrides);
    const std::string key = referenceContentKey(entry.file, overrides);
    if (scene.sequence.empty()) {
        SceneQuality q = evaluateShownScene(suite, entry, options, scene, entry.name, key);
        if (options.onScene) options.onScene(q);
        return {std::move(q)};
    }
    std::vector<SceneQuality> frames;
    const std::vector<SequenceFrame> sequence = scene.sequence;
    for (const SequenceFrame& frame : sequence) {
        showFrame(scene, frame);
        frames.push_back(evaluateShownScene(suite, entry, options, scene,
                                            fmt::format("{} frame {}", entry.name, frame.index),
                                            fmt::format("{}-frame{}", key, frame.index)));
        if (options.onScene) options.onScene(frames.back());
    }
    return frames;
}

namespace {

nlohmann::ordered_json sceneJson(const SceneQuality& q) {
    nlohmann::ordered_json j;
    j["name"] = q.name;
    j["scene"] = q.file.string();
    j["set"] = q.overrides;
    j["key"] = q.key;
    const nlohmann::ordered_json dgi = figuresJson(q.dgi);
    for (const auto& [key, value] : dgi.items()) j[key] = value;
    j["baselines"] = {{"shadow_only", figuresJson(q.shadowOnly)}, {"no_relight", figuresJson(q.noRelight)}};
    j["split"] = {{"shadow_part", q.shadowPart},
                  {"indirect_part", q.indirectPart},
                  {"reference_shadow_share", q.referenceShadowShare},
                  {"reference_indirect_share", q.referenceIndirectShare}};
    j["dgi_ms"] = q.dgiMs;
    nlohmann::ordered_json fit = nlohmann::ordered_json::array();
    for (size_t i = 0; i < q.fitSamples.size(); ++i)
        fit.push_back({{"spp", q.fitSamples[i]},
                       {"delta_rel_error", q.fitDeltaErrors[i]},
                       {"object_rel_rmse", q.fitObjectErrors[i]}});
    j["reference"] = {{"spp", q.referenceSpp},
                      {"renders", 2},
                      {"direct_spp", q.directSpp},
                      {"ms", q.referenceMs},
                      {"ms_per_spp", q.referenceMs / (2.0 * q.referenceSpp)},
                      {"noise_constant", q.noiseConstant},
                      {"object_noise_constant", q.objectNoiseConstant},
                      {"noise", q.referenceNoise},
                      {"object_noise", q.objectReferenceNoise},
                      {"noise_share", q.referenceNoise / q.dgi.deltaRelError},
                      {"object_noise_share", q.objectReferenceNoise / q.dgi.objectRelRmse},
                      {"fit", fit}};
    j["equal_error"] = {{"spp", q.equalErrorSpp},
                        {"ms", q.equalErrorMs},
                        {"ms_per_spp", q.pathTracerMsPerSpp},
                        {"timed_spp", q.timedSpp},
                        {"ms_over_dgi_ms", q.dgiMs > 0.0 ? q.equalErrorMs / q.dgiMs : kNaN}};
    j["cache"] = {{"hits", q.cacheHits}, {"misses", q.cacheMisses}};
    j["warnings"] = q.warnings;
    return j;
}

// Numbers for the table: NaN as "n/a", infinity as "∞".
std::string cell(double value, const char* format = "{:.4f}") {
    if (std::isnan(value)) return "n/a";
    if (std::isinf(value)) return "∞";
    return fmt::format(fmt::runtime(format), value);
}

std::string count(double value) {
    if (!std::isfinite(value)) return cell(value);
    return value >= 100.0 ? fmt::format("{:.0f}", value) : fmt::format("{:.3g}", value);
}

}  // namespace

nlohmann::ordered_json suiteToJson(std::span<const SceneQuality> scenes, const std::string& command) {
    nlohmann::ordered_json j;
    j["command"] = command;
    j["scenes"] = nlohmann::ordered_json::array();
    for (const SceneQuality& q : scenes) j["scenes"].push_back(sceneJson(q));
    return j;
}

std::string suiteMarkdown(std::span<const SceneQuality> scenes, const std::string& command) {
    std::string md =
        "# Quality suite\n\n"
        "DGI against the path-traced ground truth over the suite's scenes, made by\n\n"
        "```sh\n" +
        command +
        "\n```\n\n"
        "Definitions of every column: [ground-truth.md](ground-truth.md#the-quality-suite). Errors are over "
        "the "
        "real pixels (Δ) or the object's pixels, relative to the reference's norm there: 0 is perfect, "
        "`no_relight` (Δ = 0) is 1. Times are wall-clock on the machine that ran the command.\n\n";
    md +=
        "| scene | delta_rel_error | object_rel_rmse | shadow_only | no_relight | shadow part | indirect "
        "part | "
        "DGI ms | equal-error spp | equal-error PT ms | PT / DGI time | reference spp | reference noise (Δ, "
        "share) |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const SceneQuality& q : scenes)
        md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {:.0f} | {} | {} | {} | {} | {} ({}) |\n",
                          q.name, cell(q.dgi.deltaRelError), cell(q.dgi.objectRelRmse),
                          cell(q.shadowOnly.deltaRelError), cell(q.noRelight.deltaRelError),
                          cell(q.shadowPart), cell(q.indirectPart), q.dgiMs, count(q.equalErrorSpp),
                          count(q.equalErrorMs), q.dgiMs > 0.0 ? count(q.equalErrorMs / q.dgiMs) : "n/a",
                          fmt::format("2 × {}", q.referenceSpp), cell(q.referenceNoise),
                          cell(100.0 * q.referenceNoise / q.dgi.deltaRelError, "{:.1f} %"));
    md +=
        "\n## The references\n\n"
        "| scene | spp | ms | ms / spp | equal-error ms / spp (timed at spp) | shadow share of Δref "
        "| indirect share of Δref | c (Δ) | c (object) | object noise (share) | fit: spp → delta_rel_error "
        "| cache key |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|\n";
    for (const SceneQuality& q : scenes) {
        std::string fit;
        for (size_t i = 0; i < q.fitSamples.size(); ++i)
            fit +=
                fmt::format("{}{} → {}", fit.empty() ? "" : ", ", q.fitSamples[i], cell(q.fitDeltaErrors[i]));
        md += fmt::format(
            "| {} | {} | {:.0f} | {:.0f} | {:.0f} ({}) | {} | {} | {} | {} | {} ({}) | {} | `{}` |\n", q.name,
            fmt::format("2 × {}", q.referenceSpp), q.referenceMs, q.referenceMs / (2.0 * q.referenceSpp),
            q.pathTracerMsPerSpp, q.timedSpp, cell(q.referenceShadowShare), cell(q.referenceIndirectShare),
            cell(q.noiseConstant), cell(q.objectNoiseConstant), cell(q.objectReferenceNoise),
            cell(100.0 * q.objectReferenceNoise / q.dgi.objectRelRmse, "{:.1f} %"),
            fit.empty() ? "none" : fit, q.key);
    }
    std::string warnings;
    for (const SceneQuality& q : scenes)
        for (const std::string& w : q.warnings) warnings += "* " + w + "\n";
    if (!warnings.empty()) md += "\n## Warnings\n\n" + warnings;
    return md;
}

}  // namespace deltagi
