// The viewer's --stats writer thread (app/stats_file_writer.h): a reader never sees part of a
// file or an older file after a newer one, the last file handed over is the one left on disk,
// and a write that fails is reported.
#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "app/stats_file_writer.h"

namespace sb::app {
namespace {

std::filesystem::path scratchFile(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("softbody_stats_writer_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir / name;
}

TEST(StatsFileWriter, ReadersSeeWholeFilesInOrderAndTheLastOneStays) {
  const std::filesystem::path path = scratchFile("stats.json");
  std::filesystem::remove(path);
  constexpr int kPosts = 300;
  std::atomic<bool> done{false};
  std::atomic<int> reads{0};
  int torn = 0, backwards = 0;
  std::thread reader([&] {
    long last = -1;
    while (!done) {
      std::ifstream in(path);
      if (in) {  // else not written yet
        std::stringstream text;
        text << in.rdbuf();
        const nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, false);
        if (j.is_discarded() || !j.contains("n")) {
          ++torn;
        } else {
          const long n = j["n"].get<long>();
          if (n < last) ++backwards;
          last = n;
        }
      }
      ++reads;
    }
  });
  {
    StatsFileWriter writer(path.string());
    for (int n = 0; n < kPosts; ++n) {
      // A few kilobytes each, like a real stats file.
      nlohmann::json stats = {{"n", n}, {"padding", std::string(4000, 'x')}};
      EXPECT_TRUE(writer.post(std::move(stats)));
      // One more read before the next file, so that reads and writes keep crossing whatever the
      // two threads' speeds.
      const int before = reads;
      while (reads <= before) std::this_thread::yield();
    }
    EXPECT_TRUE(writer.finish());
    done = true;
    reader.join();
  }
  std::ifstream in(path);
  const nlohmann::json last = nlohmann::json::parse(in);
  EXPECT_EQ(last["n"], kPosts - 1);
  EXPECT_GE(reads, kPosts);
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(backwards, 0);
  std::filesystem::remove_all(path.parent_path());
}

TEST(StatsFileWriter, AFailedWriteIsReported) {
  const std::filesystem::path path = scratchFile("no such folder") / "stats.json";
  StatsFileWriter writer(path.string());
  writer.post({{"n", 1}});  // may still report success: the write has not run yet
  EXPECT_FALSE(writer.finish());
  EXPECT_FALSE(writer.post({{"n", 2}}));  // a failure stays reported
  EXPECT_FALSE(writer.finish());
  EXPECT_FALSE(std::filesystem::exists(path));
  std::filesystem::remove_all(path.parent_path().parent_path());
}

}  // namespace
}  // namespace sb::app
