#pragma once
// One computation at a time on a worker thread, the latest choices next:
// what the workbench's models (WorkbenchModel, NetworkModel) do so that a
// window keeps drawing the last result while a large set refits. A choice
// made while one runs marks it stale; when the caller takes the finished
// outcome it learns that and starts the next with the choices as they are
// then (never a queue of outdated ones).

#include <chrono>
#include <future>
#include <optional>
#include <utility>

namespace geoanchor::gui {

template <class Outcome>
class LatestOnWorker {
 public:
  LatestOnWorker() = default;
  ~LatestOnWorker() {
    if (pending_.valid()) pending_.wait();  // the worker holds copies only, but finish it
  }
  LatestOnWorker(const LatestOnWorker&) = delete;
  LatestOnWorker& operator=(const LatestOnWorker&) = delete;

  // Runs `compute` (returning an Outcome, holding copies of its inputs) on
  // the worker, or marks the running one stale.
  template <class Compute>
  void start(Compute compute) {
    if (pending_.valid()) {
      stale_ = true;
      return;
    }
    stale_ = false;
    pending_ = std::async(std::launch::async, std::move(compute));
  }

  bool busy() const { return pending_.valid() || stale_; }

  // The finished outcome, if one is ready; `start_again` says the choices
  // changed while it ran (the caller starts the next).
  std::optional<Outcome> take_ready(bool& start_again) {
    start_again = false;
    if (!pending_.valid() || pending_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return std::nullopt;
    std::optional<Outcome> out(pending_.get());
    start_again = stale_;
    return out;
  }

  void wait_running() {
    if (pending_.valid()) pending_.wait();
  }

 private:
  std::future<Outcome> pending_;
  bool stale_ = false;
};

}  // namespace geoanchor::gui
