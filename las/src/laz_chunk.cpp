// The LAZ item coders and the two chunk kinds (see laz_chunk.hpp). Each
// item coder holds the models and the "last value" state of its item; the
// encoder and the decoder of an item share that state and differ only in
// the direction of each coding step, so that both sides stay in lock step.

#include "laz_chunk.hpp"

#include <array>
#include <cstring>
#include <optional>

#include "laz_entropy.hpp"

namespace geoanchor::io::laz {
namespace {

template <class T>
T load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class T>
void store(std::uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}
std::uint8_t low_byte(std::uint32_t v) { return static_cast<std::uint8_t>(v & 0xFFu); }
std::int32_t clamp_to_byte(std::int32_t v) { return v <= 0 ? 0 : (v >= 255 ? 255 : v); }
std::int32_t lo8(std::uint16_t v) { return v & 0xFF; }
std::int32_t hi8(std::uint16_t v) { return v >> 8; }

// Return-number contexts of POINT10 (r and n of 3 bits each): the "return
// map" serialises the valid (n, r) pairs and maps invalid ones to contexts
// of their own; the "return level" is how many returns came before.
// Values as the LASzip paper and format define them.
constexpr std::uint8_t kReturnMap[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8}, {14, 0, 1, 3, 6, 10, 10, 9},     {13, 1, 2, 4, 7, 11, 11, 10},
    {12, 3, 4, 5, 8, 12, 12, 11},   {11, 6, 7, 8, 9, 13, 13, 12},    {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
constexpr std::uint8_t kReturnLevel[8][8] = {
    {0, 1, 2, 3, 4, 5, 6, 7}, {1, 0, 1, 2, 3, 4, 5, 6}, {2, 1, 0, 1, 2, 3, 4, 5}, {3, 2, 1, 0, 1, 2, 3, 4},
    {4, 3, 2, 1, 0, 1, 2, 3}, {5, 4, 3, 2, 1, 0, 1, 2}, {6, 5, 4, 3, 2, 1, 0, 1}, {7, 6, 5, 4, 3, 2, 1, 0}};
// The same for POINT14 (r and n of 4 bits): six map contexts, eight levels
// ("LASzip for LAS 1.4", number_return_map_6ctx and number_return_level_8ctx).
constexpr std::uint8_t kReturnMap14[16][16] = {
    {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5}, {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
    {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3}, {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};
constexpr std::uint8_t kReturnLevel14[16][16] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7, 7, 7, 7}, {1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7, 7, 7},
    {2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7, 7}, {3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7, 7},
    {4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 7}, {5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7},
    {6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7, 7}, {7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7, 7},
    {7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6, 7}, {7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5, 6},
    {7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4, 5}, {7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3, 4},
    {7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2, 3}, {7, 7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1, 2},
    {7, 7, 7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0, 1}, {7, 7, 7, 7, 7, 7, 7, 7, 7, 6, 5, 4, 3, 2, 1, 0}};

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

// ---------------------------------------------------------------------------
// GPS time (GPSTIME11 v2, and the GPS time layer of POINT14 v3). The 8 bytes
// are coded as a 64-bit integer. Four sequences are tracked (interleaved
// flight lines); within one, the difference to the previous time is
// predicted as a multiple (−10..500) of the last difference.

class GpsTimeCoder {
 public:
  // `unchanged_symbols`: v2 has a symbol for "same time" (v3 codes the
  // change in the returns layer instead), which shifts the others by one.
  GpsTimeCoder(bool unchanged_symbols, bool decoding)
      : shift_(unchanged_symbols ? 1u : 0u),
        full_(511 + shift_),
        multiplier_(515 + shift_, decoding),
        after_zero_(5 + shift_, decoding),
        ic_(32, 9, decoding) {}

  void reset(std::uint64_t first) {
    multiplier_.reset();
    after_zero_.reset();
    ic_.reset();
    last_ = next_ = 0;
    times_ = {first, 0, 0, 0};
    diffs_.fill(0);
    extremes_.fill(0);
  }

  void encode(RangeEncoder& e, std::uint64_t t) {
    for (;;) {
      const std::uint64_t prev = times_[last_];
      const bool fits = fits_32(t - prev);
      const auto d = static_cast<std::int32_t>(t - prev);
      if (diffs_[last_] == 0) {
        if (shift_ && t == prev) {
          e.encode_symbol(after_zero_, 0);
          return;
        }
        if (fits) {
          e.encode_symbol(after_zero_, shift_);
          ic_.encode(e, 0, d, 0);
          diffs_[last_] = d;
          extremes_[last_] = 0;
          times_[last_] = t;
          return;
        }
        if (const unsigned i = other_sequence(t)) {
          e.encode_symbol(after_zero_, shift_ + 1 + i);
          last_ = (last_ + i) & 3;
          continue;
        }
        e.encode_symbol(after_zero_, shift_ + 1);
        start_sequence(e, t);
        return;
      }
      if (shift_ && t == prev) {
        e.encode_symbol(multiplier_, 511);
        return;
      }
      if (fits) {
        const std::int32_t base = diffs_[last_];
        const std::int32_t multi = quantize(static_cast<float>(d) / static_cast<float>(base));
        if (multi == 1) {
          e.encode_symbol(multiplier_, 1);
          ic_.encode(e, base, d, 1);
          extremes_[last_] = 0;
        } else if (multi > 0) {
          if (multi < 500) {
            e.encode_symbol(multiplier_, static_cast<std::uint32_t>(multi));
            ic_.encode(e, times(multi, base), d, multi < 10 ? 2 : 3);
          } else {
            e.encode_symbol(multiplier_, 500);
            ic_.encode(e, times(500, base), d, 4);
            count_extreme(d);
          }
        } else if (multi < 0) {
          if (multi > -10) {
            e.encode_symbol(multiplier_, static_cast<std::uint32_t>(500 - multi));
            ic_.encode(e, times(multi, base), d, 5);
          } else {
            e.encode_symbol(multiplier_, 510);
            ic_.encode(e, times(-10, base), d, 6);
            count_extreme(d);
          }
        } else {
          e.encode_symbol(multiplier_, 0);
          ic_.encode(e, 0, d, 7);
          count_extreme(d);
        }
        times_[last_] = t;
        return;
      }
      if (const unsigned i = other_sequence(t)) {
        e.encode_symbol(multiplier_, full_ + i);
        last_ = (last_ + i) & 3;
        continue;
      }
      e.encode_symbol(multiplier_, full_);
      start_sequence(e, t);
      return;
    }
  }

  std::uint64_t decode(RangeDecoder& d) {
    // A stream switches sequence at most once per point: the encoder only
    // switches to a sequence whose difference fits 32 bits.
    for (int switches = 0;; ++switches) {
      if (switches > 1) throw StreamCorrupt{"a GPS time switches sequence twice"};
      if (diffs_[last_] == 0) {
        const std::uint32_t sym = d.decode_symbol(after_zero_);
        if (sym < shift_) return times_[last_];
        if (sym == shift_) {
          const std::int32_t diff = ic_.decode(d, 0, 0);
          diffs_[last_] = diff;
          times_[last_] += widen(diff);
          extremes_[last_] = 0;
          return times_[last_];
        }
        if (sym == shift_ + 1) return read_sequence(d);
        last_ = (last_ + sym - shift_ - 1) & 3;
        continue;
      }
      const std::uint32_t sym = d.decode_symbol(multiplier_);
      const std::int32_t base = diffs_[last_];
      if (sym == 1) {
        times_[last_] += widen(ic_.decode(d, base, 1));
        extremes_[last_] = 0;
        return times_[last_];
      }
      if (sym <= 510) {
        std::int32_t diff;
        if (sym == 0) {
          diff = ic_.decode(d, 0, 7);
          count_extreme(diff);
        } else if (sym < 500) {
          diff = ic_.decode(d, times(static_cast<std::int32_t>(sym), base), sym < 10 ? 2 : 3);
        } else if (sym == 500) {
          diff = ic_.decode(d, times(500, base), 4);
          count_extreme(diff);
        } else {
          const std::int32_t multi = 500 - static_cast<std::int32_t>(sym);
          if (multi > -10) {
            diff = ic_.decode(d, times(multi, base), 5);
          } else {
            diff = ic_.decode(d, times(-10, base), 6);
            count_extreme(diff);
          }
        }
        times_[last_] += widen(diff);
        return times_[last_];
      }
      if (shift_ && sym == 511) return times_[last_];
      if (sym == full_) return read_sequence(d);
      last_ = (last_ + sym - full_) & 3;
    }
  }

 private:
  static bool fits_32(std::uint64_t diff) {
    const auto s = static_cast<std::int64_t>(diff);
    return s >= INT32_MIN && s <= INT32_MAX;
  }
  static std::uint64_t widen(std::int32_t diff) {
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(diff));
  }
  // The product as LASzip's 32-bit integers give it (wrapping).
  static std::int32_t times(std::int32_t a, std::int32_t b) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) * static_cast<std::uint32_t>(b));
  }
  // Rounds half away from zero in single precision, as LASzip does; a
  // result outside int32 is what an x86 conversion gives (INT32_MIN).
  static std::int32_t quantize(float f) {
    const float r = f >= 0.0f ? f + 0.5f : f - 0.5f;
    if (!(r >= -2147483648.0f && r < 2147483648.0f)) return INT32_MIN;
    return static_cast<std::int32_t>(r);
  }
  // The first other sequence (1..3 ahead) within 32 bits of t, or 0.
  unsigned other_sequence(std::uint64_t t) const {
    for (unsigned i = 1; i < 4; ++i) {
      if (fits_32(t - times_[(last_ + i) & 3])) return i;
    }
    return 0;
  }
  // After 4 predictions out of range the difference itself becomes the base.
  void count_extreme(std::int32_t diff) {
    if (++extremes_[last_] > 3) {
      diffs_[last_] = diff;
      extremes_[last_] = 0;
    }
  }
  // A new sequence: the high 32 bits against the current sequence's, the low raw.
  void start_sequence(RangeEncoder& e, std::uint64_t t) {
    ic_.encode(e, static_cast<std::int32_t>(times_[last_] >> 32), static_cast<std::int32_t>(t >> 32), 8);
    e.write_int(static_cast<std::uint32_t>(t));
    next_ = (next_ + 1) & 3;
    last_ = next_;
    diffs_[last_] = 0;
    extremes_[last_] = 0;
    times_[last_] = t;
  }
  std::uint64_t read_sequence(RangeDecoder& d) {
    next_ = (next_ + 1) & 3;
    const auto high = static_cast<std::uint32_t>(ic_.decode(d, static_cast<std::int32_t>(times_[last_] >> 32), 8));
    const std::uint32_t low = d.read_int();
    times_[next_] = (std::uint64_t{high} << 32) | low;
    last_ = next_;
    diffs_[last_] = 0;
    extremes_[last_] = 0;
    return times_[last_];
  }

  std::uint32_t shift_;
  std::uint32_t full_;  // "new sequence"; the three after it switch sequence
  SymbolModel multiplier_;
  SymbolModel after_zero_;  // used while the last difference is 0
  IntegerCoder ic_;
  unsigned last_ = 0, next_ = 0;
  std::array<std::uint64_t, 4> times_{};
  std::array<std::int32_t, 4> diffs_{};
  std::array<std::int32_t, 4> extremes_{};
};

