// The light camera (the paper's Fig. 2: a fish-eye camera that records the real light): each of its frames
// becomes the scene's environment through the scene file's "environment" (its projection, e.g. "fisheye"
// with the image circle; its rotation; its intensity, which for an 8-bit camera is the exposure that turns
// the decoded sRGB values into radiance), averaged with the frames before it over a time constant, so that a
// steady light gives steady frames and a change is followed within about half a second.
//
// An 8-bit camera clips what is brighter than its white: a sun or a bare lamp in view records as white, far
// dimmer than it is, and lights the scene too weakly (docs/live.md says what to do about it).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/environment.h"
#include "deltagi/environment.h"
#include "deltagi/image.h"

namespace deltagi {

class LightCamera {
  public:
    // Reads the scene file's "environment" (with the command line's overrides); InputError when there is
    // none.
    LightCamera(const std::filesystem::path& sceneFile, const std::vector<std::string>& overrides,
                double timeConstantSeconds = 0.15);

    // The environment for a frame taken at `timeSeconds` (increasing; a frame that is not later starts the
    // average afresh). Pixels that are not finite and >= 0 count as 0. InputError naming `frameName` for a
    // frame the projection cannot take.
    Environment environment(Image frame, double timeSeconds, const std::string& frameName);
    // The share of the last frame's pixels with a channel at 1 or more: at an 8-bit camera's white, clipped.
    double clippedShare() const { return clippedShare_; }

  private:
    std::string file_;
    nlohmann::json document_;
    double timeConstant_;
    std::optional<EquirectConversion> conversion_;  // the projection's, for frames of its size
    Image smoothed_;
    double lastTime_ = 0.0;
    double clippedShare_ = 0.0;
};

}  // namespace deltagi
