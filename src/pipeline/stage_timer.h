// The frame's stage timings (RenderOutput::timings): each stage's wall time from the end of the one before,
// reported to a StageCallback as it ends.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "deltagi/renderer.h"

namespace deltagi {

class StageTimer {
  public:
    StageTimer(std::vector<StageTiming>& timings, const StageCallback& callback)
        : timings_(timings), callback_(callback), start_(Clock::now()) {}
    // Ends the current stage under `name` and starts the next one.
    void lap(std::string name) {
        const auto now = Clock::now();
        StageTiming t{std::move(name), std::chrono::duration<double, std::milli>(now - start_).count()};
        start_ = now;
        timings_.push_back(t);
        if (callback_) callback_(t);
    }

  private:
    using Clock = std::chrono::steady_clock;
    std::vector<StageTiming>& timings_;
    StageCallback callback_;
    Clock::time_point start_;
};

}  // namespace deltagi
