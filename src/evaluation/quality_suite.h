// The quality suite (`deltagi eval --suite`): DGI against path-traced references over a list of scenes, the
// references cached on disk and keyed by the scenes' content, and one table of figures per scene: the errors
// and baselines of `deltagi eval`, the split of the delta error into its shadow and indirect parts, and the
// path tracer's equal-error samples and time. Definitions: docs/ground-truth.md#the-quality-suite.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/reference.h"
#include "deltagi/scene.h"
#include "evaluation/evaluation.h"

namespace deltagi {

// ---- The suite file ----

// Reference samples per pixel of a scene whose entry does not say ("spp").
constexpr int kDefaultSuiteSamples = 256;

struct SuiteScene {
    std::string name;                    // "name"; default: the scene file's stem
    std::filesystem::path file;          // "scene", relative to the suite file's folder
    std::vector<std::string> overrides;  // "set": ["KEY=VALUE", ...], applied like --set
    // "spp": samples per pixel of each of the two full references (referenceNoiseOf()).
    int samplesPerPixel = kDefaultSuiteSamples;
    // "direct_spp": samples of the direct-light-only reference that splits the error (at most spp); 0: spp /
    // kDirectSamplesDivisor. Direct light alone is far less noisy than the full paths.
    int directSamplesPerPixel = 0;
};

// The direct-light-only reference takes spp / this many samples unless a scene says ("direct_spp").
constexpr int kDirectSamplesDivisor = 4;

struct QualitySuite {
    std::filesystem::path file;  // the suite file, or the folder whose *.json scenes make the suite
    std::vector<SuiteScene> scenes;
    uint64_t seed = 0;  // "seed": the path tracer's random sequence, for every reference of the suite
    // "fit_spp": the low-sample references that measure the path tracer's noise (each below a scene's spp
    // counts; the largest gives it); see noiseConstantOf().
    std::vector<int> fitSamples{1, 4, 16, 64};
};

// A suite file ({"scenes": [{"scene": "cornell-box.json", "spp": 512, "set": [...]}, ...]}, see
// docs/ground-truth.md) or a folder: every *.json file in it, sorted by name, is a scene with the default
// settings. Throws InputError naming the file and key for bad input (a missing file, a wrong type, an
// unknown key, no scenes).
QualitySuite loadSuite(const std::filesystem::path& fileOrFolder);

// ---- The reference cache ----

// Bump when the path tracer changes what it renders: every cached reference is then rendered again.
constexpr int kReferenceCacheVersion = 2;
// The same for the references with a bounce limit (the direct-light-only ones) alone. 2: the last bounce
// keeps the BRDF sample's MIS share of the direct light (the references with all bounces did not change).
constexpr int kLimitedReferenceCacheVersion = 2;

// 16 hex digits identifying what a path-traced reference of the scene depends on: the scene file after
// `overrides`, without "options" and "description" (the path tracer reads neither: DGI's options may change
// without rendering the reference again), the contents of every file it references (meshes and their MTL
// material files, the photo, the environment map), and kReferenceCacheVersion. Throws InputError when the
// scene file cannot be read.
std::string referenceContentKey(const std::filesystem::path& sceneFile,
                                const std::vector<std::string>& overrides);

struct CachedReference {
    ReferenceOutput output;  // composite, background and objectMask (the images an evaluation reads)
    bool hit = false;        // read from the cache; false: rendered now and stored
    std::filesystem::path folder;
    size_t snapshotsStored = 0;  // of `snapshots`, the references stored from this render's first samples
    std::filesystem::path resumedFrom;  // the earlier reference it went on from (empty: none)
    double resumedMs = 0.0;             // the earlier reference's time, which output.totalMs includes
};

// The reference of `scene` with `options` from `folder` when it holds one rendered with the same samples,
// seed and bounces (written by an earlier call), else rendered and stored there. The caller names the folder
// by the scene's content (referenceContentKey()). A time limit is not allowed (the cache holds whole
// renders only). `snapshots`: (n, folder) of references of the same settings with n < the samples asked
// for; those their folders do not hold yet are stored there from the render's first n samples (the same
// images as renders of their own, ReferenceOptions::snapshotSamples), when it renders. `earlier`: (n, folder)
// of references of the same settings with n < the samples asked for; when it renders, it goes on from the
// one with the most samples that kept its sums (ReferenceSums, `sums.bin`), rendering only the samples it
// lacks (the same image as a render of all of them). `checkpointFolder`: with options.checkpointSeconds,
// where the render stores its checkpoints (the folder of a reference of that many samples, named so that the
// caller finds it among `earlier` the next time): a reference of n samples with its sums, marked as a
// checkpoint. Only the newest is kept; it is removed when the render is stored, and so are the checkpoints
// among `earlier`. A folder that holds a reference already is left as it is.
CachedReference cachedReference(
    const Scene& scene, const ReferenceOptions& options, const std::filesystem::path& folder,
    const ReferenceProgress& onPass = {},
    const std::vector<std::pair<int, std::filesystem::path>>& snapshots = {},
    const std::vector<std::pair<int, std::filesystem::path>>& earlier = {},
    const std::function<std::filesystem::path(int samples)>& checkpointFolder = {});

// ---- The path tracer's equal-error samples ----

// The path tracer's delta error falls as c / sqrt(spp). Measured against a reference of `referenceSpp`
// samples rendered from the same random sequence (the n-sample image is the mean of the reference's first n
// samples), its expected square is c^2 (1/n - 1/referenceSpp): each point gives c. Where every sample is
// about as bright as the next the points agree; where rare bright paths dominate (caustics: a glossy glaze
// that mirrors a small lamp onto the floor) the figures of a few samples fall faster than 1/sqrt(n) and
// overstate c (cornell-textured: 40, 22 and 11 from 1, 4 and 16 samples, 10.6 from 256). So c is the point's
// with the most samples (below referenceSpp), the nearest to the reference's own regime. Points with
// n >= referenceSpp or an error that is not finite and > 0 are left out; NaN when none is left.
double noiseConstantOf(std::span<const int> samples, std::span<const double> errors, int referenceSpp);
// The c of each point (NaN for a point left out), in the order given.
std::vector<double> pointNoiseConstants(std::span<const int> samples, std::span<const double> errors,
                                        int referenceSpp);
// The first point whose c is more than 1.5 times the one used (noiseConstantOf()): the figures of few samples
// do not fall as 1/sqrt(spp). The suite warns then.
std::optional<size_t> overstatingPoint(std::span<const int> samples, std::span<const double> errors,
                                       int referenceSpp);

// Samples per pixel at which the path tracer's expected delta error equals `error`, DGI's error measured
// against a reference whose own noise is `referenceNoise` (in the same units; referenceNoiseOf()): that is
// taken out of it first (independent errors add in squares), then spp = c^2 / error^2. Infinity when the
// error is within the reference's noise; NaN when c is.
double equalErrorSamples(double c, double error, double referenceNoise);

// ---- The reference's own noise ----

// A scene's reference is the mean of two renders of spp samples each from independent random sequences
// (seeds s and s + 1). Their errors are independent and alike, so the figure of one against the other,
// `apart` (delta_rel_error or object_rel_rmse of the first judged against the second), is sqrt(2) times one
// render's noise, and the mean's noise is half of it: exact in expectation for any sampler, where the fit's
// c / sqrt(spp) assumes independent samples and so overstates the noise of stratified ones (Sobol').
double referenceNoiseOf(double apart);
// The mean of two references of the same scene and camera, image by image (`with` and `without` only when
// both have them); samplesPerPixel and totalMs add up.
ReferenceOutput meanOfReferences(const ReferenceOutput& a, const ReferenceOutput& b);

// ---- Running the suite ----

// The suite's references keep a checkpoint this often (minutes of rendering).
constexpr double kDefaultCheckpointMinutes = 10.0;

struct SceneQuality;

struct SuiteRunOptions {
    std::filesystem::path cacheFolder = "out/quality/refs";
    std::vector<std::string> overrides;           // applied to every scene after its own "set"
    std::optional<int> samplesPerPixel;           // instead of every scene's "spp"
    std::optional<uint64_t> seed;                 // instead of the suite's "seed"
    std::function<void(const std::string&)> log;  // one line per step (cache hits, renders)
    ReferenceProgress onPass;                     // progress of each reference being rendered
    // Minutes of rendering between a reference's checkpoints (cachedReference's), 0 = none: an interrupted
    // suite goes on from the last one.
    double checkpointMinutes = kDefaultCheckpointMinutes;
    // After each scene, and each frame of a sequence, that evaluateSuiteEntry evaluates, with its figures.
    std::function<void(const SceneQuality&)> onScene;
};

// The share of a figure above which the reference noise makes the suite warn: under 10 % a change of a fifth
// of a figure stands out of the noise (the issue of quality on independent scenes).
constexpr double kMaxReferenceNoiseShare = 0.10;

struct SceneQuality {
    std::string name;
    std::filesystem::path file;
    std::vector<std::string> overrides;
    std::string key;  // referenceContentKey()
    DeltaFigures dgi, shadowOnly, noRelight;
    // ||Δdgi_shadow - Δref_direct|| / ||Δref|| and ||(Δdgi - Δdgi_shadow) - (Δref - Δref_direct)|| /
    // ||Δref|| over real pixels (docs/ground-truth.md).
    double shadowPart = 0.0, indirectPart = 0.0;
    // ||Δref_direct|| / ||Δref|| and ||Δref - Δref_direct|| / ||Δref||: how much of the true change is the
    // object's shadow (direct light) and how much indirect.
    double referenceShadowShare = 0.0, referenceIndirectShare = 0.0;
    double dgiMs = 0.0;
    int referenceSpp = 0, directSpp = 0;  // of each of the two full references, and of the direct one
    double referenceMs = 0.0;  // when the references were rendered (both renders of each), from the cache
    std::vector<int> fitSamples;
    std::vector<double> fitDeltaErrors, fitObjectErrors;    // of the low-sample references
    double noiseConstant = 0.0, objectNoiseConstant = 0.0;  // c (noiseConstantOf), for Δ and the object
    // The mean reference's noise in delta_rel_error and object_rel_rmse (referenceNoiseOf()).
    double referenceNoise = 0.0, objectReferenceNoise = 0.0;
    double equalErrorSpp = 0.0, equalErrorMs = 0.0;
    // The path tracer's time per sample that equalErrorMs is made from: the largest fit reference's (a
    // render of its own, or the full reference's first samples: one run, setup included), so that a full
    // reference grown over several runs, or rendered while the machine was busy, does not change it; the full
    // reference's ms / spp without a fit. `timedSpp`: that reference's samples.
    double pathTracerMsPerSpp = 0.0;
    int timedSpp = 0;
    size_t cacheHits = 0, cacheMisses = 0;
    std::vector<std::string> warnings;  // the scene's (loader) and the suite's (reference noise)
};

// Evaluates one scene of the suite: its references from the cache (or rendered and stored), DGI and its
// baselines against them, the split and the equal-error figures. A scene with a sequence is evaluated as its
// first frame.
SceneQuality evaluateSuiteScene(const QualitySuite& suite, const SuiteScene& entry,
                                const SuiteRunOptions& options);
// evaluateSuiteScene, and for a scene with a sequence ("sequence", its "frames" range) one figure per frame:
// each frame shown (its camera, photo or none, and keyframed objects) and evaluated as a still scene, named
// "NAME frame N", its references cached under the scene's key and "-frameN" (a still render of each pose:
// the temporal reuse of `deltagi render` over the sequence is not in them). options.onScene after each scene
// or frame.
std::vector<SceneQuality> evaluateSuiteEntry(const QualitySuite& suite, const SuiteScene& entry,
                                             const SuiteRunOptions& options);

// The table: one object per scene (keys in docs/ground-truth.md), and `command`, how it was made.
nlohmann::ordered_json suiteToJson(std::span<const SceneQuality> scenes, const std::string& command);
// The same as Markdown (docs/quality.md).
std::string suiteMarkdown(std::span<const SceneQuality> scenes, const std::string& command);

// ---- Internals, for the tests ----

// A reference's composite moved onto another background: each pixel keeps its change and, by its coverage,
// the object's radiance, so that references whose backgrounds are their own path-traced `without` (noisy,
// or direct light only) compare by their change alone. With a photo both backgrounds are the photo.
Image onBackground(const ReferenceOutput& reference, const Image& background);

struct DeltaSplit {
    double shadowPart = 0.0, indirectPart = 0.0;  // SceneQuality::shadowPart, indirectPart
    double referenceShadowShare = 0.0, referenceIndirectShare = 0.0;  // SceneQuality's, of Δref
};

// Over the real pixels of `e.classes`: DGI's shadow only (e.shadowOnlyComposite) against the
// direct-light-only reference's change (over its own background), and what DGI and the reference add to them
// (the indirect change), each relative to ||Δref|| (docs/ground-truth.md#the-quality-suite).
DeltaSplit splitDeltaError(const Evaluation& e, const ReferenceOutput& direct);

}  // namespace deltagi
