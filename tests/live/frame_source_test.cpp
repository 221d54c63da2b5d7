// Frame sources (src/live/frame_source.h): cameras are opened through FFmpeg's device inputs, which
// libavdevice registers when it is loaded at the first camera (it is not linked).
#include "live/frame_source.h"

#include <gtest/gtest.h>

#include "test_errors.h"

namespace deltagi {
namespace {

TEST(FrameSource, OpensCamerasThroughFfmpegsDeviceInput) {
    // /dev/null is no camera: V4L2's own error, so the V4L2 input was there to try it.
    const std::string notACamera = test::inputErrorOf([] { openFrameSource("/dev/null"); });
    test::expectContains(notACamera, {"/dev/null", "cannot open"});
    EXPECT_EQ(notACamera.find("no V4L2 input"), std::string::npos) << notACamera;
    const std::string missing = test::inputErrorOf([] { openFrameSource("/dev/video-that-is-not-there"); });
    test::expectContains(missing, {"/dev/video-that-is-not-there", "cannot open"});
}

}  // namespace
}  // namespace deltagi
