#pragma once
// The GPS time coder of both chunk kinds.
//
// GPS time (GPSTIME11 v2, and the GPS time layer of POINT14 v3). The 8 bytes
// are coded as a 64-bit integer. Four sequences are tracked (interleaved
// flight lines); within one, the difference to the previous time is
// predicted as a multiple (−10..500) of the last difference.

#include <array>
#include <cstdint>

#include "laz_entropy.hpp"

namespace geoanchor::io::laz {

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

}  // namespace geoanchor::io::laz
