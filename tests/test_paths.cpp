#include "test_paths.h"

namespace deltagi::test {

const char* const kSourceDir = DELTAGI_SOURCE_DIR;
const char* const kSharedDataDir = DELTAGI_SHARED_DATA_DIR;
const char* const kCli = DELTAGI_CLI;

}  // namespace deltagi::test
