// A file's extension as the readers and writers choose by it.
#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace deltagi {

// ".png" for "photo.PNG"; empty without an extension.
inline std::string lowerExtension(const std::filesystem::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

}  // namespace deltagi
