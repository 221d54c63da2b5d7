// The `deltagi` command: `render` a scene file to an image (and its AOVs), print `info` about a scene, render
// the path-traced `reference`, `compare` two images, `eval` DGI against the reference, `bench` the pipeline,
// measure its `stability`, `estimate-albedo` of the real scene from its photo, `encode` frames into an H.264
// MP4, print a `marker`, `track` a video by the scene's markers into a sequence, or augment a camera's frames
// `live`.
//
// Errors: bad input (InputError) and any other exception become one line `deltagi: error: <message>` on
// stderr and exit code 1; command-line usage errors exit with code 2; SIGINT and SIGTERM exit with 130 and
// 143. Outputs (cli/outputs.h) are checked before any work and written atomically.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "albedo_command.h"
#include "bench_command.h"
#include "deltagi/error.h"
#include "deltagi/image.h"
#include "deltagi/keyframes.h"
#include "deltagi/reference.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "deltagi_version.h"
#include "encode_command.h"
#include "eval_suite.h"
#include "evaluation/evaluation.h"
#include "info_command.h"
#include "io/atomic_file.h"
#include "live_command.h"
#include "marker_command.h"
#include "messages.h"
#include "outputs.h"
#include "serve_command.h"
#include "stability_command.h"
#include "track_command.h"
#include "validators.h"
#include "video_output.h"

namespace fs = std::filesystem;
using namespace deltagi;
using cli::checkOutputs;
using cli::finiteNumber;
using cli::finiteRange;
using cli::framePath;
using cli::OutputFiles;
using cli::refuseInputs;
using cli::sceneInputs;

