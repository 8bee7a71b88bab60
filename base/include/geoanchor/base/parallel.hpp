#pragma once
// Work split over threads with results that do not depend on how many
// (the solver's assembly and statistics, the adjust outputs' formatting). `for_chunks` cuts [0, count) into chunks of a fixed
// size, whatever the number of threads, and runs `work(begin, end)` on each,
// the chunks shared out among `jobs` threads (the caller's included). Each
// chunk must write only its own results; whatever is summed across chunks
// is summed afterwards by the caller, in chunk order. The first exception
// (by chunk order) is rethrown once every thread has stopped.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace geoanchor {

// Threads for `jobs` = 0: the machine's cores.
inline int resolve_jobs(int jobs) {
  if (jobs > 0) return jobs;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

template <typename Work>
void for_chunks(std::size_t count, std::size_t chunk, int jobs, const Work& work) {
  if (count == 0) return;
  const std::size_t chunks = (count + chunk - 1) / chunk;
  const std::size_t threads = std::min<std::size_t>(static_cast<std::size_t>(std::max(1, jobs)), chunks);
  std::vector<std::exception_ptr> errors(chunks);
  std::atomic<std::size_t> next{0};
  const auto run = [&] {
    for (std::size_t c = next++; c < chunks; c = next++) {
      try {
        work(c * chunk, std::min(count, (c + 1) * chunk));
      } catch (...) {
        errors[c] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(threads);
  for (std::size_t t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(run);
    } catch (...) {  // std::system_error, std::bad_alloc: never unwind past running threads
      break;  // no more threads to be had: those started and this one share the chunks
    }
  }
  run();
  for (auto& t : pool) t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace geoanchor
