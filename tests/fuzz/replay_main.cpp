// A main() for the fuzz targets in builds without libFuzzer (GCC, the sanitizer and TSan test
// builds): runs LLVMFuzzerTestOneInput once on each file given, so the regression inputs and
// seeds are checked by every build. Reads each file whole (regular files only, at most 64 MB).
#include <cstdint>
#include <cstdio>
#include <string>

#include "sim/base/file_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int*, char***);

int main(int argc, char** argv) {
  if (LLVMFuzzerInitialize) LLVMFuzzerInitialize(&argc, &argv);
  int ran = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string bytes = sb::readFileBounded(argv[i], 64ull << 20);
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    ++ran;
  }
  std::printf("replayed %d inputs\n", ran);
  return 0;
}
