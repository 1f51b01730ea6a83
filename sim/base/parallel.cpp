#include "sim/base/parallel.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace sb {

namespace {

// How long a waiting thread spins before it sleeps: long enough to catch the next loop of a
// step (they follow each other within microseconds), short enough that a loaded machine loses
// little when the thread it waits for is not running.
constexpr auto kSpin = std::chrono::microseconds(50);

void relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

// Spins until done() or kSpin has passed; true when done.
template <typename Done>
bool spinUntil(const Done& done) {
  const auto until = std::chrono::steady_clock::now() + kSpin;
  for (int k = 0;; ++k) {
    if (done()) return true;
    relax();
    if ((k & 63) == 63 && std::chrono::steady_clock::now() > until) return done();
  }
}

thread_local bool tInsideChunk = false;

class Pool {
 public:
  ~Pool() { resize(1); }

  int size() const { return size_; }

  // Participants including the caller; joins or starts workers. Not while a loop runs.
  void resize(int threads) {
    if (threads < 1) threads = 1;
    if (threads == size_ && int(workers_.size()) == (started_ ? threads - 1 : 0)) return;
    {
      std::lock_guard<std::mutex> lock(m_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
    workers_.clear();
    stop_ = false;
    started_ = false;
    size_ = threads;
  }

  void run(int chunks, void (*fn)(void*, int), void* ctx) {
    bool expected = false;
    if (tInsideChunk || chunks <= 1 || !busy_.compare_exchange_strong(expected, true)) {
      for (int c = 0; c < chunks; ++c) fn(ctx, c);
      return;
    }
    if (!started_) start();
    fn_ = fn;
    ctx_ = ctx;
    chunks_ = chunks;
    remaining_.store(int(workers_.size()), std::memory_order_relaxed);
    {
      std::lock_guard<std::mutex> lock(m_);
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    tInsideChunk = true;
    fn(ctx, 0);
    tInsideChunk = false;
    if (!spinUntil([&] { return remaining_.load(std::memory_order_acquire) == 0; })) {
      std::unique_lock<std::mutex> lock(m_);
      done_.wait(lock, [&] { return remaining_.load(std::memory_order_acquire) == 0; });
    }
    busy_.store(false, std::memory_order_release);
  }

 private:
  void start() {
    // Each worker starts from the generation before the first job: a thread scheduled only
    // after that job was published still sees it as new.
    const std::uint64_t first = generation_.load(std::memory_order_relaxed);
    for (int w = 1; w < size_; ++w) workers_.emplace_back([this, w, first] { work(w, first); });
    started_ = true;
  }

  void work(int index, std::uint64_t seen) {
    for (;;) {
      if (!spinUntil([&] { return generation_.load(std::memory_order_acquire) != seen; })) {
        std::unique_lock<std::mutex> lock(m_);
        wake_.wait(lock,
                   [&] { return stop_ || generation_.load(std::memory_order_acquire) != seen; });
        if (stop_) return;
      }
      seen = generation_.load(std::memory_order_acquire);
      if (index < chunks_) {
        tInsideChunk = true;
        fn_(ctx_, index);
        tInsideChunk = false;
      }
      if (remaining_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        std::lock_guard<std::mutex> lock(m_);
        done_.notify_one();
      }
    }
  }

  int size_ = 1;
  bool started_ = false;
  std::vector<std::thread> workers_;
  std::mutex m_;
  std::condition_variable wake_, done_;
  bool stop_ = false;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<int> remaining_{0};
  std::atomic<bool> busy_{false};
  // Set by the caller before the generation is published (release), read by workers after
  // they see it (acquire).
  void (*fn_)(void*, int) = nullptr;
  void* ctx_ = nullptr;
  int chunks_ = 0;
};

int defaultThreads() {
  const unsigned n = std::thread::hardware_concurrency();
  return n > 0 ? int(n) : 1;
}

Pool& pool() {
  static Pool p;
  static const bool sized = (p.resize(defaultThreads()), true);
  (void)sized;
  return p;
}

}  // namespace

void setThreadCount(int threads) {
  pool().resize(threads > 0 ? threads : defaultThreads());
}

int threadCount() {
  return pool().size();
}

namespace detail {
void runChunks(int chunks, void (*fn)(void*, int), void* ctx) {
  pool().run(chunks, fn, ctx);
}
}  // namespace detail

}  // namespace sb
