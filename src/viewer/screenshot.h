// The window's pixels as an 8-bit RGB PNG (written to a temporary name and renamed).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace telescope::viewer {

void writeScreenshotPng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba);

}  // namespace telescope::viewer