// ---------------------------------------------------------------------------
// RGB (RGB12 v2, and the RGB layer of RGB14/RGBNIR14 v3): the low and high
// bytes of each channel separately; which of the six bytes changed and
// whether the colour is grey (one symbol), then byte differences, green
// and blue predicted from the change in red (and green).

struct RgbModels {
  explicit RgbModels(bool decoding)
      : used(128, decoding),
        diff{SymbolModel(256, decoding), SymbolModel(256, decoding), SymbolModel(256, decoding),
             SymbolModel(256, decoding), SymbolModel(256, decoding), SymbolModel(256, decoding)} {}
  void reset() {
    used.reset();
    for (auto& m : diff) m.reset();
  }
  SymbolModel used;
  std::array<SymbolModel, 6> diff;
};

// Returns the "changed" symbol (0 when nothing differs from `last` and the
// colour is grey).
std::uint32_t encode_rgb(RangeEncoder& e, RgbModels& m, const std::uint16_t* last, const std::uint8_t* item) {
  const std::uint16_t c[3] = {load<std::uint16_t>(item), load<std::uint16_t>(item + 2), load<std::uint16_t>(item + 4)};
  std::uint32_t sym = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    sym |= std::uint32_t{lo8(last[k]) != lo8(c[k])} << (2 * k);
    sym |= std::uint32_t{hi8(last[k]) != hi8(c[k])} << (2 * k + 1);
  }
  const bool colour = lo8(c[0]) != lo8(c[1]) || lo8(c[0]) != lo8(c[2]) || hi8(c[0]) != hi8(c[1]) || hi8(c[0]) != hi8(c[2]);
  sym |= std::uint32_t{colour} << 6;
  e.encode_symbol(m.used, sym);
  std::int32_t dl = 0, dh = 0;
  if (sym & 1) {
    dl = lo8(c[0]) - lo8(last[0]);
    e.encode_symbol(m.diff[0], low_byte(static_cast<std::uint32_t>(dl)));
  }
  if (sym & 2) {
    dh = hi8(c[0]) - hi8(last[0]);
    e.encode_symbol(m.diff[1], low_byte(static_cast<std::uint32_t>(dh)));
  }
  if (sym & 64) {
    if (sym & 4) {
      const std::int32_t corr = lo8(c[1]) - clamp_to_byte(dl + lo8(last[1]));
      e.encode_symbol(m.diff[2], low_byte(static_cast<std::uint32_t>(corr)));
    }
    if (sym & 16) {
      dl = (dl + lo8(c[1]) - lo8(last[1])) / 2;
      const std::int32_t corr = lo8(c[2]) - clamp_to_byte(dl + lo8(last[2]));
      e.encode_symbol(m.diff[4], low_byte(static_cast<std::uint32_t>(corr)));
    }
    if (sym & 8) {
      const std::int32_t corr = hi8(c[1]) - clamp_to_byte(dh + hi8(last[1]));
      e.encode_symbol(m.diff[3], low_byte(static_cast<std::uint32_t>(corr)));
    }
    if (sym & 32) {
      dh = (dh + hi8(c[1]) - hi8(last[1])) / 2;
      const std::int32_t corr = hi8(c[2]) - clamp_to_byte(dh + hi8(last[2]));
      e.encode_symbol(m.diff[5], low_byte(static_cast<std::uint32_t>(corr)));
    }
  }
  return sym;
}

