// Files the studies (`converge`, `study transmittance`) write.
#pragma once

#include <string>

namespace telescope {

// Writes PATH.partial, then renames it over PATH: a reader never sees half a file. Throws
// std::runtime_error when the write fails.
void writeTextAtomically(const std::string& path, const std::string& text);

}  // namespace telescope
