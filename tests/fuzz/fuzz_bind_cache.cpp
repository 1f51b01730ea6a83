// libFuzzer target: the bind cache loader (Embedding::fromBytes). Inputs are re-sealed with the
// file checksum first, so mutations reach the header, index, weight and statistics checks
// behind it; what loads must deform a cage of its size to finite positions.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "sim/cage/embedding.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (bytes.size() >= 8) {
    bytes.resize(bytes.size() - 8);
    const std::uint64_t sum = sb::cage::weightFileChecksum(bytes);
    bytes.append(reinterpret_cast<const char*>(&sum), 8);
  }
  try {
    const sb::cage::Embedding e = sb::cage::Embedding::fromBytes(bytes, "fuzz");
    if (std::int64_t(e.meshVertexCount()) * e.cageVertexCount() > (1 << 22)) return 0;
    Eigen::Matrix<float, Eigen::Dynamic, 3> cage(e.cageVertexCount(), 3);
    cage.setOnes();
    sb::PointsRowMajor out;
    e.deform(cage, out);
    if (out.rows() != e.meshVertexCount()) std::abort();
  } catch (const std::runtime_error&) {
  }
  return 0;
}
