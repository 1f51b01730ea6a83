#include "sim/scene/point_cache.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace sb {

namespace {

// Byte order is spelled out, not taken from the machine: PC2 is little-endian and MDD
// big-endian on every platform.
void put32(char* at, std::uint32_t v, bool bigEndian) {
  for (int i = 0; i < 4; ++i) {
    const int shift = bigEndian ? 8 * (3 - i) : 8 * i;
    at[i] = static_cast<char>((v >> shift) & 0xffu);
  }
}
std::uint32_t bitsOf(float f) {
  std::uint32_t v;
  std::memcpy(&v, &f, 4);
  return v;
}

// The path, once the layout is known to be valid: checked before the file is created.
const std::string& checkedPath(const std::string& path, int pointCount, int frameCount,
                               double startTime, double frameInterval) {
  if (pointCount < 1 || frameCount < 1 || !std::isfinite(startTime) ||
      !std::isfinite(frameInterval) || frameInterval <= 0)
    throw std::invalid_argument(path +
                                ": a point cache needs ≥ 1 point, ≥ 1 frame, a finite start "
                                "time and a finite frame interval > 0");
  return path;
}

}  // namespace

PointCacheWriter::PointCacheWriter(const std::string& path, PointCacheFormat format, int pointCount,
                                   int frameCount, double startTime, double frameInterval)
    : file_(checkedPath(path, pointCount, frameCount, startTime, frameInterval)),
      format_(format),
      pointCount_(pointCount),
      frameCount_(frameCount) {
  buffer_.resize(size_t(pointCount) * 12);
  if (format == PointCacheFormat::Pc2) {
    char header[32];
    std::memcpy(header, "POINTCACHE2\0", 12);
    put32(header + 12, 1, false);
    put32(header + 16, std::uint32_t(pointCount), false);
    put32(header + 20, bitsOf(float(startTime / frameInterval)), false);
    put32(header + 24, bitsOf(1.0f), false);
    put32(header + 28, std::uint32_t(frameCount), false);
    file_.write(header, sizeof header);
  } else {
    std::vector<char> header(8 + 4 * size_t(frameCount));
    put32(header.data(), std::uint32_t(frameCount), true);
    put32(header.data() + 4, std::uint32_t(pointCount), true);
    for (int k = 0; k < frameCount; ++k)
      put32(header.data() + 8 + 4 * size_t(k), bitsOf(float(startTime + k * frameInterval)), true);
    file_.write(header.data(), header.size());
  }
}

void PointCacheWriter::addFrame(const std::vector<PointsRowMajor>& parts) {
  long long rows = 0;
  for (const PointsRowMajor& p : parts) rows += p.rows();
  if (rows != pointCount_)
    throw std::invalid_argument(file_.path() + ": a frame of " + std::to_string(rows) +
                                " points for a cache of " + std::to_string(pointCount_));
  if (written_ == frameCount_)
    throw std::logic_error(file_.path() + ": more frames than the " + std::to_string(frameCount_) +
                           " declared");
  const bool bigEndian = format_ == PointCacheFormat::Mdd;
  char* at = buffer_.data();
  for (const PointsRowMajor& p : parts) {
    const float* x = p.data();
    for (Eigen::Index i = 0; i < 3 * p.rows(); ++i, at += 4) put32(at, bitsOf(x[i]), bigEndian);
  }
  file_.write(buffer_.data(), buffer_.size());
  ++written_;
}

void PointCacheWriter::finish() {
  if (written_ != frameCount_)
    throw std::logic_error(file_.path() + ": " + std::to_string(written_) + " frames of the " +
                           std::to_string(frameCount_) + " declared were written");
  file_.commit();
}

}  // namespace sb
