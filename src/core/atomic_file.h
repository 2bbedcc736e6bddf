// Every file Telescope writes goes through here: the bytes go to a temporary file next to the
// target (".NAME.partial-PID.EXT", same directory, so the rename cannot cross file systems),
// are flushed to the disk, and the temporary file is renamed over the target. A reader, a
// crash, `kill -9` or a full disk never leaves a half-written file under the target's name; a
// failed write removes the temporary file and throws std::runtime_error naming the target and
// the reason (for example "No space left on device").
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace telescope {

// The temporary name used for `path` by this process.
std::string temporaryPathFor(const std::string& path);

// `write(tmp)` creates the file at `tmp` (for libraries that open files by name: OpenEXR,
// libpng) and throws on failure.
void writeFileAtomically(const std::string& path, const std::function<void(const std::string& tmp)>& write);

// `write(out)` writes to a binary stream; stream failures are detected after it returns.
void writeStreamAtomically(const std::string& path, const std::function<void(std::ostream& out)>& write);

void writeTextAtomically(const std::string& path, const std::string& text);

}  // namespace telescope