namespace {

using cli::kExitInputError;
using cli::kExitUsageError;
using cli::loadAndWarn;
using cli::note;
using cli::oneLine;
using cli::plural;
constexpr int kMaxThreads = 4096;  // a sanity bound for --threads, far above any machine this runs on

struct RenderArgs {
    fs::path scene;
    fs::path output;
    fs::path aovDir;
    fs::path layers;     // a multi-layer EXR; empty: none
    std::string frames;  // a sequence's frame range "A:B"; empty: the scene's
    fs::path video;      // a sequence's H.264 MP4; empty: none
    cli::VideoSettings videoSettings;
    bool fpsGiven = false;  // --fps; otherwise the scene's frame rate
    std::vector<std::string> overrides;
    int threads = 0;  // 0: not given, TBB's default (all cores)
    bool quiet = false;
};

// `reference` and `eval` share the path tracer's settings.
struct ReferenceArgs {
    fs::path scene;
    fs::path output;  // reference: the composite image; eval: the JSON file
    fs::path aovDir;
    fs::path referenceDir;  // eval: the reference's images, rendered before
    std::vector<std::string> overrides;
    int samplesPerPixel = 64;
    double timeLimit = 0.0;
    uint64_t seed = 0;
    int maxBounces = 0;  // 0: ReferenceOptions' own (unlimited in practice)
    int threads = 0;
    bool quiet = false;
};

struct CompareArgs {
    fs::path test, reference;
    fs::path difference;
    float maxValue = 0.0f;  // 0: the 99th percentile of the image
    bool json = false;
};

int reportError(const std::string& message, int exitCode) {
    note("deltagi: error: {}\n", oneLine(message));
    return exitCode;
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

// The output and, with an AOV folder, the files the run writes into it (`names`).
std::vector<fs::path> outputFiles(const fs::path& output, const fs::path& aovDir,
                                  std::initializer_list<const char*> names) {
    std::vector<fs::path> files{output};
    if (!aovDir.empty())
        for (const char* name : names) files.push_back(aovDir / name);
    return files;
}

// timings.json: the stages in pipeline order (a stage run more than once, e.g. per light, is summed); the
// scene loading is not a pipeline stage and is reported beside them.
nlohmann::ordered_json timingsJson(const RenderOutput& output, const Scene& scene, int threads,
                                   double loadMs) {
    nlohmann::ordered_json json;
    json["stages"] = cli::stageTimesJson(output);
    json["total_ms"] = output.totalMs;
    json["load_ms"] = loadMs;
    json["threads"] = threads;
    json["width"] = scene.camera.width;
    json["height"] = scene.camera.height;
    json["volume_resolution"] = volumeRegion(scene).resolution;
    return json;
}

constexpr auto kRenderAovFiles = {"background.exr", "composite.exr", "object_mask.exr", "delta.exr",
                                  "timings.json"};

void writeAovs(const RenderOutput& output, const Scene& scene, int threads, double loadMs,
               const fs::path& folder, OutputFiles& out) {
    out.image(output.background, folder / "background.exr");
    out.image(output.composite, folder / "composite.exr");
    out.image(output.objectMask, folder / "object_mask.exr");
    out.image(output.delta, folder / "delta.exr");
    out.json(timingsJson(output, scene, threads, loadMs), folder / "timings.json");
}

// A sequence ("sequence" in the scene): every frame with its camera and photo through one FrameRenderer, each
// frame's files written and renamed into place when it is done (an interrupted run keeps the finished
// frames).
int runRenderSequence(const RenderArgs& args, Scene& scene, int threads, double loadMs) {
    if (!args.aovDir.empty() && args.aovDir.string().find('#') == std::string::npos &&
        args.aovDir.string().find('%') == std::string::npos)
        throw InputError(args.aovDir.string(),
                         "--aov with a sequence writes a folder per frame: give the frame number's place, "
                         "e.g. aov_####");
    std::vector<fs::path> outputs;
    for (const SequenceFrame& frame : scene.sequence) {
        if (!args.output.empty()) outputs.push_back(framePath(args.output, frame.index));
        if (!args.layers.empty()) outputs.push_back(framePath(args.layers, frame.index));
        if (!args.aovDir.empty())  // a folder per frame
            for (const char* name : kRenderAovFiles)
                outputs.push_back(framePath(args.aovDir, frame.index) / name);
    }
    if (!args.video.empty()) outputs.push_back(args.video);
    refuseInputs(outputs, sceneInputs(scene));
    const std::vector<SequenceFrame>& frames = scene.sequence;  // the loop changes the camera and photo only
    // Temporal reuse averages a frame with the frames before it (options.render.temporal_frames): a range
    // that starts later in the file renders those first, unwritten, so that a sequence rendered in chunks
    // gives the frames it gives at once. Their photos are needed too, and checked now.
    const int before = std::min(scene.options.render.temporalFrames - 1, frames.front().index);
    std::vector<SequenceFrame> warmUp;
    try {
        warmUp = framesBeforeSequence(scene);
    } catch (const InputError& e) {
        throw InputError(e.where(), fmt::format("{} (frames {}:{} are rendered first, unwritten, for the "
                                                "temporal reuse of options.render.temporal_frames {}; 1 "
                                                "renders without them)",
                                                e.message(), frames.front().index - before,
                                                frames.front().index, scene.options.render.temporalFrames));
    }
    std::optional<cli::VideoWriter> video;
    if (!args.video.empty()) {
        cli::VideoSettings settings = args.videoSettings;
        if (!args.fpsGiven) settings.fps = scene.frameRate;
        for (const SequenceFrame& frame : frames)
            if (frame.camera.width != frames.front().camera.width ||
                frame.camera.height != frames.front().camera.height)
                throw InputError(
                    fmt::format("{}: frames[{}]", scene.sequenceFile.string(), frame.index),
                    fmt::format(
                        "a {}x{} frame after {}x{} ones: the frames of a video (--video) have one size",
                        frame.camera.width, frame.camera.height, frames.front().camera.width,
                        frames.front().camera.height));
        createOutputFolder(args.video.parent_path());
        video.emplace(args.video, frames.front().camera.width, frames.front().camera.height, settings);
    }
    const bool progress = !args.quiet && isatty(STDERR_FILENO);
    const auto start = std::chrono::steady_clock::now();
    FrameRenderer renderer;
    double photoMs = loadMs;  // for the first frame, the scene's loading (which read its photo)
    auto renderAt = [&](const SequenceFrame& frame, bool readPhoto) {
        if (readPhoto) {
            const auto photoStart = std::chrono::steady_clock::now();
            showFrame(scene, frame);  // its camera, photo and keyframed objects
            photoMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - photoStart)
                          .count();
        } else {  // the scene's first frame, loaded with it
            scene.camera = frame.camera;
            poseObjects(scene, frame.index);
        }
        return renderer.render(scene);
    };
    for (const SequenceFrame& frame : warmUp) renderAt(frame, true);  // the frames before the range
    for (size_t i = 0; i < frames.size(); ++i) {
        const SequenceFrame& frame = frames[i];
        const RenderOutput output = renderAt(frame, i > 0 || before > 0);
        OutputFiles out;
        if (!args.output.empty()) out.image(output.composite, framePath(args.output, frame.index));
        if (!args.layers.empty()) out.layers(compositingLayers(output), framePath(args.layers, frame.index));
        if (!args.aovDir.empty())
            writeAovs(output, scene, threads, photoMs, framePath(args.aovDir, frame.index), out);
        out.commit();
        if (video) video->add(output.composite);
        if (progress) {
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const double rate = static_cast<double>(i + 1) / seconds;
            note("\rframe {}/{} (index {}): {:.2f} frames/s, {:.0f} s left   ", i + 1, frames.size(),
                 frame.index, rate, static_cast<double>(frames.size() - i - 1) / rate);
        }
    }
    if (video) video->commit();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (progress) note("\n");
    std::vector<std::string> written;
    for (const fs::path* path : {&args.output, &args.layers, &args.aovDir, &args.video})
        if (!path->empty()) written.push_back(path->string());
    if (!args.quiet)
        note("deltagi: wrote {} frames {} to {} ({}x{}, {:.2f} s, {:.2f} frames/s, {})\n", frames.size(),
             fmt::format("{}:{}", frames.front().index, frames.back().index + 1), fmt::join(written, ", "),
             scene.camera.width, scene.camera.height, seconds, static_cast<double>(frames.size()) / seconds,
             plural(threads, "thread", "threads"));
    return 0;
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

    // Bad paths fail before the render, not after it; so does an output that is one of the inputs.
    if (args.output.empty() && args.video.empty())
        return reportError("render: expected -o OUTPUT, --video OUT.mp4 or both (see deltagi --help)",
                           kExitUsageError);
    std::vector<fs::path> outputs;
    if (!args.output.empty()) {
        checkOutputPath(args.output);
        outputs = outputFiles(args.output, args.aovDir, kRenderAovFiles);
    }
    if (!args.video.empty()) {
        cli::checkVideoPath(args.video, "--video");
        cli::checkVideoEncoder(args.video, "--video");
        outputs.push_back(args.video);
    }
    if (!args.layers.empty()) {
        if (lowerExtension(args.layers) != ".exr")
            throw InputError(args.layers.string(), "--layers writes an OpenEXR file: expected .exr");
        outputs.push_back(args.layers);
    }
    checkOutputs(outputs, {{args.scene, "the scene file"}});

    const auto loadStart = std::chrono::steady_clock::now();
    Scene scene = loadAndWarn(args.scene, args.overrides, args.frames);
    const double loadMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - loadStart).count();
    if (!args.layers.empty()) scene.options.render.layers = true;
    if (!scene.sequence.empty()) return runRenderSequence(args, scene, threads, loadMs);
    if (!args.video.empty())
        throw InputError(
            "--video", "needs a scene with a \"sequence\" (the video's frames): a still is written with -o");
    if (progress) printStep("load", loadMs);
    refuseInputs(outputs, sceneInputs(scene));