void decode_rgb(RangeDecoder& d, RgbModels& m, const std::uint16_t* last, std::uint16_t* c) {
  const std::uint32_t sym = d.decode_symbol(m.used);
  auto add = [](std::uint32_t corr, std::int32_t base) {
    return static_cast<std::int32_t>(low_byte(corr + static_cast<std::uint32_t>(base)));
  };
  std::int32_t l0 = sym & 1 ? add(d.decode_symbol(m.diff[0]), lo8(last[0])) : lo8(last[0]);
  std::int32_t h0 = sym & 2 ? add(d.decode_symbol(m.diff[1]), hi8(last[0])) : hi8(last[0]);
  c[0] = static_cast<std::uint16_t>(l0 | (h0 << 8));
  if (sym & 64) {
    std::int32_t diff = l0 - lo8(last[0]);
    const std::int32_t l1 = sym & 4 ? add(d.decode_symbol(m.diff[2]), clamp_to_byte(diff + lo8(last[1]))) : lo8(last[1]);
    std::int32_t l2 = lo8(last[2]);
    if (sym & 16) {
      const std::uint32_t corr = d.decode_symbol(m.diff[4]);
      diff = (diff + l1 - lo8(last[1])) / 2;
      l2 = add(corr, clamp_to_byte(diff + lo8(last[2])));
    }
    diff = h0 - hi8(last[0]);
    const std::int32_t h1 = sym & 8 ? add(d.decode_symbol(m.diff[3]), clamp_to_byte(diff + hi8(last[1]))) : hi8(last[1]);
    std::int32_t h2 = hi8(last[2]);
    if (sym & 32) {
      const std::uint32_t corr = d.decode_symbol(m.diff[5]);
      diff = (diff + h1 - hi8(last[1])) / 2;
      h2 = add(corr, clamp_to_byte(diff + hi8(last[2])));
    }
    c[1] = static_cast<std::uint16_t>(l1 | (h1 << 8));
    c[2] = static_cast<std::uint16_t>(l2 | (h2 << 8));
  } else {
    c[1] = c[0];
    c[2] = c[0];
  }
}

// NIR (RGBNIR14 v3): which byte changed, then byte differences.
struct NirModels {
  explicit NirModels(bool decoding) : used(4, decoding), low(256, decoding), high(256, decoding) {}
  void reset() {
    used.reset();
    low.reset();
    high.reset();
  }
  SymbolModel used, low, high;
};

std::uint32_t encode_nir(RangeEncoder& e, NirModels& m, std::uint16_t last, std::uint16_t v) {
  const std::uint32_t sym = std::uint32_t{lo8(last) != lo8(v)} | (std::uint32_t{hi8(last) != hi8(v)} << 1);
  e.encode_symbol(m.used, sym);
  if (sym & 1) e.encode_symbol(m.low, low_byte(static_cast<std::uint32_t>(lo8(v) - lo8(last))));
  if (sym & 2) e.encode_symbol(m.high, low_byte(static_cast<std::uint32_t>(hi8(v) - hi8(last))));
  return sym;
}

std::uint16_t decode_nir(RangeDecoder& d, NirModels& m, std::uint16_t last) {
  const std::uint32_t sym = d.decode_symbol(m.used);
  const std::uint32_t l = sym & 1 ? low_byte(d.decode_symbol(m.low) + static_cast<std::uint32_t>(lo8(last)))
                                  : static_cast<std::uint32_t>(lo8(last));
  const std::uint32_t h = sym & 2 ? low_byte(d.decode_symbol(m.high) + static_cast<std::uint32_t>(hi8(last)))
                                  : static_cast<std::uint32_t>(hi8(last));
  return static_cast<std::uint16_t>(l | (h << 8));
}

// ---------------------------------------------------------------------------
// Pointwise chunks: POINT10 v2, GPSTIME11 v2, RGB12 v2, BYTE v2.

class Point10Coder {
 public:
  explicit Point10Coder(bool decoding)
      : changed_(64, decoding),
        intensity_(16, 4, decoding),
        scan_angle_{SymbolModel(256, decoding), SymbolModel(256, decoding)},
        source_(16, 1, decoding),
        bit_byte_(256, 256, decoding),
        classification_(256, 256, decoding),
        user_data_(256, 256, decoding),
        dx_(32, 2, decoding),
        dy_(32, 22, decoding),
        z_(32, 20, decoding) {}

  // `decoding`: the decoder forgets the first point's intensity (the
  // encoder never looks at it; LASzip's decoder zeroes it).
  void reset(const std::uint8_t* first, bool decoding) {
    changed_.reset();
    intensity_.reset();
    scan_angle_[0].reset();
    scan_angle_[1].reset();
    source_.reset();
    bit_byte_.new_chunk();
    classification_.new_chunk();
    user_data_.new_chunk();
    dx_.reset();
    dy_.reset();
    z_.reset();
    for (auto& m : mx_) m.reset();
    for (auto& m : my_) m.reset();
    intensities_.fill(0);
    heights_.fill(0);
    std::memcpy(last_, first, 20);
    if (decoding) last_[12] = last_[13] = 0;
  }

  void encode(RangeEncoder& e, const std::uint8_t* item) {
    const std::uint32_t r = item[14] & 7u, n = (item[14] >> 3) & 7u;
    const std::uint32_t m = kReturnMap[n][r], l = kReturnLevel[n][r];
    const auto intensity = load<std::uint16_t>(item + 12);
    const auto source = load<std::uint16_t>(item + 18);
    const auto last_source = load<std::uint16_t>(last_ + 18);
    const std::uint32_t changed = (std::uint32_t{last_[14] != item[14]} << 5) |
                                  (std::uint32_t{intensities_[m] != intensity} << 4) |
                                  (std::uint32_t{last_[15] != item[15]} << 3) | (std::uint32_t{last_[16] != item[16]} << 2) |
                                  (std::uint32_t{last_[17] != item[17]} << 1) | std::uint32_t{last_source != source};
    e.encode_symbol(changed_, changed);
    if (changed & 32) e.encode_symbol(bit_byte_.at(last_[14]), item[14]);
    if (changed & 16) {
      intensity_.encode(e, intensities_[m], intensity, m < 3 ? m : 3);
      intensities_[m] = intensity;
    }
    if (changed & 8) e.encode_symbol(classification_.at(last_[15]), item[15]);
    if (changed & 4) e.encode_symbol(scan_angle_[(item[14] >> 6) & 1u], low_byte(item[16] - std::uint32_t{last_[16]}));
    if (changed & 2) e.encode_symbol(user_data_.at(last_[17]), item[17]);
    if (changed & 1) source_.encode(e, last_source, source, 0);

    const std::int32_t dx = difference(item, 0), dy = difference(item, 4);
    dx_.encode(e, mx_[m].get(), dx, n == 1);
    mx_[m].add(dx);
    dy_.encode(e, my_[m].get(), dy, (n == 1) + y_context(dx_.k()));
    my_[m].add(dy);
    const auto z = load<std::int32_t>(item + 8);
    z_.encode(e, heights_[l], z, (n == 1) + z_context((dx_.k() + dy_.k()) / 2));
    heights_[l] = z;
    std::memcpy(last_, item, 20);
  }

