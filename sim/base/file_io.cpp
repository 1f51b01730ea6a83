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

void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& write) {
  static std::atomic<unsigned> counter{0};
  const std::string tmp =
      path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  try {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw FileError(path + ": cannot create the temporary file " + tmp + ": " + errnoText());
    write(out);
    out.flush();
    if (!out) throw FileError(path + ": cannot write (disk full or I/O error)");
    out.close();
    if (!out) throw FileError(path + ": cannot write (disk full or I/O error)");
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  syncFile(tmp);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = errnoText();
    std::remove(tmp.c_str());
    throw FileError(path + ": cannot replace the file: " + why);
  }
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
