// Opening an image file for reading with OpenImageIO (image_io.cpp, scene/texture.cpp).
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include <OpenImageIO/imageio.h>

namespace deltagi {

// Opens `path` with the reader its extension names, and only that one: OpenImageIO's ImageInput::open() tries
// every format's reader when the file's own fails, which for a PNG with a damaged text chunk took 12 s (its
// DICOM reader among them). A file whose extension names no reader is tried with every reader, as
// OpenImageIO does. `config` as ImageInput::open()'s (may be null). Null when it cannot be opened, with
// OpenImageIO's message in `error`.
// A PNG file (`path`) is first checked by pngChunkError(): openImageInput gives its message instead.
std::unique_ptr<OIIO::ImageInput> openImageInput(const std::string& path, const OIIO::ImageSpec* config,
                                                 std::string& error);

// Whether a PNG's chunks fit in its bytes: each chunk's declared length against the bytes left after it.
// libpng allocates and clears what a text chunk declares before reading it: a 351-byte PNG whose chunk
// claimed 1.7 GB took 6 s of page faults per open. `bytes` are the whole file, or its first part with
// `fileSize` the whole's. The problem in words ("its 'tEXt' chunk claims ... bytes, but ... are left"), or
// nothing; not a PNG: nothing.
std::optional<std::string> pngChunkError(std::span<const std::byte> bytes, uint64_t fileSize);

}  // namespace deltagi
