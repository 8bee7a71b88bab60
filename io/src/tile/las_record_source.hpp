#pragma once
// The records of a LAS or LAZ tile's runs of points for any thread (private
// to io): a run that is one of the file's chunks is read straight into the
// caller's buffer, others from chunks decompressed once and shared.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "geoanchor/las/las.hpp"

namespace geoanchor::io::detail {

// The records of any run of the tile's points, for any thread. A run that
// is one of the file's chunks (an uncompressed file's runs of
// kLasChunkPoints, a LAZ file written with the unit's chunk size) is read
// straight into the caller's buffer; otherwise the chunks it overlaps are
// decompressed once, by the first thread that asks, and kept until every
// run that needs a part of them has taken it.
class RecordSource {
 public:
  using Bytes = std::vector<std::uint8_t>;

  RecordSource(const LasReader& reader, std::uint64_t unit_points) : r_(reader), unit_(unit_points) {
    firsts_.reserve(r_.chunk_count());
    for (std::size_t i = 0; i < r_.chunk_count(); ++i) firsts_.push_back(r_.chunk_first_point(i));
  }

  // The chunk holding point `p` (0-based).
  std::size_t chunk_of(std::uint64_t p) const {
    return static_cast<std::size_t>(std::upper_bound(firsts_.begin(), firsts_.end(), p) - firsts_.begin()) - 1;
  }

  // Records [first, first + n) into `out` (n × record length bytes).
  void fetch(std::uint64_t first, std::size_t n, Bytes& out) {
    const std::size_t len = r_.header().record_length;
    std::size_t i = chunk_of(first);
    if (r_.chunk_first_point(i) == first && r_.chunk_points(i) == n) {
      r_.decode_chunk(i, out);
      return;
    }
    out.resize(n * len);
    for (std::uint64_t at = first; at < first + n; ++i) {
      const std::uint64_t c0 = r_.chunk_first_point(i), c1 = c0 + r_.chunk_points(i);
      const std::uint64_t to = std::min<std::uint64_t>(c1, first + n);
      const std::shared_ptr<const Bytes> records = acquire(i);
      std::memcpy(out.data() + (at - first) * len, records->data() + (at - c0) * len, static_cast<std::size_t>(to - at) * len);
      release(i);
      at = to;
    }
  }

 private:
  struct Cached {
    std::shared_future<std::shared_ptr<const Bytes>> records;
    std::uint64_t takers = 0;  // runs that have yet to take their part
  };
  std::shared_ptr<const Bytes> acquire(std::size_t i) {
    std::promise<std::shared_ptr<const Bytes>> promise;
    std::shared_future<std::shared_ptr<const Bytes>> records;
    bool mine = false;
    {
      const std::lock_guard<std::mutex> lock(m_);
      auto it = cache_.find(i);
      if (it == cache_.end()) {
        const std::uint64_t c0 = r_.chunk_first_point(i), c1 = c0 + r_.chunk_points(i);
        Cached c{promise.get_future().share(), (c1 - 1) / unit_ - c0 / unit_ + 1};
        it = cache_.emplace(i, std::move(c)).first;
        mine = true;
      }
      records = it->second.records;
    }
    if (mine) {
      try {
        auto b = std::make_shared<Bytes>();
        r_.decode_chunk(i, *b);
        promise.set_value(std::move(b));
      } catch (...) {
        promise.set_exception(std::current_exception());
      }
    }
    return records.get();  // rethrows the chunk's error for every run that needs it
  }
  void release(std::size_t i) {
    const std::lock_guard<std::mutex> lock(m_);
    const auto it = cache_.find(i);
    if (it != cache_.end() && --it->second.takers == 0) cache_.erase(it);
  }

  const LasReader& r_;
  const std::uint64_t unit_;
  std::vector<std::uint64_t> firsts_;
  std::mutex m_;
  std::map<std::size_t, Cached> cache_;
};

}  // namespace geoanchor::io::detail