  void decode(RangeDecoder& d, std::uint8_t* out) {
    const std::uint32_t changed = d.decode_symbol(changed_);
    if (changed & 32) last_[14] = low_byte(d.decode_symbol(bit_byte_.at(last_[14])));
    const std::uint32_t r = last_[14] & 7u, n = (last_[14] >> 3) & 7u;
    const std::uint32_t m = kReturnMap[n][r], l = kReturnLevel[n][r];
    if (changed != 0) {
      if (changed & 16) {
        intensities_[m] = static_cast<std::uint16_t>(intensity_.decode(d, intensities_[m], m < 3 ? m : 3));
      }
      store(last_ + 12, intensities_[m]);
      if (changed & 8) last_[15] = low_byte(d.decode_symbol(classification_.at(last_[15])));
      if (changed & 4) {
        last_[16] = low_byte(d.decode_symbol(scan_angle_[(last_[14] >> 6) & 1u]) + last_[16]);
      }
      if (changed & 2) last_[17] = low_byte(d.decode_symbol(user_data_.at(last_[17])));
      if (changed & 1) {
        store(last_ + 18, static_cast<std::uint16_t>(source_.decode(d, load<std::uint16_t>(last_ + 18), 0)));
      }
    }
    const std::int32_t dx = dx_.decode(d, mx_[m].get(), n == 1);
    mx_[m].add(dx);
    store(last_, wrap_add(load<std::int32_t>(last_), dx));
    const std::int32_t dy = dy_.decode(d, my_[m].get(), (n == 1) + y_context(dx_.k()));
    my_[m].add(dy);
    store(last_ + 4, wrap_add(load<std::int32_t>(last_ + 4), dy));
    const std::int32_t z = z_.decode(d, heights_[l], (n == 1) + z_context((dx_.k() + dy_.k()) / 2));
    heights_[l] = z;
    store(last_ + 8, z);
    std::memcpy(out, last_, 20);
  }

 private:
  std::int32_t difference(const std::uint8_t* item, std::size_t at) const {
    return static_cast<std::int32_t>(load<std::uint32_t>(item + at) - load<std::uint32_t>(last_ + at));
  }
  static std::int32_t wrap_add(std::int32_t a, std::int32_t b) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) + static_cast<std::uint32_t>(b));
  }
  // The Y and Z contexts: the even part of X's (and Y's) interval index, capped.
  static unsigned y_context(unsigned k) { return k < 20 ? (k & ~1u) : 20; }
  static unsigned z_context(unsigned k) { return k < 18 ? (k & ~1u) : 18; }

  SymbolModel changed_;
  IntegerCoder intensity_;
  std::array<SymbolModel, 2> scan_angle_;  // by scan direction flag
  IntegerCoder source_;
  ModelTable bit_byte_, classification_, user_data_;  // by the last point's value
  IntegerCoder dx_, dy_, z_;
  std::array<Median5, 16> mx_{}, my_{};  // by return map
  std::array<std::uint16_t, 16> intensities_{};
  std::array<std::int32_t, 8> heights_{};  // by return level
  std::uint8_t last_[20] = {};
};

class BytesCoder {
 public:
  BytesCoder(std::size_t count, bool decoding) : last_(count) {
    models_.reserve(count);
    for (std::size_t i = 0; i < count; ++i) models_.emplace_back(256, decoding);
  }
  void reset(const std::uint8_t* first) {
    for (auto& m : models_) m.reset();
    std::memcpy(last_.data(), first, last_.size());
  }
  void encode(RangeEncoder& e, const std::uint8_t* item) {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      e.encode_symbol(models_[i], low_byte(item[i] - std::uint32_t{last_[i]}));
      last_[i] = item[i];
    }
  }
  void decode(RangeDecoder& d, std::uint8_t* out) {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      last_[i] = low_byte(d.decode_symbol(models_[i]) + last_[i]);
      out[i] = last_[i];
    }
  }

 private:
  std::vector<SymbolModel> models_;
  std::vector<std::uint8_t> last_;
};

class PointwiseCoder {
 public:
  PointwiseCoder(const ChunkLayout& layout, bool decoding)
      : layout_(layout), decoding_(decoding), point_(decoding) {
    if (layout.gps_time) gps_.emplace(true, decoding);
    if (layout.rgb) rgb_.emplace(decoding);
    if (layout.extra_bytes) bytes_.emplace(layout.extra_bytes, decoding);
  }

  void encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out) {
    const std::size_t len = layout_.record_length;
    out.insert(out.end(), records, records + len);
    reset(records);
    RangeEncoder e(out);
    for (std::size_t i = 1; i < n; ++i) {
      const std::uint8_t* rec = records + i * len;
      point_.encode(e, rec);
      std::size_t at = 20;
      if (gps_) {
        gps_->encode(e, load<std::uint64_t>(rec + at));
        at += 8;
      }
      if (rgb_) {
        encode_rgb(e, *rgb_, last_rgb_.data(), rec + at);
        for (std::size_t k = 0; k < 3; ++k) last_rgb_[k] = load<std::uint16_t>(rec + at + 2 * k);
        at += 6;
      }
      if (bytes_) bytes_->encode(e, rec + at);
    }
    e.finish();
  }

  std::size_t decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out) {
    const std::size_t len = layout_.record_length;
    if (size < len) throw StreamOverrun{};
    std::memcpy(out, data, len);
    reset(data);
    RangeDecoder d;
    d.start(data + len, data + size);
    for (std::size_t i = 1; i < n; ++i) {
      std::uint8_t* rec = out + i * len;
      point_.decode(d, rec);
      std::size_t at = 20;
      if (gps_) {
        store(rec + at, gps_->decode(d));
        at += 8;
      }
      if (rgb_) {
        std::uint16_t c[3];
        decode_rgb(d, *rgb_, last_rgb_.data(), c);
        for (std::size_t k = 0; k < 3; ++k) {
          last_rgb_[k] = c[k];
          store(rec + at + 2 * k, c[k]);
        }
        at += 6;
      }
      if (bytes_) bytes_->decode(d, rec + at);
    }
    return static_cast<std::size_t>(d.position() - data);
  }

 private:
  void reset(const std::uint8_t* first) {
    point_.reset(first, decoding_);
    std::size_t at = 20;
    if (gps_) {
      gps_->reset(load<std::uint64_t>(first + at));
      at += 8;
    }
    if (rgb_) {
      rgb_->reset();
      for (std::size_t k = 0; k < 3; ++k) last_rgb_[k] = load<std::uint16_t>(first + at + 2 * k);
      at += 6;
    }
    if (bytes_) bytes_->reset(first + at);
  }

  ChunkLayout layout_;
  bool decoding_;
  Point10Coder point_;
  std::optional<GpsTimeCoder> gps_;
  std::optional<RgbModels> rgb_;
  std::array<std::uint16_t, 3> last_rgb_{};
  std::optional<BytesCoder> bytes_;
};

// ---------------------------------------------------------------------------
// Layered chunks: POINT14 v3, RGB14 / RGBNIR14 v3, BYTE14 v3.
//
// Each of the four scanner channels has its own context (models and last
// point); a context starts, when its channel first appears in a chunk,
// from the last point of the channel before it.

// The layers of POINT14, in the order of the chunk.
enum Layer14 : std::size_t {
  kReturnsXY,
  kZ,
  kClassification,
  kFlags,
  kIntensity,
  kScanAngle,
  kUserData,
  kPointSource,
  kGpsTime,
  kPoint14Layers
};

// Fields of a format 6-10 record (LAS 1.4 R15, table 15).
std::uint32_t return_number(const std::uint8_t* p) { return p[14] & 0x0Fu; }
std::uint32_t number_of_returns(const std::uint8_t* p) { return p[14] >> 4; }
std::uint32_t channel_of(const std::uint8_t* p) { return (p[15] >> 4) & 3u; }
// Edge of flight line (bit 5), scan direction (bit 4), classification flags (bits 0-3).
std::uint32_t flags_of(const std::uint8_t* p) { return ((p[15] >> 2) & 0x30u) | (p[15] & 0x0Fu); }

