// Image files written for tests with the libraries directly, in forms deltagi's own writers do not make
// (16-bit PNG, an OpenEXR data window inside a larger display window).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

namespace deltagi::test {

// A 16-bit PNG of `channels` (1 to 4) interleaved samples. Fails the calling test's ASSERTs on error
// (throws).
void writePng16(const std::filesystem::path& path, std::span<const uint16_t> samples, int width, int height,
                int channels);

// An 8-bit palette PNG: `indices` (width * height) into `palette` (RGB triples), with the palette entries
// alphas `alphas` (a tRNS chunk; may be empty or shorter than the palette: the rest are opaque).
void writePngPalette(const std::filesystem::path& path, std::span<const uint8_t> indices, int width,
                     int height, std::span<const uint8_t> palette, std::span<const uint8_t> alphas);

// An OpenEXR file of RGB float pixels whose data window (`width` x `height` at (dataX, dataY)) lies within a
// display window of `fullWidth` x `fullHeight` at (0, 0).
void writeExrInWindow(const std::filesystem::path& path, std::span<const float> rgb, int width, int height,
                      int dataX, int dataY, int fullWidth, int fullHeight);

}  // namespace deltagi::test
