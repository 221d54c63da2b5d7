// Where the tests find the project's files and the command line. Set by CMake for test_paths.cpp alone, so
// that no other test source depends on the checkout's or the build's folder (and each compiles to the same
// object in any clone, which ccache then finds).
#pragma once

namespace deltagi::test {

extern const char* const kSourceDir;      // the repository's root
extern const char* const kSharedDataDir;  // ../shared/data beside it (may be absent)
extern const char* const kCli;            // the deltagi command line built beside the tests

}  // namespace deltagi::test