struct Point14Context {
  explicit Point14Context(bool decoding)
      : changed{SymbolModel(128, decoding), SymbolModel(128, decoding), SymbolModel(128, decoding),
                SymbolModel(128, decoding), SymbolModel(128, decoding), SymbolModel(128, decoding),
                SymbolModel(128, decoding), SymbolModel(128, decoding)},
        channel(3, decoding),
        returns(16, 16, decoding),
        return_number(16, 16, decoding),
        return_step(13, decoding),
        dx(32, 2, decoding),
        dy(32, 22, decoding),
        z(32, 20, decoding),
        classification(64, 256, decoding),
        flags(64, 64, decoding),
        user_data(64, 256, decoding),
        intensity(16, 4, decoding),
        scan_angle(16, 2, decoding),
        source(16, 1, decoding),
        gps(false, decoding) {}

  void reset(const std::uint8_t* from) {
    for (auto& m : changed) m.reset();
    channel.reset();
    returns.new_chunk();
    return_number.new_chunk();
    return_step.reset();
    dx.reset();
    dy.reset();
    z.reset();
    classification.new_chunk();
    flags.new_chunk();
    user_data.new_chunk();
    intensity.reset();
    scan_angle.reset();
    source.reset();
    gps.reset(load<std::uint64_t>(from + 22));
    for (auto& m : mx) m.reset();
    for (auto& m : my) m.reset();
    heights.fill(load<std::int32_t>(from + 8));
    intensities.fill(load<std::uint16_t>(from + 12));
    std::memcpy(last, from, 30);
    last_gps_changed = false;
    in_use = true;
  }

  std::array<SymbolModel, 8> changed;  // by the last point's return kind and GPS change
  SymbolModel channel;
  ModelTable returns;        // number of returns, by the last one
  ModelTable return_number;  // by the last one, when the GPS time changed
  SymbolModel return_step;   // return number step (2..14) when it did not
  IntegerCoder dx, dy, z;
  ModelTable classification, flags, user_data;
  IntegerCoder intensity, scan_angle, source;
  GpsTimeCoder gps;
  std::array<Median5, 12> mx{}, my{};       // by return map and GPS change
  std::array<std::int32_t, 8> heights{};     // by return level
  std::array<std::uint16_t, 8> intensities{};  // by return kind and GPS change
  std::uint8_t last[30] = {};
  bool last_gps_changed = false;
  bool in_use = false;
};

// encode() and decode() return the context of the items after POINT14 for
// that point: LASzip hands them the new channel on a point that switches
// channel and 0 on every other point (its per-point context starts at 0 and
// only a switch sets it), the chunk's first point excepted. The items
// follow that value, not the point's channel; a stream depends on it.
class Point14Coder {
 public:
  explicit Point14Coder(bool decoding) : decoding_(decoding) {}

  // The chunk's first point; returns its channel (the context of the items after it).
  unsigned reset(const std::uint8_t* first) {
    for (auto& c : contexts_) {
      if (c) c->in_use = false;
    }
    current_ = channel_of(first);
    context(current_).reset(first);
    return current_;
  }

  unsigned encode(std::array<RangeEncoder*, kPoint14Layers>& e, std::array<bool, kPoint14Layers>& changed,
                  const std::uint8_t* item) {
    Point14Context* cur = contexts_[current_].get();
    const std::uint8_t* last = cur->last;
    const std::uint32_t lpr = last_return_kind(last) + (cur->last_gps_changed ? 4u : 0u);
    const unsigned channel = channel_of(item);
    if (channel != current_ && contexts_[channel] && contexts_[channel]->in_use) last = contexts_[channel]->last;

    const bool source_changed = load<std::uint16_t>(item + 20) != load<std::uint16_t>(last + 20);
    const bool gps_changed = load<std::uint64_t>(item + 22) != load<std::uint64_t>(last + 22);
    const bool scan_changed = load<std::int16_t>(item + 18) != load<std::int16_t>(last + 18);
    const std::uint32_t last_n = number_of_returns(last), last_r = return_number(last);
    const std::uint32_t n = number_of_returns(item), r = return_number(item);
    std::uint32_t sym = (std::uint32_t{channel != current_} << 6) | (std::uint32_t{source_changed} << 5) |
                        (std::uint32_t{gps_changed} << 4) | (std::uint32_t{scan_changed} << 3) |
                        (std::uint32_t{n != last_n} << 2);
    if (r != last_r) sym |= r == ((last_r + 1) & 15u) ? 1u : (r == ((last_r + 15) & 15u) ? 2u : 3u);
    RangeEncoder& xy = *e[kReturnsXY];
    xy.encode_symbol(cur->changed[lpr], sym);
    if (sym & 64) {
      xy.encode_symbol(cur->channel, (channel + 3 - current_) & 3u);  // channel = current + symbol + 1 (mod 4)
      if (!contexts_[channel] || !contexts_[channel]->in_use) {
        context(channel).reset(cur->last);
        last = contexts_[channel]->last;
      }
      current_ = channel;
      cur = contexts_[channel].get();
    }
    if (sym & 4) xy.encode_symbol(cur->returns.at(last_n), n);
    if ((sym & 3) == 3) {
      if (gps_changed) {
        xy.encode_symbol(cur->return_number.at(last_r), r);
      } else {
        xy.encode_symbol(cur->return_step, (r + 16 - last_r - 2) & 15u);  // r = last_r + symbol + 2 (mod 16)
      }
    }
    const std::uint32_t m = kReturnMap14[n][r], l = kReturnLevel14[n][r];
    const std::uint32_t cpr = current_return_kind(n, r);
    const std::size_t slot = (m << 1) | std::uint32_t{gps_changed};

    const auto dx = static_cast<std::int32_t>(load<std::uint32_t>(item) - load<std::uint32_t>(last));
    cur->dx.encode(xy, cur->mx[slot].get(), dx, n == 1);
    cur->mx[slot].add(dx);
    const auto dy = static_cast<std::int32_t>(load<std::uint32_t>(item + 4) - load<std::uint32_t>(last + 4));
    cur->dy.encode(xy, cur->my[slot].get(), dy, (n == 1) + y_context(cur->dx.k()));
    cur->my[slot].add(dy);
    const auto z = load<std::int32_t>(item + 8);
    cur->z.encode(*e[kZ], cur->heights[l], z, (n == 1) + z_context((cur->dx.k() + cur->dy.k()) / 2));
    cur->heights[l] = z;

    const std::uint32_t cls = item[16], last_cls = last[16];
    changed[kClassification] = changed[kClassification] || cls != last_cls;
    e[kClassification]->encode_symbol(cur->classification.at(((last_cls & 0x1Fu) << 1) + (cpr == 3)), cls);

    const std::uint32_t flags = flags_of(item), last_flags = flags_of(last);
    changed[kFlags] = changed[kFlags] || flags != last_flags;
    e[kFlags]->encode_symbol(cur->flags.at(last_flags), flags);

    const auto intensity = load<std::uint16_t>(item + 12);
    changed[kIntensity] = changed[kIntensity] || intensity != load<std::uint16_t>(last + 12);
    const std::size_t islot = (cpr << 1) | std::uint32_t{gps_changed};
    cur->intensity.encode(*e[kIntensity], cur->intensities[islot], intensity, cpr);
    cur->intensities[islot] = intensity;

    if (scan_changed) {
      changed[kScanAngle] = true;
      cur->scan_angle.encode(*e[kScanAngle], load<std::int16_t>(last + 18), load<std::int16_t>(item + 18), gps_changed);
    }
    changed[kUserData] = changed[kUserData] || item[17] != last[17];
    e[kUserData]->encode_symbol(cur->user_data.at(last[17] / 4u), item[17]);
    if (source_changed) {
      changed[kPointSource] = true;
      cur->source.encode(*e[kPointSource], load<std::uint16_t>(last + 20), load<std::uint16_t>(item + 20), 0);
    }
    if (gps_changed) {
      changed[kGpsTime] = true;
      cur->gps.encode(*e[kGpsTime], load<std::uint64_t>(item + 22));
    }
    std::memcpy(cur->last, item, 30);
    cur->last_gps_changed = gps_changed;
    return (sym & 64) ? current_ : 0u;
  }