    StageCallback onStage;
    if (progress) onStage = [&](const StageTiming& stage) { printStep(stage.name, stage.ms); };
    const RenderOutput output = render(scene, onStage);

    OutputFiles out;
    out.image(output.composite, args.output);
    if (!args.aovDir.empty()) writeAovs(output, scene, threads, loadMs, args.aovDir, out);
    if (!args.layers.empty()) out.layers(compositingLayers(output), args.layers);
    out.commit();

    if (progress) printStep("total", output.totalMs);
    if (!args.quiet) {
        note("deltagi: wrote {} ({}x{}, {:.1f} ms, {}){}\n", args.output.string(), scene.camera.width,
             scene.camera.height, output.totalMs, plural(threads, "thread", "threads"),
             args.aovDir.empty() ? "" : fmt::format(", AOVs in {}", args.aovDir.string()));
    }
    return 0;
}

// Sets TBB's thread count for as long as it lives; `threads()` is what the pool will use.
class ThreadLimit {
  public:
    explicit ThreadLimit(int threads) {
        if (threads > 0) limit_.emplace(tbb::global_control::max_allowed_parallelism, threads);
    }
    int threads() const {
        return static_cast<int>(
            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    }

  private:
    std::optional<tbb::global_control> limit_;
};

std::string formatSeconds(double seconds) {
    if (seconds < 60.0) return fmt::format("{:.0f} s", seconds);
    if (seconds < 3600.0)
        return fmt::format("{:.0f} min {:02.0f} s", std::floor(seconds / 60.0), std::fmod(seconds, 60.0));
    return fmt::format("{:.0f} h {:02.0f} min", std::floor(seconds / 3600.0),
                       std::fmod(seconds, 3600.0) / 60.0);
}

// A progress bar on one terminal line: samples done, time spent and an estimate of the time left (the
// smaller of the rate's estimate and what is left of the time limit).
ReferenceProgress progressBar(double timeLimit) {
    return [timeLimit](int done, int total, double seconds) {
        constexpr int kWidth = 30;
        const int filled = total > 0 ? done * kWidth / total : kWidth;
        double left = done > 0 ? seconds / done * (total - done) : 0.0;
        if (timeLimit > 0.0) left = std::min(left, std::max(timeLimit - seconds, 0.0));
        note("\r  [{}{}] {}/{} spp  {}  ETA {}   ", std::string(filled, '#'),
             std::string(kWidth - filled, '.'), done, total, formatSeconds(seconds), formatSeconds(left));
        if (done == total) note("\n");
    };
}

ReferenceOptions referenceOptions(const ReferenceArgs& args) {
    ReferenceOptions options;
    options.samplesPerPixel = args.samplesPerPixel;
    options.timeLimitSeconds = args.timeLimit;
    options.seed = args.seed;
    if (args.maxBounces > 0) options.maxBounces = args.maxBounces;
    return options;
}

constexpr auto kReferenceAovFiles = {"with.exr",      "without.exr",     "background.exr",
                                     "composite.exr", "object_mask.exr", "delta.exr"};

void writeReferenceAovs(const ReferenceOutput& output, const fs::path& folder, OutputFiles& out) {
    out.image(output.with, folder / "with.exr");
    out.image(output.without, folder / "without.exr");
    out.image(output.background, folder / "background.exr");
    out.image(output.composite, folder / "composite.exr");
    out.image(output.objectMask, folder / "object_mask.exr");
    out.image(output.delta, folder / "delta.exr");
}

// The images writeReferenceAovs wrote, for `eval --reference`; each must match the camera.
ReferenceOutput readReferenceAovs(const fs::path& folder, const Camera& camera) {
    ReferenceOutput r;
    for (auto [image, name] :
         {std::pair{&r.with, "with.exr"}, std::pair{&r.without, "without.exr"},
          std::pair{&r.background, "background.exr"}, std::pair{&r.composite, "composite.exr"},
          std::pair{&r.objectMask, "object_mask.exr"}, std::pair{&r.delta, "delta.exr"}}) {
        const fs::path path = folder / name;
        if (!fs::exists(path))
            throw InputError(path.string(),
                             "missing: --reference expects the folder of `deltagi reference --aov` or "
                             "`deltagi eval --aov`");
        const auto wrongSize = [&](int width, int height) {
            return InputError(path.string(), fmt::format("{}x{}, but the scene's camera is {}x{}", width,
                                                         height, camera.width, camera.height));
        };
        if (const auto size = imageFileSize(path);  // by the header, before decoding
            size && (size->first != camera.width || size->second != camera.height))
            throw wrongSize(size->first, size->second);
        *image = readImage(path);
        if (image->width() != camera.width || image->height() != camera.height)
            throw wrongSize(image->width(), image->height());
    }
    return r;
}

// Interrupted (SIGINT, SIGTERM), it writes nothing: the outputs stay as they were (installInterruptHandlers).
int runReference(const ReferenceArgs& args) {
    const ThreadLimit limit(args.threads);
    checkOutputPath(args.output);
    const std::vector<fs::path> outputs = outputFiles(args.output, args.aovDir, kReferenceAovFiles);
    checkOutputs(outputs, {{args.scene, "the scene file"}});
    const Scene scene = loadAndWarn(args.scene, args.overrides);
    refuseInputs(outputs, sceneInputs(scene));
    cli::noteFirstFrame(scene, "reference");

    const bool progress = !args.quiet && isatty(STDERR_FILENO);
    const ReferenceOutput output = renderReference(
        scene, referenceOptions(args), progress ? progressBar(args.timeLimit) : ReferenceProgress{});
    if (progress && output.samplesPerPixel < args.samplesPerPixel) note("\n");

    OutputFiles out;
    out.image(output.composite, args.output);
    if (!args.aovDir.empty()) writeReferenceAovs(output, args.aovDir, out);
    out.commit();
    if (!args.quiet) {
        note("deltagi: wrote {} ({}x{}, {} spp{}, {:.1f} s, {}){}\n", args.output.string(),
             scene.camera.width, scene.camera.height, output.samplesPerPixel,
             output.samplesPerPixel < args.samplesPerPixel ? " (time limit)" : "", output.totalMs / 1000.0,
             plural(limit.threads(), "thread", "threads"),
             args.aovDir.empty() ? "" : fmt::format(", AOVs in {}", args.aovDir.string()));
    }
    return 0;
}

int runCompare(const CompareArgs& args) {
    if (!args.difference.empty()) {
        checkOutputPath(args.difference);
        checkOutputs({args.difference},
                     {{args.test, "the image to judge"}, {args.reference, "the reference image"}});
    }
    // By their headers first: images of two sizes are not decoded.
    const auto testSize = imageFileSize(args.test), referenceSize = imageFileSize(args.reference);
    if (testSize && referenceSize && testSize != referenceSize)
        throw InputError(args.test.string() + " vs " + args.reference.string(),
                         fmt::format("images differ in size: {}x{} and {}x{}", testSize->first,
                                     testSize->second, referenceSize->first, referenceSize->second));
    const Image test = readImage(args.test);
    const Image reference = readImage(args.reference);
    ImageMetrics metrics;
    try {
        metrics = compareImages(test, reference);
    } catch (const InputError& error) {
        throw InputError(args.test.string() + " vs " + args.reference.string(), error.what());
    }
    float maxValue = args.maxValue;
    if (!args.difference.empty()) {
        const Image squared = squaredDifference(test, reference);
        if (!(maxValue > 0.0f)) maxValue = robustMaximum(squared);
        OutputFiles out;
        out.image(falseColour(squared, maxValue), args.difference);
        out.commit();
    }
    if (args.json) {
        nlohmann::ordered_json json;
        json["rmse"] = metrics.rmse;
        json["rel_mse"] = metrics.relMse;
        json["mae"] = metrics.mae;
        if (!args.difference.empty()) json["difference_max"] = maxValue;
        fmt::print("{}\n", json.dump(2));
    } else {
        fmt::print("rmse     {:.6g}\nrel_mse  {:.6g}\nmae      {:.6g}\n", metrics.rmse, metrics.relMse,
                   metrics.mae);
        if (!args.difference.empty())
            fmt::print("difference {} (2x squared difference, full scale {:.4g})\n", args.difference.string(),
                       maxValue);
    }
    return 0;
}

constexpr auto kEvaluationAovFiles = {"with.exr",       "without.exr",         "background.exr",
                                      "composite.exr",  "object_mask.exr",     "delta.exr",
                                      "reference.exr",  "reference.png",       "dgi.exr",
                                      "dgi.png",        "dgi_object_mask.exr", "no_relight.exr",
                                      "difference.exr", "difference.png",      "pixel_classes.exr"};

void writeEvaluationAovs(const Evaluation& e, const fs::path& folder, OutputFiles& out) {
    writeReferenceAovs(e.reference, folder,
                       out);  // with, without, background, composite (the reference's) ...
    out.image(e.reference.composite, folder / "reference.exr");
    out.image(e.reference.composite, folder / "reference.png");
    out.image(e.dgiRender.composite, folder / "dgi.exr");
    out.image(e.dgiRender.composite, folder / "dgi.png");
    out.image(e.dgiRender.objectMask, folder / "dgi_object_mask.exr");
    out.image(e.noRelightComposite, folder / "no_relight.exr");
    const Image squared = squaredDifference(e.dgiRender.composite, e.reference.composite);
    out.image(squared, folder / "difference.exr");
    out.image(falseColour(squared, robustMaximum(squared)), folder / "difference.png");
    Image classes(e.classes.width, e.classes.height, 1);
    for (size_t i = 0; i < e.classes.classes.size(); ++i)  // 0 silhouette, 1 object, 2 lit, 3 shadowed
        classes.data()[i] = static_cast<float>(e.classes.classes[i]);
    out.image(classes, folder / "pixel_classes.exr");
}

// eval over a scene's sequence: each frame scored (evaluateSequence), the figures per frame, their mean and
// the worst.
int runEvalSequence(const ReferenceArgs& args, Scene& scene) {
    if (!args.aovDir.empty())
        throw InputError("--aov",
                         "not with a \"sequence\": its figures are per frame (write the frames' images "
                         "with render --aov and reference over --set sequence.frames=A:A+1)");
    if (!args.referenceDir.empty())
        throw InputError("--reference", "not with a \"sequence\": each frame's reference is rendered");
    const bool progress = !args.quiet && isatty(STDERR_FILENO);
    const SequenceEvaluation e = evaluateSequence(scene, referenceOptions(args), [&](int done, int total) {
        if (progress) note("\rframe {}/{}   ", done, total);
    });
    if (progress) note("\n");
    OutputFiles out;
    out.json(sequenceEvaluationToJson(e, scene), args.output);
    out.commit();
    if (!args.quiet)
        note(
            "deltagi: {} frames: delta_rel_error mean {:.4f}, worst {:.4f}; object_rel_rmse mean {:.4f}, "
            "worst {:.4f} (references at {} spp); wrote {}\n",
            e.frames.size(), e.mean.deltaRelError, e.worst.deltaRelError, e.mean.objectRelRmse,
            e.worst.objectRelRmse, args.samplesPerPixel, args.output.string());
    return 0;
}

int runEval(const ReferenceArgs& args) {
    const ThreadLimit limit(args.threads);
    if (lowerExtension(args.output) != ".json")
        throw InputError(args.output.string(), "expected a .json file for the figures");
    const std::vector<fs::path> outputs = outputFiles(args.output, args.aovDir, kEvaluationAovFiles);
    std::vector<cli::RunInput> inputs{{args.scene, "the scene file"}};
    if (!args.referenceDir.empty())
        for (const char* name : kReferenceAovFiles)
            inputs.push_back({args.referenceDir / name, "a reference image of --reference"});
    checkOutputs(outputs, inputs);
    Scene scene = loadAndWarn(args.scene, args.overrides);
    refuseInputs(outputs, sceneInputs(scene));
    if (!scene.sequence.empty()) return runEvalSequence(args, scene);

    const bool progress = !args.quiet && isatty(STDERR_FILENO) && args.referenceDir.empty();
    if (progress) note("reference\n");
    const Evaluation e = !args.referenceDir.empty()
                             ? evaluate(scene, readReferenceAovs(args.referenceDir, scene.camera))
                             : evaluate(scene, referenceOptions(args),
                                        progress ? progressBar(args.timeLimit) : ReferenceProgress{});
    if (progress && e.reference.samplesPerPixel < args.samplesPerPixel) note("\n");

    OutputFiles out;
    out.json(evaluationToJson(e), args.output);
    if (!args.aovDir.empty()) writeEvaluationAovs(e, args.aovDir, out);
    out.commit();
    if (!args.quiet) {
        note(
            "deltagi: delta_rel_error {:.4f}, object_rel_rmse {:.4f}, composite_rmse {:.5f} "
            "(DGI {:.0f} ms, {}); pixels: {} lit, {} shadowed, {} object\n",
            e.dgi.deltaRelError, e.dgi.objectRelRmse, e.dgi.compositeRmse, e.dgiMs,
            args.referenceDir.empty() ? fmt::format("reference {} spp {:.1f} s", e.reference.samplesPerPixel,
                                                    e.referenceMs / 1000.0)
                                      : fmt::format("reference from {}", args.referenceDir.string()),
            e.classes.count(PixelClass::RealLit), e.classes.count(PixelClass::RealShadowed),
            e.classes.count(PixelClass::Object));
        note("deltagi: wrote {}{}\n", args.output.string(),
             args.aovDir.empty() ? "" : fmt::format(", images in {}", args.aovDir.string()));
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "deltagi: Delta Global Illumination, virtual objects in real images (voxel cone tracing + "
        "differential rendering)"};
    app.require_subcommand(1);
    app.set_version_flag("--version",
                         fmt::format("deltagi {} (git {})", DELTAGI_VERSION, DELTAGI_GIT_REVISION),
                         "Print the version and the git revision it was built from, and exit");
    app.footer(
        "Outputs are written to temporary files beside them and renamed into place together when all are "
        "complete; an output that is one of the run's inputs is refused.\nExit status: 0 done, 1 bad input "
        "or "
        "an output that cannot be written, 2 usage error, 130 or 143 interrupted by SIGINT or SIGTERM (the "
        "previous outputs left as they were).");
    cli::installInterruptHandlers();
    retainFreedMemory();

    RenderArgs renderArgs;
    CLI::App* renderCommand = app.add_subcommand("render", "Render a scene file to an image");
    renderCommand->add_option("scene", renderArgs.scene, "Scene file (JSON, see docs/scene-format.md)")
        ->required();
    renderCommand->add_option("-o,--output", renderArgs.output,
                              "Output image: .png (8-bit sRGB), .exr or .hdr (linear); with a sequence, each "
                              "frame's (frame_####.png); may be left out with --video");
    renderCommand->add_option(
        "--aov", renderArgs.aovDir,
        "Also write background, composite, object_mask, delta (.exr) and timings.json into this folder; "
        "with a sequence, one folder per frame (aov_####)");
    renderCommand->add_option("--layers", renderArgs.layers,
                              "Also write the compositing layers into one EXR: composite, background, object "
                              "(RGBA, premultiplied), shadow, indirect, delta, depth (see README)");
    renderCommand->add_option("--frames", renderArgs.frames,
                              "With a \"sequence\": the frames A:B to render (A included, B not; e.g. 0:120, "
                              "40:, :10); -o and --layers then name each frame's file with #### or %04d");
    CLI::Option* videoOption =
        renderCommand->add_option("--video", renderArgs.video,
                                  "With a \"sequence\": also (or, without -o, only) write the composites as "
                                  "an H.264 MP4 (8-bit sRGB as the PNGs, yuv420p), or .y4m: uncompressed");
    renderCommand
        ->add_option("--fps", renderArgs.videoSettings.fps,
                     "The video's frames per second (default: the sequence's, sequence.fps or 30)")
        ->check(finiteNumber(0.0, true, "a number of frames per second > 0"))
        ->check(finiteRange(0.0, kMaxFrameRate))
        ->needs(videoOption);
    renderCommand
        ->add_option("--crf", renderArgs.videoSettings.crf,
                     "The video's quality: x264's constant rate factor, 0 (lossless) to 51 (default 18)")
        ->check(CLI::Range(0, cli::kMaxCrf))
        ->needs(videoOption);
    renderCommand->add_option("--set", renderArgs.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    renderCommand->add_option("--threads", renderArgs.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, kMaxThreads));
    renderCommand->add_flag("-q,--quiet", renderArgs.quiet, "Print nothing but errors");

    cli::InfoArgs infoArgs;
    CLI::App* infoCommand = cli::addInfoCommand(app, infoArgs);

    ReferenceArgs referenceArgs;
    CLI::App* referenceCommand = app.add_subcommand(
        "reference",
        "Path-trace the ground truth: a differential composite from renders with and without the "
        "virtual objects");
    ReferenceArgs evalArgs;
    CLI::App* evalCommand = app.add_subcommand(
        "eval", "Render DGI and the path-traced reference and write how close they are (JSON)");
    for (auto [command, args] :
         {std::pair{referenceCommand, &referenceArgs}, std::pair{evalCommand, &evalArgs}}) {
        const bool isEval = command == evalCommand;  // eval: a scene, or --suite
        command->add_option("scene", args->scene, "Scene file (JSON)")->required(!isEval);
        command
            ->add_option(isEval ? "--json" : "-o,--output", args->output,
                         isEval ? "Figures (JSON)" : "Output image: .png, .exr or .hdr")
            ->required(!isEval);
        command->add_option(
            "--aov", args->aovDir,
            isEval ? "Also write the images (DGI, reference, difference, with/without, pixel classes)"
                   : "Also write with, without, background, composite, object_mask, delta (.exr)");
        command->add_option("--spp", args->samplesPerPixel, "Samples per pixel (default 64)")
            ->check(CLI::Range(1, 1 << 20));
        command
            ->add_option("--time-limit", args->timeLimit,
                         "Stop after the first whole pass past this many seconds (default: none)")
            ->check(finiteNumber(0.0, false, "a number of seconds >= 0"));
        command->add_option("--seed", args->seed, "Random seed (default 0)");
        command
            ->add_option(
                "--max-bounces", args->maxBounces,
                "Surfaces a path may meet, the camera's first included: 1 is direct light only, 2 adds "
                "one bounce of indirect light (default: unlimited; Russian roulette ends paths)")
            ->check(CLI::Range(1, 256));
        command->add_option("--set", args->overrides, "Override a scene key: KEY=VALUE (repeatable)");
        command->add_option("--threads", args->threads, "Worker threads (default: all cores)")
            ->check(CLI::Range(1, kMaxThreads));
        command->add_flag("-q,--quiet", args->quiet, "Print nothing but errors");
    }
    evalCommand
        ->add_option("--reference", evalArgs.referenceDir,
                     "Judge against the reference images in this folder (written before by --aov of "
                     "`reference` or `eval`) instead of path tracing them")
        ->excludes("--spp")
        ->excludes("--time-limit")
        ->excludes("--seed")
        ->excludes("--max-bounces");
    cli::SuiteArgs suiteArgs;
    cli::addSuiteOptions(*evalCommand, suiteArgs);

    CompareArgs compareArgs;
    CLI::App* compareCommand = app.add_subcommand(
        "compare", "Compare an image with a reference: RMSE, relative MSE, mean absolute error");
    compareCommand->add_option("image", compareArgs.test, "The image to judge")->required();
    compareCommand->add_option("reference", compareArgs.reference, "The reference image")->required();
    compareCommand->add_option("-o,--output", compareArgs.difference,
                               "False-colour image of 2x the squared difference (like the paper's Fig. 3c)");
    compareCommand
        ->add_option("--max", compareArgs.maxValue,
                     "Full scale of the difference image (default: its 99th percentile)")
        ->check(finiteNumber(0.0, true, "a number > 0"));
    compareCommand->add_flag("--json", compareArgs.json, "Print JSON on stdout");

    cli::BenchArgs benchArgs;
    CLI::App* benchCommand = cli::addBenchCommand(app, benchArgs, kMaxThreads);
    cli::StabilityArgs stabilityArgs;
    CLI::App* stabilityCommand = cli::addStabilityCommand(app, stabilityArgs, kMaxThreads);

    cli::AlbedoArgs albedoArgs;
    CLI::App* albedoCommand = cli::addAlbedoCommand(app, albedoArgs, kMaxThreads);

    cli::EncodeArgs encodeArgs;
    CLI::App* encodeCommand = cli::addEncodeCommand(app, encodeArgs);

    cli::TrackArgs trackArgs;
    CLI::App* trackCommand = cli::addTrackCommand(app, trackArgs);

    cli::MarkerArgs markerArgs;
    CLI::App* markerCommand = cli::addMarkerCommand(app, markerArgs);

    cli::LiveArgs liveArgs;
    CLI::App* liveCommand = cli::addLiveCommand(app, liveArgs);

    cli::ServeArgs serveArgs;
    CLI::App* serveCommand = cli::addServeCommand(app, serveArgs, kMaxThreads);

    try {
        app.parse(argc, argv);
        renderArgs.fpsGiven = renderCommand->count("--fps") > 0;
    } catch (const CLI::ParseError& error) {
        if (error.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))
            return app.exit(error);  // --help
        if (app.get_subcommands().empty() && argc > 1 && argv[1][0] != '-')
            return reportError(
                fmt::format(
                    "unknown command '{}': expected 'render', 'info', 'reference', 'compare', 'eval', "
                    "'bench', 'stability', 'estimate-albedo', 'encode', 'marker', 'track', 'live' or 'serve' "
                    "(see deltagi --help)",
                    argv[1]),
                kExitUsageError);
        return reportError(fmt::format("{} (see deltagi --help)", error.what()), kExitUsageError);
    }

