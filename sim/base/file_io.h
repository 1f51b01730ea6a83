// Reading and writing whole files safely: the one place that knows how (every reader and writer
// of the project goes through here).
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>

namespace sb {

// what() = "PATH: reason".
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes a file atomically: `write` fills a temporary file in the same folder
// (PATH.tmp.<pid>.<n>), which is flushed to disk and then renamed over PATH. Readers see the old
// file or the complete new one, never a part; on any failure the temporary file is removed, PATH
// is untouched and FileError says why. `write` may throw; the exception is passed on after the
// clean-up.
void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& write);

// Reads a whole regular file of at most maxBytes bytes. Refuses, with FileError, what is not a
// regular file (a folder, FIFO, device such as /dev/zero: none of them can block or stream
// without end here), a file that cannot be opened, and a file larger than maxBytes.
std::string readFileBounded(const std::string& path, std::uint64_t maxBytes);

// Bytes in a human-readable unit ("12.5 MB"), for messages.
std::string formatBytes(std::uint64_t bytes);

}  // namespace sb
