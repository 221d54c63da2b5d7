// Checks of the command line's numbers (cli/validators.h).
#include "validators.h"

#include <cmath>
#include <optional>

#include <fmt/format.h>

namespace deltagi::cli {

namespace {

// The whole text as a finite number; nothing otherwise.
std::optional<double> finiteValue(const std::string& text) {
    size_t used = 0;
    double value = 0.0;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {
        return std::nullopt;
    }
    if (used == 0 || used != text.size() || !std::isfinite(value)) return std::nullopt;
    return value;
}

}  // namespace

CLI::Validator finiteNumber(double lo, bool open, const std::string& what) {
    return CLI::Validator(
        [=](std::string& text) -> std::string {
            const std::optional<double> value = finiteValue(text);
            if (!value || (open ? *value <= lo : *value < lo))
                return fmt::format("expected {}, got '{}'", what, text);
            return {};
        },
        what);
}

CLI::Validator finiteRange(double lo, double hi) {
    const std::string what = fmt::format("a number in [{:g}, {:g}]", lo, hi);
    return CLI::Validator(
        [=](std::string& text) -> std::string {
            const std::optional<double> value = finiteValue(text);
            if (!value || *value < lo || *value > hi) return fmt::format("expected {}, got '{}'", what, text);
            return {};
        },
        what);
}

}  // namespace deltagi::cli
