// What the command line tells the user on stderr, shared by its commands: progress notes, one-line messages
// and a scene's loader warnings.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <fmt/core.h>

#include "deltagi/scene.h"

namespace deltagi::cli {

// Progress and errors go to stderr; stdout holds only what `info` was asked for.
template <typename... Args>
void note(fmt::format_string<Args...> format, Args&&... args) {
    fmt::print(stderr, format, std::forward<Args>(args)...);
    std::fflush(stderr);
}

// One line, whatever the message holds: the lines of a multi-line message are joined with "; ", and a line
// longer than 1000 characters (a message that quotes a huge value from the input) is cut.
std::string oneLine(const std::string& message);

// Loads a scene and prints what the loader accepted with a warning (always: a warning matters even with
// --quiet). `frames` (a --frames A:B, empty: none) takes those frames of the scene's "sequence" in place of
// the scene file's own range: only their photos are read and checked. InputError naming `framesOption` when
// the scene has no sequence or the range is malformed.
Scene loadAndWarn(const std::filesystem::path& file, const std::vector<std::string>& overrides,
                  const std::string& frames = {}, const std::string& framesOption = "--frames");

// For the commands that take one image of a scene: with a "sequence", says (always) that its first frame is
// the one taken, and how to pick another.
void noteFirstFrame(const Scene& scene, const char* command);

// "1 mesh", "2 meshes".
std::string plural(size_t count, const char* one, const char* many);

}  // namespace deltagi::cli