  // `present[k]`: layer k is in the chunk (else its values stay as they were).
  unsigned decode(std::array<RangeDecoder, kPoint14Layers>& d, const std::array<bool, kPoint14Layers>& present,
                  std::uint8_t* out) {
    Point14Context* cur = contexts_[current_].get();
    const std::uint32_t lpr = last_return_kind(cur->last) + (cur->last_gps_changed ? 4u : 0u);
    RangeDecoder& xy = d[kReturnsXY];
    const std::uint32_t sym = xy.decode_symbol(cur->changed[lpr]);
    if (sym & 64) {
      const unsigned channel = (current_ + xy.decode_symbol(cur->channel) + 1) & 3u;
      if (!contexts_[channel] || !contexts_[channel]->in_use) context(channel).reset(cur->last);
      current_ = channel;
      cur = contexts_[channel].get();
      cur->last[15] = static_cast<std::uint8_t>((cur->last[15] & 0xCFu) | (channel << 4));
    }
    std::uint8_t* last = cur->last;
    const bool gps_changed = (sym & 16) != 0;
    const std::uint32_t last_n = number_of_returns(last), last_r = return_number(last);
    const std::uint32_t n = sym & 4 ? xy.decode_symbol(cur->returns.at(last_n)) : last_n;
    std::uint32_t r = last_r;
    switch (sym & 3) {
      case 1: r = (last_r + 1) & 15u; break;
      case 2: r = (last_r + 15) & 15u; break;
      case 3:
        r = gps_changed ? xy.decode_symbol(cur->return_number.at(last_r))
                        : (last_r + xy.decode_symbol(cur->return_step) + 2) & 15u;
        break;
      default: break;
    }
    last[14] = static_cast<std::uint8_t>(r | (n << 4));
    const std::uint32_t m = kReturnMap14[n][r], l = kReturnLevel14[n][r];
    const std::uint32_t cpr = current_return_kind(n, r);
    const std::size_t slot = (m << 1) | std::uint32_t{gps_changed};

    const std::int32_t dx = cur->dx.decode(xy, cur->mx[slot].get(), n == 1);
    cur->mx[slot].add(dx);
    store(last, load<std::uint32_t>(last) + static_cast<std::uint32_t>(dx));
    const std::int32_t dy = cur->dy.decode(xy, cur->my[slot].get(), (n == 1) + y_context(cur->dx.k()));
    cur->my[slot].add(dy);
    store(last + 4, load<std::uint32_t>(last + 4) + static_cast<std::uint32_t>(dy));
    if (present[kZ]) {
      const std::int32_t z = cur->z.decode(d[kZ], cur->heights[l], (n == 1) + z_context((cur->dx.k() + cur->dy.k()) / 2));
      cur->heights[l] = z;
      store(last + 8, z);
    }
    if (present[kClassification]) {
      last[16] = low_byte(d[kClassification].decode_symbol(cur->classification.at(((last[16] & 0x1Fu) << 1) + (cpr == 3))));
    }
    if (present[kFlags]) {
      const std::uint32_t f = d[kFlags].decode_symbol(cur->flags.at(flags_of(last)));
      last[15] = static_cast<std::uint8_t>(((f & 0x30u) << 2) | (last[15] & 0x30u) | (f & 0x0Fu));
    }
    if (present[kIntensity]) {
      const std::size_t islot = (cpr << 1) | std::uint32_t{gps_changed};
      const auto v = static_cast<std::uint16_t>(cur->intensity.decode(d[kIntensity], cur->intensities[islot], cpr));
      cur->intensities[islot] = v;
      store(last + 12, v);
    }
    if (present[kScanAngle] && (sym & 8)) {
      store(last + 18, static_cast<std::uint16_t>(cur->scan_angle.decode(d[kScanAngle], load<std::int16_t>(last + 18), gps_changed)));
    }
    if (present[kUserData]) last[17] = low_byte(d[kUserData].decode_symbol(cur->user_data.at(last[17] / 4u)));
    if (present[kPointSource] && (sym & 32)) {
      store(last + 20, static_cast<std::uint16_t>(cur->source.decode(d[kPointSource], load<std::uint16_t>(last + 20), 0)));
    }
    if (present[kGpsTime] && gps_changed) store(last + 22, cur->gps.decode(d[kGpsTime]));
    std::memcpy(out, last, 30);
    cur->last_gps_changed = gps_changed;
    return (sym & 64) ? current_ : 0u;
  }

 private:
  Point14Context& context(unsigned channel) {
    if (!contexts_[channel]) contexts_[channel] = std::make_unique<Point14Context>(decoding_);
    return *contexts_[channel];
  }
  // Of the last point: first (1), last (2), single (3) or intermediate (0).
  static std::uint32_t last_return_kind(const std::uint8_t* p) {
    const std::uint32_t r = return_number(p), n = number_of_returns(p);
    return (r == 1 ? 1u : 0u) + (r >= n ? 2u : 0u);
  }
  // Of the current point: first (2), last (1), single (3), intermediate (0).
  static std::uint32_t current_return_kind(std::uint32_t n, std::uint32_t r) { return (r == 1 ? 2u : 0u) + (r >= n ? 1u : 0u); }
  static unsigned y_context(unsigned k) { return k < 20 ? (k & ~1u) : 20; }
  static unsigned z_context(unsigned k) { return k < 18 ? (k & ~1u) : 18; }

  bool decoding_;
  unsigned current_ = 0;
  std::array<std::unique_ptr<Point14Context>, 4> contexts_;
};

// The items after POINT14 follow the context it hands them (the chunk's
// first channel, then a new channel on each switch and 0 on every other
// point: see Point14Coder). Their reference value has a quirk of format
// version 3 that must be kept too: it is taken from the previous point's
// context, and on a switch to a context already used in the chunk it stays
// there for that one point (the previous context's last value predicts the
// point and is the one overwritten by it), while the models are the new
// context's. Version 4 of these items, not implemented, changes both.
struct ColourContext {
  explicit ColourContext(bool decoding) : rgb(decoding), nir(decoding) {}
  RgbModels rgb;
  NirModels nir;
  std::array<std::uint16_t, 4> last{};
  bool in_use = false;
};

class Colour14Coder {
 public:
  Colour14Coder(bool with_nir, bool decoding) : nir_(with_nir), decoding_(decoding) {}

  void reset(const std::uint8_t* first, unsigned channel) {
    for (auto& c : contexts_) {
      if (c) c->in_use = false;
    }
    current_ = channel;
    start(channel, first);
  }

  void encode(RangeEncoder& rgb, RangeEncoder* nir, bool& rgb_changed, bool& nir_changed, const std::uint8_t* item,
              unsigned channel) {
    auto& last = switch_to(channel);
    ColourContext& c = *contexts_[current_];
    if (encode_rgb(rgb, c.rgb, last.data(), item) != 0) rgb_changed = true;
    for (std::size_t k = 0; k < 3; ++k) last[k] = load<std::uint16_t>(item + 2 * k);
    if (nir_) {
      const auto v = load<std::uint16_t>(item + 6);
      if (encode_nir(*nir, c.nir, last[3], v) != 0) nir_changed = true;
      last[3] = v;
    }
  }

