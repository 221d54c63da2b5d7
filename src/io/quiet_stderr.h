// Silencing libpng's own error lines while OpenImageIO reads an image (image_io.cpp, texture.cpp).
#pragma once

#include <cstdio>
#include <mutex>

namespace deltagi {

// libpng's default error handler prints "libpng error: ..." on stderr before OpenImageIO reports the same
// error, which our message then carries: the user would see two lines. glibc lets a program assign stderr
// ("stdin, stdout, and stderr are normal variables", glibc manual 12.2), so while an image is read it points
// at /dev/null. Only the FILE is swapped: file descriptor 2 stays, and sanitizer reports still reach it.
// `stderr` is one global: images read on several threads at once (the frame feeds of `deltagi live`) take
// turns, holding stderrMutex() while it is swapped, and what prints on stderr meanwhile from another thread
// (cli/messages.h's note) waits for it rather than vanish.
inline std::recursive_mutex& stderrMutex() {
    static std::recursive_mutex mutex;
    return mutex;
}

class QuietStderr {
  public:
    QuietStderr() : lock_(stderrMutex()), saved_(stderr), null_(std::fopen("/dev/null", "w")) {
        if (null_ != nullptr) stderr = null_;
    }
    ~QuietStderr() {
        stderr = saved_;
        if (null_ != nullptr) std::fclose(null_);
    }
    QuietStderr(const QuietStderr&) = delete;
    QuietStderr& operator=(const QuietStderr&) = delete;

  private:
    std::lock_guard<std::recursive_mutex> lock_;
    FILE* saved_;
    FILE* null_;
};

}  // namespace deltagi
