// Test image files written with libpng and OpenEXR directly (test_image_files.h). A library of its own
// (tests/CMakeLists.txt): only this file needs OpenEXR's include folders.
#include "test_image_files.h"

#include <csetjmp>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <png.h>

namespace deltagi::test {

namespace {

void pngError(png_structp png, png_const_charp) {
    std::longjmp(png_jmpbuf(png), 1);
}

// libpng's calls, with no object to destroy between setjmp() and the longjmp() of an error.
bool writePngRows(png_structp png, png_infop info, std::FILE* file, png_bytepp rows, int width, int height,
                  int colorType) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, file);
    png_set_IHDR(png, info, width, height, 16, colorType, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_set_swap(png);  // the samples are in the machine's (little-endian) order; PNG's are big-endian
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    return true;
}

}  // namespace

void writePng16(const std::filesystem::path& path, std::span<const uint16_t> samples, int width, int height,
                int channels) {
    static constexpr int kColorTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                          PNG_COLOR_TYPE_RGB_ALPHA};
    if (channels < 1 || channels > 4 || samples.size() != static_cast<size_t>(width) * height * channels)
        throw std::invalid_argument("writePng16: samples and size disagree");
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"), std::fclose);
    if (!file) throw std::runtime_error("writePng16: cannot create " + path.string());
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, pngError, nullptr);
    png_infop info = png_create_info_struct(png);
    std::vector<png_bytep> rows(height);
    for (int y = 0; y < height; ++y)
        rows[y] = reinterpret_cast<png_bytep>(const_cast<uint16_t*>(samples.data()) +
                                              static_cast<size_t>(y) * width * channels);
    const bool ok =
        writePngRows(png, info, file.get(), rows.data(), width, height, kColorTypes[channels - 1]);
    png_destroy_write_struct(&png, &info);
    if (!ok) throw std::runtime_error("writePng16: libpng failed on " + path.string());
}

void writeExrInWindow(const std::filesystem::path& path, std::span<const float> rgb, int width, int height,
                      int dataX, int dataY, int fullWidth, int fullHeight) {
    const Imath::Box2i display({0, 0}, {fullWidth - 1, fullHeight - 1});
    const Imath::Box2i data({dataX, dataY}, {dataX + width - 1, dataY + height - 1});
    Imf::Header header(display, data);
    Imf::FrameBuffer frame;
    const char* names[] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        frame.insert(names[c], Imf::Slice::Make(Imf::FLOAT, rgb.data() + c, data, 3 * sizeof(float),
                                                3 * sizeof(float) * width));
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(height);
}

}  // namespace deltagi::test
