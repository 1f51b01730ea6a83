// The --stats file written on a thread of its own: the frame hands over the JSON and goes on.
// One slot, latest wins: a file handed over while an older one waits replaces it, so a slow disk
// never holds frames back and the file on disk only moves forward in time. Each write is atomic
// (temporary file and rename), so a reader never sees part of a file.
#pragma once

#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

namespace sb::app {

class StatsFileWriter {
 public:
  explicit StatsFileWriter(std::string path);
  ~StatsFileWriter();  // writes what is still waiting, then stops the thread
  StatsFileWriter(const StatsFileWriter&) = delete;
  StatsFileWriter& operator=(const StatsFileWriter&) = delete;

  // Queues `stats` to be written. Returns false if a write has failed so far (the reason went to
  // stderr).
  bool post(nlohmann::json stats);
  // Waits until everything posted is on disk; false if a write has failed so far.
  bool finish();

 private:
  void run();

  const std::string path_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::optional<nlohmann::json> waiting_;
  bool writing_ = false, stopping_ = false, failed_ = false;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace sb::app
