// Checks of the command line's numbers. CLI11's Range and NonNegativeNumber take "nan" (every comparison with
// NaN is false) and print their bounds as doubles in full; these refuse what is not a finite number and name
// what is expected.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace deltagi::cli {

// A finite number, at least `lo` (above it when `open`); the message says `what` is expected.
CLI::Validator finiteNumber(double lo, bool open, const std::string& what);

// A finite number in [lo, hi].
CLI::Validator finiteRange(double lo, double hi);

}  // namespace deltagi::cli
