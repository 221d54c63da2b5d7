// Errors raised for bad input: files, JSON, meshes, images, options.
//
// Following Falcor's three tiers: programmer mistakes are asserts, bad input raises InputError (carrying
// where it was: a file and, for scene files, the JSON path of the key), and expected failures return codes.
// The CLI turns an InputError into one line on stderr and a non-zero exit.
#pragma once

#include <stdexcept>
#include <string>

#include "deltagi/export.h"

DELTAGI_API_BEGIN
namespace deltagi {

class InputError : public std::runtime_error {
  public:
    // `where` names the file and/or key, e.g. "scenes/box.json: options.volume.resolution".
    InputError(std::string where, const std::string& what)
        : std::runtime_error(where.empty() ? what : where + ": " + what),
          where_(std::move(where)),
          message_(what) {}
    const std::string& where() const { return where_; }
    // What was expected, without `where` (for callers that name the place again, further out).
    const std::string& message() const { return message_; }

  private:
    std::string where_;
    std::string message_;
};

}  // namespace deltagi
DELTAGI_API_END