  void decode(RangeDecoder* rgb, RangeDecoder* nir, std::uint8_t* out, unsigned channel) {
    auto& last = switch_to(channel);
    ColourContext& c = *contexts_[current_];
    if (rgb) {
      std::uint16_t v[3];
      decode_rgb(*rgb, c.rgb, last.data(), v);
      for (std::size_t k = 0; k < 3; ++k) last[k] = v[k];
    }
    for (std::size_t k = 0; k < 3; ++k) store(out + 2 * k, last[k]);
    if (nir_) {
      if (nir) last[3] = decode_nir(*nir, c.nir, last[3]);
      store(out + 6, last[3]);
    }
  }

 private:
  void start(unsigned channel, const std::uint8_t* from) {
    if (!contexts_[channel]) contexts_[channel] = std::make_unique<ColourContext>(decoding_);
    ColourContext& c = *contexts_[channel];
    c.rgb.reset();
    c.nir.reset();
    for (std::size_t k = 0; k < 3; ++k) c.last[k] = load<std::uint16_t>(from + 2 * k);
    c.last[3] = nir_ ? load<std::uint16_t>(from + 6) : 0;
    c.in_use = true;
  }
  // Makes `channel` current; returns the reference value for this point.
  std::array<std::uint16_t, 4>& switch_to(unsigned channel) {
    std::array<std::uint16_t, 4>* reference = &contexts_[current_]->last;
    if (channel != current_) {
      current_ = channel;
      if (!contexts_[channel] || !contexts_[channel]->in_use) {
        std::uint8_t from[8];
        for (std::size_t k = 0; k < 4; ++k) store(from + 2 * k, (*reference)[k]);
        start(channel, from);
        reference = &contexts_[channel]->last;
      }
    }
    return *reference;
  }

  bool nir_;
  bool decoding_;
  unsigned current_ = 0;
  std::array<std::unique_ptr<ColourContext>, 4> contexts_;
};

struct BytesContext {
  std::vector<SymbolModel> models;
  std::vector<std::uint8_t> last;
  bool in_use = false;
};

class Bytes14Coder {
 public:
  Bytes14Coder(std::size_t count, bool decoding) : count_(count), decoding_(decoding), from_(count) {}
  std::size_t count() const { return count_; }

  void reset(const std::uint8_t* first, unsigned channel) {
    for (auto& c : contexts_) {
      if (c) c->in_use = false;
    }
    current_ = channel;
    start(channel, first);
  }

  void encode(std::vector<std::unique_ptr<RangeEncoder>>& e, std::vector<bool>& changed, const std::uint8_t* item,
              unsigned channel) {
    auto& last = switch_to(channel);
    BytesContext& c = *contexts_[current_];
    for (std::size_t i = 0; i < count_; ++i) {
      const std::uint32_t diff = low_byte(item[i] - std::uint32_t{last[i]});
      e[i]->encode_symbol(c.models[i], diff);
      if (diff != 0) changed[i] = true;
      last[i] = item[i];
    }
  }

  void decode(std::vector<RangeDecoder>& d, const std::vector<bool>& present, std::uint8_t* out, unsigned channel) {
    auto& last = switch_to(channel);
    BytesContext& c = *contexts_[current_];
    for (std::size_t i = 0; i < count_; ++i) {
      if (present[i]) last[i] = low_byte(d[i].decode_symbol(c.models[i]) + last[i]);
      out[i] = last[i];
    }
  }

 private:
  void start(unsigned channel, const std::uint8_t* from) {
    if (!contexts_[channel]) {
      contexts_[channel] = std::make_unique<BytesContext>();
      auto& c = *contexts_[channel];
      c.models.reserve(count_);
      for (std::size_t i = 0; i < count_; ++i) c.models.emplace_back(256, decoding_);
      c.last.resize(count_);
    }
    BytesContext& c = *contexts_[channel];
    for (auto& m : c.models) m.reset();
    std::memcpy(c.last.data(), from, count_);
    c.in_use = true;
  }
  // As Colour14Coder::switch_to.
  std::vector<std::uint8_t>& switch_to(unsigned channel) {
    std::vector<std::uint8_t>* reference = &contexts_[current_]->last;
    if (channel != current_) {
      current_ = channel;
      if (!contexts_[channel] || !contexts_[channel]->in_use) {
        from_ = *reference;
        start(channel, from_.data());
        reference = &contexts_[channel]->last;
      }
    }
    return *reference;
  }

  std::size_t count_;
  bool decoding_;
  unsigned current_ = 0;
  std::array<std::unique_ptr<BytesContext>, 4> contexts_;
  std::vector<std::uint8_t> from_;
};

class LayeredCoder {
 public:
  LayeredCoder(const ChunkLayout& layout, bool decoding) : layout_(layout), point_(decoding) {
    if (layout.rgb) colour_.emplace(layout.nir, decoding);
    if (layout.extra_bytes) bytes_.emplace(layout.extra_bytes, decoding);
  }

