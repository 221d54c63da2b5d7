// The OpenEXR decoder of image_codecs.h (exr_codec.cpp, apart for its include folders; encodeExr is declared
// in image_codecs.h).
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <string>

#include "io/image_codecs.h"

namespace deltagi {

// Read the header at once; ImageCodecError when the file is not a readable OpenEXR file.
std::unique_ptr<ImageDecoder> openExrFile(const std::string& path);
// `bytes` must outlive the decoder.
std::unique_ptr<ImageDecoder> openExrBytes(std::span<const std::byte> bytes);

}  // namespace deltagi
