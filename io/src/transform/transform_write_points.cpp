// The "points" array of a fitted transform file: one JSON object a line,
// formed in a stack buffer, blocks of records formatted by worker threads
// and written in order (the bytes of a one-thread loop).

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <exception>
#include <mutex>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

#include "geoanchor/io/transform/transform_file.hpp"
#include "transform/transform_common.hpp"

namespace geoanchor::io::detail {
namespace {

// One point record, one JSON object a line, appended to `out` (`first`: the
// array's first element, written without the comma). The record is formed
// in a stack buffer (numbers formatted in place, keys copied with their
// lengths known) and appended once: most of its cost is the 13 shortest
// round-trip numbers.
void append_point_record(std::string& out, const FitPointRecord& p, bool first) {
  // 13 numbers of at most 24 characters, an int, the keys: under 700 bytes.
  char buf[1024];
  char* at = buf;
  const auto lit = [&](std::string_view v) {
    std::memcpy(at, v.data(), v.size());
    at += v.size();
  };
  const auto num = [&](double v) {
    if (!std::isfinite(v)) {
      lit("null");
      return;
    }
    at = std::to_chars(at, at + 32, v).ptr;  // 32 > the longest double, "-2.2250738585072014e-308"
  };
  const auto triple = [&](const std::array<double, 3>& v) {
    *at++ = '[';
    num(v[0]);
    lit(", ");
    num(v[1]);
    lit(", ");
    num(v[2]);
    *at++ = ']';
  };
  const auto flag = [&](bool b) { lit(b ? std::string_view("true") : std::string_view("false")); };
  // A JSON string: as is when nothing in it needs escaping (the common id),
  // else through the JSON library; the record is flushed first, since an id
  // has no length limit.
  const auto text_value = [&](const std::string& v) {
    const bool plain = std::all_of(v.begin(), v.end(), [](char c) {
      return c != '"' && c != '\\' && static_cast<unsigned char>(c) >= 0x20 && c != 0x7f;
    });
    out.append(buf, static_cast<std::size_t>(at - buf));
    at = buf;
    if (plain) {
      out += '"';
      out += v;
      out += '"';
    } else {
      out += json(v).dump();
    }
  };
  lit(first ? std::string_view("\n    {\"id\": ") : std::string_view(",\n    {\"id\": "));
  text_value(p.id);
  lit(", \"mdb_m\": ");
  num(p.mdb_m);
  if (!p.note.empty()) {
    lit(", \"note\": ");
    text_value(p.note);
  }
  lit(", \"outlier\": ");
  flag(p.outlier);
  lit(", \"point_test\": {\"dof\": ");
  at = std::to_chars(at, at + 16, p.point_test_dof).ptr;
  lit(", \"p_value\": ");
  num(p.point_test_p);
  lit(", \"statistic\": ");
  num(p.point_test);
  lit("}, \"redundancy_enu\": ");
  triple(p.redundancy_enu);
  lit(", \"residual_enu_m\": ");
  triple(p.residual_enu_m);
  if (p.robust_weight < 1.0) {
    lit(", \"robust_weight\": ");
    num(p.robust_weight);
  }
  if (p.snooping_rank > 0) {
    lit(", \"snooping_rank\": ");
    at = std::to_chars(at, at + 24, p.snooping_rank).ptr;
  }
  if (p.solution) {
    lit(", \"solution\": \"");
    lit(geodesy::to_string(*p.solution));
    *at++ = '"';
  }
  if (!p.status.empty()) {
    lit(", \"status\": \"");
    lit(p.status);
    *at++ = '"';
  }
  lit(", \"used\": ");
  flag(p.used);
  // w_test is one of w_enu (the largest in magnitude): its text is copied
  // from there, not formed again.
  lit(", \"w_enu\": [");
  std::array<std::pair<const char*, const char*>, 3> w_text{};
  for (std::size_t k = 0; k < 3; ++k) {
    if (k) lit(", ");
    w_text[k].first = at;
    num(p.w_enu[k]);
    w_text[k].second = at;
  }
  lit("], \"w_test\": ");
  const auto same = std::find_if(w_text.begin(), w_text.end(), [&](const auto& t) {
    return std::bit_cast<std::uint64_t>(p.w_enu[static_cast<std::size_t>(&t - w_text.data())]) ==
           std::bit_cast<std::uint64_t>(p.w_test);
  });
  if (same != w_text.end()) {
    lit(std::string_view(same->first, static_cast<std::size_t>(same->second - same->first)));
  } else {
    num(p.w_test);
  }
  *at++ = '}';
  out.append(buf, static_cast<std::size_t>(at - buf));
}

}  // namespace

// The "points" array's elements, in order. Formatting the numbers is most of
// a large fit's output time (10⁶ marks: about 450 MB of text, 0.5 s of CPU),
// so blocks of records are formatted by one worker a core (at most 8), each taking the
// next block as it finishes one, while this thread writes the blocks in
// order; the bytes are those of a one-thread loop. The workers run ahead of
// the writer by at most kSlots blocks (about 14 MB), so that a wait for the
// disk (the output's writeback) does not stop them, and no more is held.
// The records are `held`, or else formed by `streamed`.
void write_point_records(std::ostream& out, const std::vector<FitPointRecord>& held, const PointRecordSource* streamed) {
  constexpr std::size_t kBlock = 2048;  // records a worker formats at once (about 0.9 MB)
  constexpr std::size_t kSlots = 16;    // blocks formed and not yet written, at most
  const std::size_t records = streamed ? streamed->count : held.size();
  const std::size_t blocks = (records + kBlock - 1) / kBlock;
  const std::size_t workers = std::min(std::clamp<std::size_t>(std::thread::hardware_concurrency(), 1, 8), blocks);
  const auto format_block = [&](std::size_t b, std::string& text) {
    text.clear();
    FitPointRecord formed;
    const std::size_t end = std::min(records, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) {
      if (streamed) streamed->record(i, formed);
      append_point_record(text, streamed ? formed : held[i], i == 0);
    }
  };
  const auto on_this_thread = [&] {
    std::string text;
    for (std::size_t b = 0; b < blocks; ++b) {
      format_block(b, text);
      out.write(text.data(), static_cast<std::streamsize>(text.size()));
    }
  };
  if (workers <= 1) {
    on_this_thread();
    return;
  }
  struct Slot {
    std::string text;
    std::size_t block = SIZE_MAX;  // the block `text` holds, once formed
    std::exception_ptr error;      // its formatting's failure (bad_alloc)
  };
  std::array<Slot, kSlots> slots;
  std::mutex mutex;
  std::condition_variable formed, written;
  std::size_t next_block = 0;  // the next block a worker takes
  std::size_t done = 0;        // blocks written (their slots free again)
  bool stop = false;           // the writer is done or has failed: the workers end
  const auto work = [&] {
    std::unique_lock lock(mutex);
    while (true) {
      written.wait(lock, [&] { return stop || next_block >= blocks || next_block < done + kSlots; });
      if (stop || next_block >= blocks) return;
      const std::size_t b = next_block++;
      Slot& slot = slots[b % kSlots];
      lock.unlock();
      std::exception_ptr error;
      try {
        format_block(b, slot.text);
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      slot.error = error;
      slot.block = b;
      formed.notify_all();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers);
  // The workers end before this frame does, whatever is thrown.
  struct Join {
    std::vector<std::thread>& pool;
    std::mutex& mutex;
    std::condition_variable& written;
    bool& stop;
    ~Join() {
      {
        const std::lock_guard lock(mutex);
        stop = true;
      }
      written.notify_all();
      for (auto& t : pool) t.join();
    }
  } join{pool, mutex, written, stop};
  for (std::size_t k = 0; k < workers; ++k) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {  // no more threads to be had: those started do the work
      break;
    }
  }
  if (pool.empty()) {
    on_this_thread();
    return;
  }
  for (std::size_t b = 0; b < blocks; ++b) {
    Slot& slot = slots[b % kSlots];
    {
      std::unique_lock lock(mutex);
      formed.wait(lock, [&] { return slot.block == b; });
      if (slot.error) std::rethrow_exception(slot.error);
    }
    out.write(slot.text.data(), static_cast<std::streamsize>(slot.text.size()));
    {
      const std::lock_guard lock(mutex);
      done = b + 1;
    }
    written.notify_all();
  }
}

}  // namespace geoanchor::io::detail
