#include "app/stats_file_writer.h"

#include <cstdio>
#include <utility>

#include "sim/base/file_io.h"

namespace sb::app {

StatsFileWriter::StatsFileWriter(std::string path)
    : path_(std::move(path)), thread_([this] { run(); }) {}

StatsFileWriter::~StatsFileWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

bool StatsFileWriter::post(nlohmann::json stats) {
  bool failed = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_ = std::move(stats);
    failed = failed_;
  }
  changed_.notify_all();  // also after a failure: finish() waits for this file to be tried
  return !failed;
}

bool StatsFileWriter::finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !waiting_ && !writing_; });
  return !failed_;
}

void StatsFileWriter::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return waiting_ || stopping_; });
    if (!waiting_) return;  // stopping, and nothing left to write
    const nlohmann::json stats = std::move(*waiting_);
    waiting_.reset();
    writing_ = true;
    lock.unlock();
    bool written = true;
    try {
      // Unsynced: rewritten every --stats-every frames; readers need it whole, not crash-proof.
      writeFileAtomic(
          path_, [&](std::ostream& out) { out << stats.dump(2) << "\n"; }, Durability::Unsynced);
    } catch (const FileError& e) {
      std::fprintf(stderr, "softbody: cannot write the stats file: %s\n", e.what());
      written = false;
    }
    lock.lock();
    writing_ = false;
    failed_ = failed_ || !written;
    changed_.notify_all();
  }
}

}  // namespace sb::app
