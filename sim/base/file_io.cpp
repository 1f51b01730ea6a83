#include "sim/base/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>

namespace sb {

namespace {

std::string errnoText() {
  return std::strerror(errno);
}

// Flushes a written file's data to the device, so a rename cannot expose an empty file after a
// crash. Best effort: file systems that cannot sync are not an error.
void syncFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

}  // namespace

AtomicFileWriter::AtomicFileWriter(std::string path, Durability durability)
    : path_(std::move(path)), durability_(durability) {
  static std::atomic<unsigned> counter{0};
  std::error_code ec;
  if (std::filesystem::is_directory(path_, ec))
    throw FileError(path_ + ": is a directory, not a file");
  tmp_ = path_ + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  out_.open(tmp_, std::ios::binary | std::ios::trunc);
  if (!out_)
    throw FileError(path_ + ": cannot create the temporary file " + tmp_ + ": " + errnoText());
}

AtomicFileWriter::~AtomicFileWriter() {
  if (committed_) return;
  out_.close();
  std::remove(tmp_.c_str());
}

void AtomicFileWriter::write(const void* data, std::size_t bytes) {
  out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  if (!out_) throw FileError(path_ + ": cannot write (disk full or I/O error)");
}

void AtomicFileWriter::commit() {
  out_.flush();
  if (!out_) throw FileError(path_ + ": cannot write (disk full or I/O error)");
  out_.close();
  if (!out_) throw FileError(path_ + ": cannot write (disk full or I/O error)");
  if (durability_ == Durability::Synced) syncFile(tmp_);
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0)
    throw FileError(path_ + ": cannot replace the file: " + errnoText());
  committed_ = true;
}

void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& write,
                     Durability durability) {
  AtomicFileWriter file(path, durability);
  write(file.stream());
  file.commit();
}

std::string readFileBounded(const std::string& path, std::uint64_t maxBytes) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused just below.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    if (err == ENOENT) throw FileError(path + ": cannot open the file: no such file");
    throw FileError(path + ": cannot open the file: " + std::strerror(err));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw FileError(path + ": cannot read the file: " + errnoText());
  if (S_ISDIR(st.st_mode)) throw FileError(path + ": is a directory, not a file");
  if (!S_ISREG(st.st_mode))
    throw FileError(path + ": is not a regular file (a FIFO, socket or device); refused");
  if (std::uint64_t(st.st_size) > maxBytes)
    throw FileError(path + ": the file is " + formatBytes(std::uint64_t(st.st_size)) +
                    ", more than the " + formatBytes(maxBytes) + " this reader accepts");
  // Back to blocking reads for a regular file (O_NONBLOCK has no effect on them anyway).
  std::string data;
  data.resize(size_t(st.st_size));
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::read(fd, data.data() + done, data.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw FileError(path + ": cannot read the file: " + errnoText());
    }
    if (n == 0) break;  // shrank while reading
    done += size_t(n);
  }
  data.resize(done);
  // A file that grew while being read is cut at the size it had: a bounded read.
  return data;
}

std::string formatBytes(std::uint64_t bytes) {
  const char* units[] = {"bytes", "KB", "MB", "GB", "TB"};
  double v = double(bytes);
  int u = 0;
  while (v >= 1000.0 && u < 4) {
    v /= 1000.0;
    ++u;
  }
  char buf[48];
  if (u == 0)
    std::snprintf(buf, sizeof buf, "%llu bytes", static_cast<unsigned long long>(bytes));
  else
    std::snprintf(buf, sizeof buf, "%.1f %s", v, units[u]);
  return buf;
}

}  // namespace sb