  void encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out) {
    const std::size_t len = layout_.record_length;
    out.insert(out.end(), records, records + len);
    const std::size_t colour_at = 30, bytes_at = 30 + colour_size();
    unsigned channel = point_.reset(records);
    if (colour_) colour_->reset(records + colour_at, channel);
    if (bytes_) bytes_->reset(records + bytes_at, channel);

    const std::size_t layers = layer_count();
    buffers_.resize(layers);
    for (auto& b : buffers_) b.clear();
    std::vector<std::unique_ptr<RangeEncoder>> enc;
    enc.reserve(layers);
    for (auto& b : buffers_) enc.push_back(std::make_unique<RangeEncoder>(b));
    std::array<RangeEncoder*, kPoint14Layers> point_enc{};
    for (std::size_t k = 0; k < kPoint14Layers; ++k) point_enc[k] = enc[k].get();
    std::array<bool, kPoint14Layers> point_changed{};
    point_changed[kReturnsXY] = point_changed[kZ] = true;  // always written
    bool rgb_changed = false, nir_changed = false;
    std::vector<std::unique_ptr<RangeEncoder>> byte_enc;
    std::vector<bool> bytes_changed(bytes_ ? bytes_->count() : 0, false);
    for (std::size_t i = kPoint14Layers + colour_layers(); i < layers; ++i) byte_enc.push_back(std::move(enc[i]));

    for (std::size_t i = 1; i < n; ++i) {
      const std::uint8_t* rec = records + i * len;
      channel = point_.encode(point_enc, point_changed, rec);
      if (colour_) {
        colour_->encode(*enc[kPoint14Layers], layout_.nir ? enc[kPoint14Layers + 1].get() : nullptr, rgb_changed,
                        nir_changed, rec + colour_at, channel);
      }
      if (bytes_) bytes_->encode(byte_enc, bytes_changed, rec + bytes_at, channel);
    }
    for (std::size_t k = 0; k < kPoint14Layers; ++k) enc[k]->finish();
    for (std::size_t k = 0; k < colour_layers(); ++k) enc[kPoint14Layers + k]->finish();
    for (auto& e : byte_enc) e->finish();

    std::vector<bool> keep(layers, false);
    for (std::size_t k = 0; k < kPoint14Layers; ++k) keep[k] = point_changed[k];
    if (colour_) {
      keep[kPoint14Layers] = rgb_changed;
      if (layout_.nir) keep[kPoint14Layers + 1] = nir_changed;
    }
    for (std::size_t i = 0; i < bytes_changed.size(); ++i) keep[kPoint14Layers + colour_layers() + i] = bytes_changed[i];

    put_u32(out, static_cast<std::uint32_t>(n));
    for (std::size_t k = 0; k < layers; ++k) put_u32(out, keep[k] ? static_cast<std::uint32_t>(buffers_[k].size()) : 0u);
    for (std::size_t k = 0; k < layers; ++k) {
      if (keep[k]) out.insert(out.end(), buffers_[k].begin(), buffers_[k].end());
    }
  }

  std::size_t decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out) {
    const std::size_t len = layout_.record_length;
    const std::size_t layers = layer_count();
    if (size < len + 4 * (1 + layers)) throw StreamOverrun{};
    std::memcpy(out, data, len);
    // The chunk's own point count must be the one the header and the chunk
    // table give it: fewer would drop the rest silently (issue 40 point 8).
    const auto stored = load<std::uint32_t>(data + len);
    if (stored != n) throw ChunkCountMismatch{stored};
    const std::uint8_t* at = data + len + 4;
    std::vector<std::size_t> sizes(layers);
    std::size_t total = len + 4 * (1 + layers);
    for (std::size_t k = 0; k < layers; ++k, at += 4) {
      sizes[k] = load<std::uint32_t>(at);
      total += sizes[k];
    }
    if (total > size) throw StreamCorrupt{"its layers are longer than the chunk"};
    if (n == 1) return total;  // nothing to decode

    const std::size_t colour_at = 30, bytes_at = 30 + colour_size();
    unsigned channel = point_.reset(data);
    if (colour_) colour_->reset(data + colour_at, channel);
    if (bytes_) bytes_->reset(data + bytes_at, channel);

    std::array<RangeDecoder, kPoint14Layers> point_dec{};
    std::array<bool, kPoint14Layers> point_present{};
    std::vector<RangeDecoder> other(layers - kPoint14Layers);
    std::vector<bool> present(layers, false);
    for (std::size_t k = 0; k < layers; ++k) {
      // X/Y is decoded whatever its size says (an empty one is an overrun).
      present[k] = sizes[k] != 0 || k == kReturnsXY;
      if (present[k]) {
        RangeDecoder& d = k < kPoint14Layers ? point_dec[k] : other[k - kPoint14Layers];
        d.start(at, at + sizes[k]);
      }
      at += sizes[k];
      if (k < kPoint14Layers) point_present[k] = present[k];
    }
    const std::size_t first_byte_layer = colour_layers();
    std::vector<RangeDecoder> byte_dec(other.begin() + static_cast<std::ptrdiff_t>(first_byte_layer), other.end());
    std::vector<bool> byte_present(present.begin() + static_cast<std::ptrdiff_t>(kPoint14Layers + first_byte_layer),
                                   present.end());
    RangeDecoder* rgb = colour_ && present[kPoint14Layers] ? &other[0] : nullptr;
    RangeDecoder* nir = colour_ && layout_.nir && present[kPoint14Layers + 1] ? &other[1] : nullptr;

    for (std::size_t i = 1; i < n; ++i) {
      std::uint8_t* rec = out + i * len;
      channel = point_.decode(point_dec, point_present, rec);
      if (colour_) colour_->decode(rgb, nir, rec + colour_at, channel);
      if (bytes_) bytes_->decode(byte_dec, byte_present, rec + bytes_at, channel);
    }
    return total;
  }

 private:
  std::size_t colour_size() const { return layout_.rgb ? (layout_.nir ? 8 : 6) : 0; }
  std::size_t colour_layers() const { return layout_.rgb ? (layout_.nir ? 2 : 1) : 0; }
  std::size_t layer_count() const { return kPoint14Layers + colour_layers() + layout_.extra_bytes; }
  static void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
    std::uint8_t b[4];
    store(b, v);
    out.insert(out.end(), b, b + 4);
  }

  ChunkLayout layout_;
  Point14Coder point_;
  std::optional<Colour14Coder> colour_;
  std::optional<Bytes14Coder> bytes_;
  std::vector<std::vector<std::uint8_t>> buffers_;
};

}  // namespace

struct ChunkEncoder::Impl {
  explicit Impl(const ChunkLayout& l) {
    if (l.layered) {
      layered.emplace(l, false);
    } else {
      pointwise.emplace(l, false);
    }
  }
  std::optional<PointwiseCoder> pointwise;
  std::optional<LayeredCoder> layered;
};

ChunkEncoder::ChunkEncoder(const ChunkLayout& layout) : impl_(std::make_unique<Impl>(layout)) {}
ChunkEncoder::~ChunkEncoder() = default;
ChunkEncoder::ChunkEncoder(ChunkEncoder&&) noexcept = default;
ChunkEncoder& ChunkEncoder::operator=(ChunkEncoder&&) noexcept = default;

void ChunkEncoder::encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out) {
  if (n == 0) return;
  if (impl_->layered) {
    impl_->layered->encode(records, n, out);
  } else {
    impl_->pointwise->encode(records, n, out);
  }
}

struct ChunkDecoder::Impl {
  explicit Impl(const ChunkLayout& l) {
    if (l.layered) {
      layered.emplace(l, true);
    } else {
      pointwise.emplace(l, true);
    }
  }
  std::optional<PointwiseCoder> pointwise;
  std::optional<LayeredCoder> layered;
};

ChunkDecoder::ChunkDecoder(const ChunkLayout& layout) : impl_(std::make_unique<Impl>(layout)) {}
ChunkDecoder::~ChunkDecoder() = default;
ChunkDecoder::ChunkDecoder(ChunkDecoder&&) noexcept = default;
ChunkDecoder& ChunkDecoder::operator=(ChunkDecoder&&) noexcept = default;

std::size_t ChunkDecoder::decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out) {
  if (n == 0) return 0;
  return impl_->layered ? impl_->layered->decode(data, size, n, out) : impl_->pointwise->decode(data, size, n, out);
}

std::vector<std::uint8_t> encode_chunk_table(const std::vector<ChunkEntry>& chunks, bool with_points) {
  std::vector<std::uint8_t> out;
  if (chunks.empty()) return out;
  RangeEncoder e(out);
  IntegerCoder ic(32, 2, false);
  ChunkEntry prev;
  for (const auto& c : chunks) {
    if (with_points) ic.encode(e, static_cast<std::int32_t>(prev.points), static_cast<std::int32_t>(c.points), 0);
    ic.encode(e, static_cast<std::int32_t>(prev.bytes), static_cast<std::int32_t>(c.bytes), 1);
    prev = c;
  }
  e.finish();
  return out;
}

std::vector<ChunkEntry> decode_chunk_table(const std::uint8_t* data, std::size_t size, std::size_t count,
                                           bool with_points) {
  std::vector<ChunkEntry> chunks(count);
  if (count == 0) return chunks;
  RangeDecoder d;
  d.start(data, data + size);
  IntegerCoder ic(32, 2, true);
  ChunkEntry prev;
  for (auto& c : chunks) {
    if (with_points) c.points = static_cast<std::uint32_t>(ic.decode(d, static_cast<std::int32_t>(prev.points), 0));
    c.bytes = static_cast<std::uint32_t>(ic.decode(d, static_cast<std::int32_t>(prev.bytes), 1));
    prev = c;
  }
  return chunks;
}

}  // namespace geoanchor::io::laz