    try {
        if (*renderCommand) return runRender(renderArgs);
        if (*referenceCommand) return runReference(referenceArgs);
        if (*compareCommand) return runCompare(compareArgs);
        if (*evalCommand && !suiteArgs.suite.empty()) return cli::runSuite(*evalCommand, suiteArgs);
        if (*evalCommand && (evalArgs.scene.empty() || evalArgs.output.empty()))
            return reportError(
                "eval: expected SCENE.json and --json OUT.json, or --suite FILE (see deltagi --help)",
                kExitUsageError);
        if (*evalCommand) return runEval(evalArgs);
        if (*benchCommand) return cli::runBench(benchArgs);
        if (*stabilityCommand) return cli::runStability(stabilityArgs);
        if (*albedoCommand) return cli::runAlbedo(albedoArgs);
        if (*encodeCommand) return cli::runEncode(encodeArgs);
        if (*trackCommand) return cli::runTrack(trackArgs);
        if (*liveCommand) return cli::runLive(liveArgs);
        if (*markerCommand) return cli::runMarker(markerArgs);
        if (*serveCommand) return cli::runServe(serveArgs);
        if (*infoCommand && infoArgs.scene.empty() && !infoArgs.optionsMarkdown)
            return reportError("info: expected SCENE.json, or --options-markdown (see deltagi --help)",
                               kExitUsageError);
        return cli::runInfo(infoArgs);
    } catch (const std::exception& error) {  // InputError and everything else: one line
        removeTemporaryOutputs();            // output folders made for nothing
        return reportError(error.what(), kExitInputError);
    } catch (...) {
        removeTemporaryOutputs();
        return reportError("unexpected error", kExitInputError);
    }
}
