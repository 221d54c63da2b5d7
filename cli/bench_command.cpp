#include "bench_command.h"

#include <unistd.h>

#include <cstdio>
#include <optional>

#include <fmt/core.h>
#include <tbb/global_control.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "outputs.h"
#include "validators.h"

namespace deltagi::cli {

CLI::App* addBenchCommand(CLI::App& app, BenchArgs& args, int maxThreads) {
    CLI::App* command = app.add_subcommand(
        "bench",
        "Time the pipeline's stages over frames in which the virtual objects move, or over a scene's tracked "
        "sequence (the paper's Table 1)");
    command->add_option("scene", args.scene, "Scene file (JSON)")->required();
    command
        ->add_option(
            "--frames", args.options.frames,
            "Measured frames (default 10); a \"sequence\" is played from its first frame again after "
            "its last")
        ->check(CLI::Range(1, 100000));
    command->add_option("--warmup", args.options.warmup, "Frames rendered before measuring (default 2)")
        ->check(CLI::Range(0, 100000));
    command->add_flag("--cold", args.options.cold,
                      "Rebuild everything every frame, the static reconstruction's voxels, RSMs and BVH too");
    args.motionOption =
        command
            ->add_option(
                "--motion", args.options.motionVoxels,
                "Radius of the objects' circular motion in voxels (default 1; 0 keeps them still; not "
                "with a sequence, whose objects follow their keyframes)")
            ->check(finiteRange(0.0, 1000.0));
    command
        ->add_option("--camera-motion", args.options.cameraDegrees,
                     "Move the camera too: swing it up to DEG degrees either way about the objects' centre "
                     "(default 0: still); each pose's photo is rendered first, untimed")
        ->check(finiteRange(0.0, 90.0));
    command->add_flag(
        "--live", args.options.live,
        "The live frame: the real light changes every frame too (point and spot lights move, "
        "directional ones swing, an environment map turns), and the camera swings (--camera-motion, "
        "default 5 then); each frame over its photo");
    command->add_option("--json", args.json, "Also write the figures as JSON here");
    command->add_option("--set", args.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    command->add_option("--threads", args.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, maxThreads));
    command->add_flag("-q,--quiet", args.quiet, "Print only the table");
    return command;
}

int runBench(const BenchArgs& args) {
    std::optional<tbb::global_control> threadLimit;
    if (args.threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, args.threads);
    // A bad JSON path fails before the frames are rendered; the file is written only at the end, whole, so
    // a failed or interrupted run leaves the previous figures in it.
    const bool json = !args.json.empty();
    if (json) {
        const std::filesystem::path folder = args.json.parent_path();
        if (!folder.empty() && !std::filesystem::is_directory(folder))
            throw InputError(args.json.string(),
                             fmt::format("cannot write file: folder '{}' does not exist", folder.string()));
        checkOutputs({args.json}, {{args.scene, "the scene file"}});
    }
    Scene scene = loadScene(args.scene, args.overrides);
    if (json) refuseInputs({args.json}, sceneInputs(scene));
    if (!scene.sequence.empty() && args.motionOption && args.motionOption->count() > 0)
        throw InputError(
            "--motion", "not with a \"sequence\": its objects move as their keyframes say (none: they stay)");
    if (scene.virtuals.empty() && scene.sequence.empty())
        throw InputError(args.scene.string(),
                         "virtual: the benchmark needs at least one virtual object to move");

    const bool progress = !args.quiet && isatty(STDERR_FILENO);
    const BenchResult result = runBenchmark(scene, args.options, [&](int frame, double ms) {
        if (progress) fmt::print(stderr, "  frame {:>4}  {:>9.1f} ms\n", frame, ms);
    });
    fmt::print("{}", benchTable(result));
    std::fflush(stdout);
    if (json) writeJson(benchToJson(result), args.json);
    return 0;
}

}  // namespace deltagi::cli
