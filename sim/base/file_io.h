// Reading and writing whole files safely: the one place that knows how (every reader and writer
// of the project goes through here).
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
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

// Whether a finished file is flushed to the device before it is renamed over PATH. Synced: a
// crash right after cannot leave an empty PATH (saved scenes, exports). Unsynced: still atomic for
// readers, but not crash-proof; for files rewritten every frame (the viewer's --stats file, where
// the fsync cost 0.3–0.6 ms of every write on the 2-core VM's ext4 disk).
enum class Durability { Synced, Unsynced };

// Writes a file atomically: `write` fills a temporary file in the same folder
// (PATH.tmp.<pid>.<n>), which is flushed to disk (unless Unsynced) and then renamed over PATH.
// Readers see the old file or the complete new one, never a part; on any failure the temporary file
// is removed, PATH is untouched and FileError says why. `write` may throw; the exception is passed
// on after the clean-up.
void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& write,
                     Durability durability = Durability::Synced);

// The same for a file written in parts over time (a point cache filled frame by frame): the
// bytes go to the temporary file, which commit() flushes and renames over PATH. Until then PATH
// is untouched; a writer destroyed without a successful commit() removes the temporary file, so
// an interrupted export leaves nothing behind. Throws FileError naming PATH, at once when PATH
// is a folder (not after a long export).
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::string path, Durability durability = Durability::Synced);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  // The temporary file, opened binary; seekable (a header may be patched at the end).
  std::ostream& stream() { return out_; }
  // Appends bytes to it; FileError (disk full, I/O error) names PATH.
  void write(const void* data, std::size_t bytes);
  // Checks the stream, flushes the data to the device and renames the file over PATH.
  void commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  Durability durability_;
  std::string tmp_;
  std::ofstream out_;
  bool committed_ = false;
};

// Reads a whole regular file of at most maxBytes bytes. Refuses, with FileError, what is not a
// regular file (a folder, FIFO, device such as /dev/zero: none of them can block or stream
// without end here), a file that cannot be opened, and a file larger than maxBytes.
std::string readFileBounded(const std::string& path, std::uint64_t maxBytes);

// Bytes in a human-readable unit ("12.5 MB"), for messages.
std::string formatBytes(std::uint64_t bytes);

}  // namespace sb
