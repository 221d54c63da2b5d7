// `deltagi encode` (cli/encode_command.h).
#include "encode_command.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include <fmt/core.h>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "deltagi/scene_io.h"
#include "outputs.h"
#include "validators.h"

namespace fs = std::filesystem;

namespace deltagi::cli {

namespace {

constexpr size_t kMaxFrameDigits = 9;  // frame numbers fit an int

// The frame numbers of the files in the pattern's folder that the pattern names, in increasing order.
std::vector<int> framesFound(const FramePattern& pattern, const fs::path& shown) {
    const fs::path prefix(pattern.prefix);
    if (pattern.suffix.find('/') != std::string::npos)
        throw InputError(shown.string(), "the frame number's place must be in the file name, not a folder's");
    const std::string namePrefix = prefix.filename().string();
    const fs::path folder = prefix.parent_path().empty() ? fs::path(".") : prefix.parent_path();
    std::error_code error;
    if (!fs::is_directory(folder, error))
        throw InputError(shown.string(),
                         fmt::format("no folder '{}' to take the frames from", folder.string()));
    std::vector<int> found;
    for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= namePrefix.size() + pattern.suffix.size() || !name.starts_with(namePrefix) ||
            !name.ends_with(pattern.suffix))
            continue;
        const std::string number =
            name.substr(namePrefix.size(), name.size() - namePrefix.size() - pattern.suffix.size());
        const size_t digits = number.find_first_not_of(' ');
        if (digits == std::string::npos || number.size() - digits > kMaxFrameDigits ||
            number.find_first_not_of("0123456789", digits) != std::string::npos)
            continue;
        const int index = std::stoi(number.substr(digits));
        if (pattern.path(index).filename() == name) found.push_back(index);  // as the pattern writes it
    }
    if (error) throw InputError(folder.string(), "cannot list the folder: " + error.message());
    std::sort(found.begin(), found.end());
    return found;
}

}  // namespace

CLI::App* addEncodeCommand(CLI::App& app, EncodeArgs& args) {
    CLI::App* command = app.add_subcommand(
        "encode",
        "Encode frames written before (e.g. by chunks of `render --frames`) into an H.264 MP4, or into a Y4M "
        "(uncompressed: a fake camera for a browser)");
    command
        ->add_option("frames", args.frames,
                     "The frames' files, the number's place as #### or %04d (out/frame_####.png); PNG "
                     "(8-bit sRGB) or EXR/HDR (linear, encoded as PNGs are)")
        ->required();
    command->add_option("-o,--output", args.video, "The video (.mp4, or .y4m)")->required();
    command->add_option("--frames", args.range,
                        "The frames A:B (A included, B not); default: every frame found, which must be "
                        "consecutive");
    command->add_option("--fps", args.settings.fps, "Frames per second (default 30)")
        ->check(finiteRange(1e-3, kMaxFrameRate));
    command
        ->add_option("--crf", args.settings.crf,
                     "x264's constant rate factor, 0 (lossless) to 51 (default 18)")
        ->check(CLI::Range(0, kMaxCrf));
    command->add_flag("-q,--quiet", args.quiet, "Print nothing but errors");
    return command;
}

int runEncode(const EncodeArgs& args) {
    checkVideoPath(args.video, "encode");
    checkVideoEncoder(args.video, "encode");
    const FramePattern pattern = parseFramePattern(args.frames);
    std::vector<int> indices;
    if (!args.range.empty()) {
        const FrameRange range = parseFrameRange(args.range, "--frames");
        std::vector<int> found = framesFound(pattern, args.frames);
        const int last = range.last >= 0 ? range.last : (found.empty() ? range.first + 1 : found.back() + 1);
        for (int i = range.first; i < last; ++i) indices.push_back(i);
    } else {
        const std::vector<int> found = framesFound(pattern, args.frames);
        if (found.empty())
            throw InputError(args.frames.string(),
                             fmt::format("no frames found (files such as '{}')", pattern.path(0).string()));
        for (int i = found.front(); i <= found.back(); ++i) indices.push_back(i);
    }
    std::vector<RunInput> inputs;
    for (int i : indices) {
        const fs::path file = pattern.path(i);
        if (!fs::is_regular_file(file))
            throw InputError(file.string(), fmt::format("frame {} of {}:{} is missing", i, indices.front(),
                                                        indices.back() + 1));
        inputs.push_back({file, fmt::format("frame {}", i)});
    }
    checkOutputs({args.video}, inputs);

    const bool progress = !args.quiet && isatty(STDERR_FILENO);
    std::optional<VideoWriter> video;
    int width = 0, height = 0;
    for (size_t k = 0; k < inputs.size(); ++k) {
        if (video)  // by the header first: a frame of another size is not decoded
            if (const auto size = imageFileSize(inputs[k].path);
                size && (size->first != width || size->second != height))
                throw InputError(
                    inputs[k].path.string(),
                    fmt::format("is {}x{}, the first frame {}x{}: a video's frames have one size",
                                size->first, size->second, width, height));
        const Image image = readImage(inputs[k].path);
        if (!video) {
            width = image.width(), height = image.height();
            createOutputFolder(args.video.parent_path());
            video.emplace(args.video, width, height, args.settings);
        } else if (image.width() != width || image.height() != height) {
            throw InputError(inputs[k].path.string(),
                             fmt::format("is {}x{}, the first frame {}x{}: a video's frames have one size",
                                         image.width(), image.height(), width, height));
        }
        video->add(image);
        if (progress) fmt::print(stderr, "\rframe {}/{}   ", k + 1, inputs.size());
    }
    video->commit();
    if (progress) fmt::print(stderr, "\n");
    if (!args.quiet)
        fmt::print(stderr, "deltagi: wrote {} ({} frames {}:{}, {}x{}, {:.6g} frames/s{})\n",
                   args.video.string(), inputs.size(), indices.front(), indices.back() + 1, width, height,
                   args.settings.fps,
                   isY4m(args.video) ? ", uncompressed" : fmt::format(", CRF {}", args.settings.crf));
    return 0;
}

}  // namespace deltagi::cli
