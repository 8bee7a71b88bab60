#pragma once
// What the LAZ item coders of both chunk kinds (laz_pointwise.cpp,
// laz_layered.cpp; see laz_chunk.hpp) share: record fields as stored, byte
// arithmetic, the predictor of coordinate differences and models made on
// first use.
//
// Each item coder holds the models and the "last value" state of its item; the
// encoder and the decoder of an item share that state and differ only in
// the direction of each coding step, so that both sides stay in lock step.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "las_internal.hpp"
#include "laz_entropy.hpp"

namespace geoanchor::io::laz {

// A record's little-endian field, read as LAS reads it; and written.
using las_internal::get;
template <class T>
void store(std::uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}
inline std::uint8_t low_byte(std::uint32_t v) { return static_cast<std::uint8_t>(v & 0xFFu); }
inline std::int32_t clamp_to_byte(std::int32_t v) { return v <= 0 ? 0 : (v >= 255 ? 255 : v); }
inline std::int32_t lo8(std::uint16_t v) { return v & 0xFF; }
inline std::int32_t hi8(std::uint16_t v) { return v >> 8; }

// The predictor of coordinate differences: a running "median" of five
// sorted values that drops the largest or the smallest in turn. Not the
// exact median of the last five differences, but the format's rule: while
// dropping the largest, a new value at or above the middle switches to
// dropping the smallest, and one at or below the middle switches back.
class Median5 {
 public:
  void reset() {
    v_.fill(0);
    drop_largest_ = true;
  }
  std::int32_t get() const { return v_[2]; }
  void add(std::int32_t x) {
    const std::int32_t middle = v_[2];
    if (drop_largest_) {
      int i = 3;
      for (; i >= 0 && v_[static_cast<std::size_t>(i)] > x; --i) {
        v_[static_cast<std::size_t>(i) + 1] = v_[static_cast<std::size_t>(i)];
      }
      v_[static_cast<std::size_t>(i + 1)] = x;
      if (x >= middle) drop_largest_ = false;
    } else {
      std::size_t i = 1;
      for (; i <= 4 && v_[i] < x; ++i) v_[i - 1] = v_[i];
      v_[i - 1] = x;
      if (x <= middle) drop_largest_ = true;
    }
  }

 private:
  std::array<std::int32_t, 5> v_{};
  bool drop_largest_ = true;
};

// Symbol models selected by a previous value, made on first use and reset
// on the first use after each new_chunk() (LASzip creates them lazily and
// re-initialises the ones that exist at each chunk).
class ModelTable {
 public:
  ModelTable(std::size_t count, std::uint32_t symbols, bool decoding)
      : symbols_(symbols), decoding_(decoding), models_(count), epochs_(count, 0) {}
  void new_chunk() { ++epoch_; }
  SymbolModel& at(std::size_t i) {
    if (!models_[i]) {
      models_[i] = std::make_unique<SymbolModel>(symbols_, decoding_);
      epochs_[i] = epoch_;
    } else if (epochs_[i] != epoch_) {
      models_[i]->reset();
      epochs_[i] = epoch_;
    }
    return *models_[i];
  }

 private:
  std::uint32_t symbols_;
  bool decoding_;
  std::uint64_t epoch_ = 1;
  std::vector<std::unique_ptr<SymbolModel>> models_;
  std::vector<std::uint64_t> epochs_;
};

}  // namespace geoanchor::io::laz
