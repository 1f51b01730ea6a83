// Atomic writes leave either the old or the complete new file; bounded reads refuse what is not
// a regular file, and files over their bound.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "sim/base/file_io.h"
#include "tests/support/temp_dir_test.h"

namespace sb {
namespace {

namespace fs = std::filesystem;

class FileIo : public sb::test_support::TempDirTest {
 protected:
  // Files in the folder other than `keep` (a temporary file left behind would show up here).
  int othersThan(const std::string& keep) const {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir_))
      if (e.path().filename() != keep) ++n;
    return n;
  }
};

TEST_F(FileIo, AtomicWriteReplacesTheFileWhole) {
  const std::string p = path("a.txt");
  writeFileAtomic(p, [](std::ostream& out) { out << "first"; });
  EXPECT_EQ(contents(p), "first");
  writeFileAtomic(p, [](std::ostream& out) { out << "second, longer"; });
  EXPECT_EQ(contents(p), "second, longer");
  // Unsynced (the viewer's stats file) skips only the flush to the device: same replacement.
  writeFileAtomic(
      p, [](std::ostream& out) { out << "third"; }, Durability::Unsynced);
  EXPECT_EQ(contents(p), "third");
  EXPECT_EQ(othersThan("a.txt"), 0);
}

TEST_F(FileIo, AWriterThatFailsLeavesTheOldFileAndNoTemporary) {
  const std::string p = path("keep.txt");
  writeFileAtomic(p, [](std::ostream& out) { out << "precious"; });
  EXPECT_THROW(writeFileAtomic(p,
                               [](std::ostream& out) {
                                 out << "half";
                                 throw std::runtime_error("writer gave up");
                               }),
               std::runtime_error);
  EXPECT_EQ(contents(p), "precious");
  EXPECT_THROW(
      writeFileAtomic(
          p, [](std::ostream&) { throw std::runtime_error("gave up"); }, Durability::Unsynced),
      std::runtime_error);
  EXPECT_EQ(contents(p), "precious");
  EXPECT_EQ(othersThan("keep.txt"), 0);
}

TEST_F(FileIo, WritingIntoAMissingFolderNamesThePath) {
  const std::string p = path("no/such/folder/x.txt");
  try {
    writeFileAtomic(p, [](std::ostream& out) { out << "x"; });
    FAIL() << "wrote into a folder that does not exist";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

TEST_F(FileIo, BoundedReadReturnsTheBytes) {
  const std::string p = path("data.bin");
  const std::string bytes("a\0b\nc", 5);
  writeFileAtomic(p, [&](std::ostream& out) { out << bytes; });
  EXPECT_EQ(readFileBounded(p, 5), bytes);
}

TEST_F(FileIo, BoundedReadRefusesLargerFiles) {
  const std::string p = path("big.txt");
  writeFileAtomic(p, [](std::ostream& out) { out << std::string(1001, 'x'); });
  try {
    readFileBounded(p, 1000);
    FAIL() << "read a file over its bound";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("more than"), std::string::npos) << e.what();
  }
}

TEST_F(FileIo, BoundedReadRefusesFoldersFifosAndDevices) {
  auto refused = [](const std::string& p, const std::string& why) {
    try {
      readFileBounded(p, 1 << 20);
      ADD_FAILURE() << "read " << p;
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    }
  };
  refused(dir_.string(), "is a directory");
  const std::string fifo = path("pipe");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  refused(fifo, "not a regular file");  // returns at once: no writer is waited for
  refused("/dev/zero", "not a regular file");
  refused(path("missing.txt"), "no such file");
}

}  // namespace
}  // namespace sb
