#include "stability_command.h"

#include <cstdio>
#include <optional>

#include <fmt/core.h>
#include <tbb/global_control.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "outputs.h"
#include "validators.h"

namespace deltagi::cli {

CLI::App* addStabilityCommand(CLI::App& app, StabilityArgs& args, int maxThreads) {
    CLI::App* command = app.add_subcommand(
        "stability",
        "Measure flicker: render frames in which the objects (and the camera) move steadily, or a scene's "
        "tracked sequence, and report "
        "temporal_instability = RMS(D[t+1] - 2 D[t] + D[t-1]) / RMS((D[t+1] - D[t-1]) / 2)");
    command->add_option("scene", args.scene, "Scene file (JSON)")->required();
    args.framesOption =
        command
            ->add_option("--frames", args.motion.frames,
                         "Frames to measure (default 8; with a \"sequence\", its frames, the first N of them "
                         "with --frames N); options.render.temporal_frames - 1 frames are rendered before "
                         "them, the motion continued backwards (a sequence's: those before it in the file), "
                         "as in a running session")
            ->check(CLI::Range(3, 10000));
    args.motionOptions.push_back(
        command
            ->add_option("--object-step", args.motion.objectStepVoxels,
                         "How far the objects move each frame, in voxels of the volume (default 0.25)")
            ->check(finiteRange(0.0, 1000.0)));
    args.motionOptions.push_back(command
                                     ->add_option("--direction", args.direction,
                                                  "Direction of the objects' motion X,Y,Z (default 1,0,0)")
                                     ->delimiter(',')
                                     ->expected(3)
                                     ->check(finiteRange(-1e6, 1e6)));
    args.motionOptions.push_back(
        command
            ->add_option(
                "--camera-step", args.motion.cameraStepDeg,
                "Degrees the camera turns each frame about the objects' centre (default 0); the measure then "
                "follows the surface points from frame to frame instead of fixed pixels")
            ->check(finiteRange(-45.0, 45.0)));
    command->add_option("--json", args.json, "Also write the figures as JSON here");
    command->add_option("--set", args.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    command->add_option("--threads", args.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, maxThreads));
    return command;
}

int runStability(StabilityArgs args) {
    std::optional<tbb::global_control> threadLimit;
    if (args.threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, args.threads);
    if (!args.direction.empty())
        args.motion.objectDirection = {args.direction[0], args.direction[1], args.direction[2]};
    if (!args.json.empty()) checkOutputs({args.json}, {{args.scene, "the scene file"}});
    Scene scene = loadScene(args.scene, args.overrides);
    if (!args.json.empty()) refuseInputs({args.json}, sceneInputs(scene));
    if (scene.virtuals.empty())
        throw InputError(args.scene.string(),
                         "virtual: the objects' motion needs at least one virtual object");
    const bool sequence = !scene.sequence.empty();
    if (sequence)
        for (const CLI::Option* option : args.motionOptions)
            if (option && option->count() > 0)
                throw InputError(option->get_name(),
                                 "not with a \"sequence\": its frames move the camera and the keyframed "
                                 "objects as the transforms file and the keyframes say");
    const MotionFrames motion =
        sequence ? renderSequence(
                       scene, args.framesOption && args.framesOption->count() > 0 ? args.motion.frames : 0)
                 : renderMotion(scene, args.motion);
    const TemporalFigures figures = temporalInstability(motion);
    if (sequence)
        fmt::print("{} frames {}:{} of {}, {}x{}, camera and objects as tracked and keyframed\n",
                   motion.frames.size(), motion.indices.front(), motion.indices.back() + 1,
                   scene.sequenceFile.string(), scene.camera.width, scene.camera.height);
    else
        fmt::print("{} frames of {}x{}, objects moving {} voxels a frame, camera turning {} deg a frame\n",
                   motion.frames.size(), scene.camera.width, scene.camera.height,
                   args.motion.objectStepVoxels, args.motion.cameraStepDeg);
    if (figures.followsSurfaces)
        fmt::print("following the surface points from frame to frame (the camera moves)\n");
    fmt::print("temporal_instability real pixels (delta):      {:.3f} ({} pixel-triples)\n",
               figures.realInstability, figures.realSamples);
    fmt::print("temporal_instability object pixels (composite): {:.3f} ({} pixel-triples)\n",
               figures.objectInstability, figures.objectSamples);
    std::string means;
    for (double m : figures.meanDelta) means += fmt::format(" {:.6f}", m);
    fmt::print("mean delta per frame:{}\n", means);
    std::fflush(stdout);
    if (!args.json.empty()) writeJson(temporalToJson(figures), args.json);
    return 0;
}

}  // namespace deltagi::cli
