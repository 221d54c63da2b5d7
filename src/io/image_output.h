// Images written into an AtomicFile's temporary, closed but not renamed into place: for callers that commit
// several outputs together (a failure before then replaces none of them). writeImage and writeLayers of
// deltagi/image.h, which name a path, commit at once.
#pragma once

#include <span>

#include "deltagi/image.h"
#include "io/atomic_file.h"

namespace deltagi {

void writeImage(const Image& image, AtomicFile& file);
// The layers into one EXR (see deltagi/image.h's writeLayers).
void writeLayers(std::span<const ImageLayer> layers, AtomicFile& file);

}  // namespace deltagi
