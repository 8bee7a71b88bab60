#pragma once
// The entropy coder of LAZ: a 32-bit range coder (base/length arithmetic
// with carry propagation and byte-wise renormalisation) driven by adaptive
// multi-symbol models and adaptive binary models, plus raw bits; and the
// integer coder built on it, which codes the difference between a value
// and its prediction as an interval index k and an offset inside it.
//
// Sources, read to learn the bit stream, none copied:
// - M. Isenburg, "LASzip: lossless compression of LiDAR data",
//   Photogrammetric Engineering & Remote Sensing 79(2), 2013, pp. 209-217
//   (sections on the arithmetic coder and on the corrector coding);
// - A. Said, "Introduction to Arithmetic Coding - Theory and Practice",
//   HP Labs HPL-2004-76, 2004: the coder LASzip adapted (FastAC);
// - the LASzip library's sources (Apache-2.0 / LGPL, github.com/LASzip) and
//   laz-perf (Apache-2.0), read to pin down the constants, the model update
//   schedule and the order of operations that the format depends on.
//
// Everything here is bit-exact with LASzip: a model's counts, its update
// cycle, the rescaling of its cumulative distribution and the coder's
// interval arithmetic are those of the format, so that a stream written by
// either side decodes on the other. The code is ours; where a LASzip
// quantity has a different name here, the comment says which.
//
// Robustness: the decoder reads only inside the span it was given. A byte
// past its end throws StreamOverrun (a malformed or truncated chunk), so a
// corrupt stream can neither read out of bounds nor run forever: every
// decoding step consumes either a symbol or a bounded number of bytes, and
// every loop in the item coders is bounded by the number of points.

#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

namespace geoanchor::io::laz {

// Thrown by RangeDecoder when a stream ends before its decoding does.
struct StreamOverrun {};

// Thrown by item decoders when a decoded value is impossible (the stream
// is corrupt though it did not run out).
struct StreamCorrupt {
  const char* what;
};

// Thrown by a chunk decoder when the chunk holds another number of points
// than it was asked to decode (a layered chunk states its own count).
struct ChunkCountMismatch {
  std::uint32_t stored;
};

// The interval is renormalised (a byte shifted out) whenever its length
// falls below 2^24; it starts as the whole 32-bit range.
inline constexpr std::uint32_t kMinLength = 1u << 24;
inline constexpr std::uint32_t kFullLength = 0xFFFFFFFFu;
// Binary models keep their probability of a 0 in 13 bits; symbol models
// their cumulative distribution in 15 bits.
inline constexpr unsigned kBitScaleBits = 13;
inline constexpr std::uint32_t kBitCountLimit = 1u << kBitScaleBits;
inline constexpr unsigned kSymbolScaleBits = 15;
inline constexpr std::uint32_t kSymbolCountLimit = 1u << kSymbolScaleBits;

// An adaptive model of one binary decision.
class BitModel {
 public:
  BitModel() { reset(); }
  // The equiprobable start, with frequent updates at first.
  void reset() {
    zeros_ = 1;
    seen_ = 2;
    p0_ = 1u << (kBitScaleBits - 1);
    cycle_ = 4;
    until_update_ = 4;
  }

 private:
  friend class RangeEncoder;
  friend class RangeDecoder;

  // Recomputes the probability after `cycle_` decisions; halves the counts
  // past the limit, and lengthens the cycle up to 64 decisions.
  void adapt() {
    seen_ += cycle_;
    if (seen_ > kBitCountLimit) {
      seen_ = (seen_ + 1) >> 1;
      zeros_ = (zeros_ + 1) >> 1;
      if (zeros_ == seen_) ++seen_;
    }
    const std::uint32_t scale = 0x80000000u / seen_;
    p0_ = (zeros_ * scale) >> (31 - kBitScaleBits);
    cycle_ = (5 * cycle_) >> 2;
    if (cycle_ > 64) cycle_ = 64;
    until_update_ = cycle_;
  }

  std::uint32_t p0_ = 0;      // probability of a 0, in units of 2^-13 (never 0, never 2^13)
  std::uint32_t zeros_ = 0;   // zeros counted
  std::uint32_t seen_ = 0;    // decisions counted (more than zeros_)
  std::uint32_t cycle_ = 0;   // decisions between two updates
  std::uint32_t until_update_ = 0;
};

// An adaptive model of a symbol in [0, symbols), 2 <= symbols <= 2048.
// A decoding model of more than 16 symbols keeps a lookup table that
// narrows the search for a symbol to a few candidates.
class SymbolModel {
 public:
  SymbolModel(std::uint32_t symbols, bool decoding)
      : symbols_(symbols), last_(symbols - 1) {
    std::uint32_t table_bits = 0;
    if (decoding && symbols > 16) {
      table_bits = 3;
      while (symbols > (1u << (table_bits + 2))) ++table_bits;
      table_size_ = 1u << table_bits;
      table_shift_ = kSymbolScaleBits - table_bits;
    }
    storage_ = std::make_unique<std::uint32_t[]>(2 * std::size_t{symbols} + (table_size_ ? table_size_ + 2 : 0));
    cdf_ = storage_.get();
    counts_ = cdf_ + symbols;
    lookup_ = table_size_ ? counts_ + symbols : nullptr;
  }

  // Every symbol counted once; updates come every (symbols + 6) / 2 symbols.
  // Done on the model's next use: a chunk resets every model, most of them
  // unused in a small chunk (a COPC node), and the state is the same.
  void reset() { stale_ = true; }
  std::uint32_t symbols() const { return symbols_; }

 private:
  friend class RangeEncoder;
  friend class RangeDecoder;

  void refresh() {
    stale_ = false;
    for (std::uint32_t k = 0; k < symbols_; ++k) counts_[k] = 1;
    total_ = 0;
    cycle_ = symbols_;
    adapt();
    cycle_ = (symbols_ + 6) >> 1;
    until_update_ = cycle_;
  }

  // Adds the symbols counted since the last update, halves the counts past
  // the limit, rebuilds the cumulative distribution (scaled to 2^15) and,
  // when decoding, the lookup table; lengthens the update cycle by 5/4 up to
  // 8 × (symbols + 6).
  void adapt() {
    total_ += cycle_;
    if (total_ > kSymbolCountLimit) {
      total_ = 0;
      for (std::uint32_t k = 0; k < symbols_; ++k) {
        counts_[k] = (counts_[k] + 1) >> 1;
        total_ += counts_[k];
      }
    }
    const std::uint32_t scale = 0x80000000u / total_;
    std::uint32_t sum = 0;
    for (std::uint32_t k = 0; k < symbols_; ++k) {
      cdf_[k] = (scale * sum) >> (31 - kSymbolScaleBits);
      sum += counts_[k];
    }
    if (lookup_) {
      // lookup_[t]: the last symbol whose cumulative count is at most
      // t << table_shift_; a value in [t, t + 1) << table_shift_ decodes to a
      // symbol in [lookup_[t], lookup_[t + 1]].
      std::uint32_t k = 0;
      for (std::uint32_t t = 0; t <= table_size_; ++t) {
        const std::uint32_t edge = t << table_shift_;
        while (k < last_ && cdf_[k + 1] <= edge) ++k;
        lookup_[t] = k;
      }
      lookup_[table_size_ + 1] = last_;
    }
    cycle_ = (5 * cycle_) >> 2;
    const std::uint32_t max_cycle = (symbols_ + 6) << 3;
    if (cycle_ > max_cycle) cycle_ = max_cycle;
    until_update_ = cycle_;
  }

  std::uint32_t symbols_;
  std::uint32_t last_;
  std::uint32_t total_ = 0;
  std::uint32_t cycle_ = 0;
  std::uint32_t until_update_ = 0;
  std::uint32_t table_size_ = 0;
  std::uint32_t table_shift_ = 0;
  std::unique_ptr<std::uint32_t[]> storage_;
  std::uint32_t* cdf_ = nullptr;     // cumulative counts, scaled to 2^15; cdf_[0] = 0
  std::uint32_t* counts_ = nullptr;  // per symbol, at least 1
  std::uint32_t* lookup_ = nullptr;  // decoding only: table_size_ + 2 entries
  bool stale_ = true;                // reset() pending
};

// Appends the coded bytes of one stream to a byte vector.
class RangeEncoder {
 public:
  // Bytes go to the end of `out`; those already there are left alone.
  explicit RangeEncoder(std::vector<std::uint8_t>& out) : out_(out), first_(out.size()) {}

  void encode_bit(BitModel& m, std::uint32_t bit) {
    const std::uint32_t x = m.p0_ * (length_ >> kBitScaleBits);
    if (bit == 0) {
      length_ = x;
      ++m.zeros_;
    } else {
      add_to_base(x);
      length_ -= x;
    }
    if (length_ < kMinLength) renormalise();
    if (--m.until_update_ == 0) m.adapt();
  }

  void encode_symbol(SymbolModel& m, std::uint32_t symbol) {
    if (m.stale_) m.refresh();
    if (symbol == m.last_) {
      const std::uint32_t x = m.cdf_[symbol] * (length_ >> kSymbolScaleBits);
      add_to_base(x);
      length_ -= x;
    } else {
      length_ >>= kSymbolScaleBits;
      const std::uint32_t x = m.cdf_[symbol] * length_;
      add_to_base(x);
      length_ = m.cdf_[symbol + 1] * length_ - x;
    }
    if (length_ < kMinLength) renormalise();
    ++m.counts_[symbol];
    if (--m.until_update_ == 0) m.adapt();
  }

  // `bits` (1..32) raw bits of `value`; more than 19 go as 16 and the rest.
  void write_bits(unsigned bits, std::uint32_t value) {
    if (bits > 19) {
      write_short(static_cast<std::uint16_t>(value & 0xFFFFu));
      value >>= 16;
      bits -= 16;
    }
    length_ >>= bits;
    add_to_base(value * length_);
    if (length_ < kMinLength) renormalise();
  }
  void write_short(std::uint16_t value) {
    length_ >>= 16;
    add_to_base(std::uint32_t{value} * length_);
    if (length_ < kMinLength) renormalise();
  }
  // Low 16 bits first.
  void write_int(std::uint32_t value) {
    write_short(static_cast<std::uint16_t>(value & 0xFFFFu));
    write_short(static_cast<std::uint16_t>(value >> 16));
  }

  // Ends the stream: one or two bytes that pin a value inside the final
  // interval, then zeros so that the stream is 4 bytes longer than the
  // number of renormalisations (the decoder reads exactly that many).
  void finish() {
    bool third_zero = true;
    if (length_ > 2 * kMinLength) {
      add_to_base(kMinLength);
      length_ = kMinLength >> 1;
    } else {
      add_to_base(kMinLength >> 1);
      length_ = kMinLength >> 9;
      third_zero = false;
    }
    renormalise();
    out_.push_back(0);
    out_.push_back(0);
    if (third_zero) out_.push_back(0);
  }

 private:
  void add_to_base(std::uint32_t x) {
    const std::uint32_t before = base_;
    base_ += x;
    if (base_ < before) propagate_carry();
  }
  // The carry runs back through the bytes already out (0xFF becomes 0x00).
  // It cannot pass this stream's first byte: the code value stays below 1.
  void propagate_carry() {
    std::size_t at = out_.size();
    while (at > first_) {
      --at;
      if (out_[at] != 0xFF) {
        ++out_[at];
        return;
      }
      out_[at] = 0;
    }
  }
  void renormalise() {
    do {
      out_.push_back(static_cast<std::uint8_t>(base_ >> 24));
      base_ <<= 8;
      length_ <<= 8;
    } while (length_ < kMinLength);
  }

  std::vector<std::uint8_t>& out_;
  std::size_t first_;
  std::uint32_t base_ = 0;
  std::uint32_t length_ = kFullLength;
};

// Decodes one stream held in memory, [begin, end).
class RangeDecoder {
 public:
  RangeDecoder() = default;
  // Starts on a stream; reads its first four bytes.
  void start(const std::uint8_t* begin, const std::uint8_t* end) {
    at_ = begin;
    end_ = end;
    length_ = kFullLength;
    value_ = 0;
    for (int i = 0; i < 4; ++i) value_ = (value_ << 8) | next_byte();
  }
  // Bytes read so far from `begin`.
  const std::uint8_t* position() const { return at_; }

  std::uint32_t decode_bit(BitModel& m) {
    const std::uint32_t x = m.p0_ * (length_ >> kBitScaleBits);
    std::uint32_t bit;
    if (value_ < x) {
      bit = 0;
      length_ = x;
      ++m.zeros_;
    } else {
      bit = 1;
      value_ -= x;
      length_ -= x;
    }
    if (length_ < kMinLength) renormalise();
    if (--m.until_update_ == 0) m.adapt();
    return bit;
  }

  std::uint32_t decode_symbol(SymbolModel& m) {
    if (m.stale_) m.refresh();
    std::uint32_t symbol, low, high = length_;
    length_ >>= kSymbolScaleBits;
    if (m.lookup_) {
      // The symbol whose cumulative count is the last at or below value/length.
      const std::uint32_t target = value_ / length_;
      std::uint32_t t = target >> m.table_shift_;
      if (t > m.table_size_) t = m.table_size_;  // only a corrupt stream gets here
      symbol = m.lookup_[t];
      std::uint32_t top = m.lookup_[t + 1];
      while (symbol < top) {
        const std::uint32_t mid = (symbol + top + 1) >> 1;
        if (m.cdf_[mid] <= target) {
          symbol = mid;
        } else {
          top = mid - 1;
        }
      }
      low = m.cdf_[symbol] * length_;
      if (symbol != m.last_) high = m.cdf_[symbol + 1] * length_;
    } else {
      // Few symbols: bisection on the products, no division.
      std::uint32_t lo = 0, hi = m.symbols_;
      low = 0;
      while (hi - lo > 1) {
        const std::uint32_t mid = (lo + hi) >> 1;
        const std::uint32_t edge = m.cdf_[mid] * length_;
        if (edge > value_) {
          hi = mid;
          high = edge;
        } else {
          lo = mid;
          low = edge;
        }
      }
      symbol = lo;
    }
    value_ -= low;
    length_ = high - low;
    if (length_ < kMinLength) renormalise();
    ++m.counts_[symbol];
    if (--m.until_update_ == 0) m.adapt();
    return symbol;
  }

  // `bits` (1..32) raw bits.
  std::uint32_t read_bits(unsigned bits) {
    if (bits > 19) {
      const std::uint32_t low = read_short();
      const std::uint32_t high = read_bits(bits - 16);
      return (high << 16) | low;
    }
    length_ >>= bits;
    std::uint32_t v = value_ / length_;
    value_ -= length_ * v;
    if (length_ < kMinLength) renormalise();
    return v & ((1u << bits) - 1);  // the mask only matters for a corrupt stream
  }
  std::uint32_t read_short() {
    length_ >>= 16;
    const std::uint32_t v = value_ / length_;
    value_ -= length_ * v;
    if (length_ < kMinLength) renormalise();
    return v & 0xFFFFu;
  }
  std::uint32_t read_int() {
    const std::uint32_t low = read_short();
    const std::uint32_t high = read_short();
    return (high << 16) | low;
  }

 private:
  std::uint32_t next_byte() {
    if (at_ == end_) throw StreamOverrun{};
    return *at_++;
  }
  void renormalise() {
    do {
      value_ = (value_ << 8) | next_byte();
      length_ <<= 8;
    } while (length_ < kMinLength);
  }

  const std::uint8_t* at_ = nullptr;
  const std::uint8_t* end_ = nullptr;
  std::uint32_t value_ = 0;
  std::uint32_t length_ = kFullLength;
};

// Codes an integer as the corrector c = actual − predicted, folded into the
// coder's range: first k, the index of the interval [-(2^k − 1), 2^k] that
// holds c (a symbol among bits + 1 per context), then c's place inside it:
// one adaptive bit for k = 0, an adaptive symbol of k bits for k ≤ 8, the
// top 8 bits adaptive and the rest raw for larger k. LASzip's
// IntegerCompressor with bits_high = 8 and no explicit range.
class IntegerCoder {
 public:
  // `bits`: 16 (values wrap modulo 2^16) or 32 (modulo 2^32).
  IntegerCoder(unsigned bits, unsigned contexts, bool decoding) : bits_(bits) {
    k_models_.reserve(contexts);
    for (unsigned c = 0; c < contexts; ++c) k_models_.emplace_back(bits + 1, decoding);
    offsets_.reserve(bits);
    for (unsigned k = 1; k <= bits; ++k) offsets_.emplace_back(1u << (k <= kHighBits ? k : kHighBits), decoding);
  }
  void reset() {
    for (auto& m : k_models_) m.reset();
    zero_or_one_.reset();
    for (auto& m : offsets_) m.reset();
    k_ = 0;
  }
  // The interval index of the last corrector coded (LASzip's getK()).
  unsigned k() const { return k_; }

  void encode(RangeEncoder& e, std::int32_t predicted, std::int32_t actual, unsigned context) {
    std::uint32_t diff = static_cast<std::uint32_t>(actual) - static_cast<std::uint32_t>(predicted);
    if (bits_ < 32) {  // fold into [-2^(bits-1), 2^(bits-1)): sign-extend the low bits
      const std::uint32_t sign = 1u << (bits_ - 1);
      diff = ((diff & ((1u << bits_) - 1)) ^ sign) - sign;
    }
    const auto c = static_cast<std::int32_t>(diff);
    // k: the bit length of |c| (of c − 1 for positive c, so that 2^k fits).
    const std::uint32_t magnitude = c <= 0 ? 0u - diff : diff - 1;
    unsigned k = 0;
    for (std::uint32_t m = magnitude; m != 0; m >>= 1) ++k;
    k_ = k;
    e.encode_symbol(k_models_[context], k);
    if (k == 0) {
      e.encode_bit(zero_or_one_, diff);  // c is 0 or 1
    } else if (k < 32) {
      // The offset in [0, 2^k): negative c from the bottom, positive from the middle.
      const std::uint32_t offset = c < 0 ? diff + ((1u << k) - 1) : diff - 1;
      if (k <= kHighBits) {
        e.encode_symbol(offsets_[k - 1], offset);
      } else {
        const unsigned low_bits = k - kHighBits;
        e.encode_symbol(offsets_[k - 1], offset >> low_bits);
        e.write_bits(low_bits, offset & ((1u << low_bits) - 1));
      }
    }  // k = 32: c is -2^31, nothing more to say
  }

  // The decoded value, modulo 2^bits (callers keep the bits they need).
  std::int32_t decode(RangeDecoder& d, std::int32_t predicted, unsigned context) {
    const std::uint32_t k = d.decode_symbol(k_models_[context]);
    k_ = k;
    std::uint32_t c;
    if (k == 0) {
      c = d.decode_bit(zero_or_one_);
    } else if (k < 32) {
      std::uint32_t offset;
      if (k <= kHighBits) {
        offset = d.decode_symbol(offsets_[k - 1]);
      } else {
        const unsigned low_bits = k - kHighBits;
        const std::uint32_t high = d.decode_symbol(offsets_[k - 1]);
        offset = (high << low_bits) | d.read_bits(low_bits);
      }
      c = offset >= (1u << (k - 1)) ? offset + 1 : offset - ((1u << k) - 1);
    } else {
      c = 0x80000000u;
    }
    std::uint32_t v = static_cast<std::uint32_t>(predicted) + c;
    if (bits_ < 32) v &= (1u << bits_) - 1;
    return static_cast<std::int32_t>(v);
  }

 private:
  static constexpr unsigned kHighBits = 8;
  unsigned bits_;
  unsigned k_ = 0;
  std::vector<SymbolModel> k_models_;  // per context: k in [0, bits]
  BitModel zero_or_one_;               // k = 0
  std::vector<SymbolModel> offsets_;   // [k − 1]: the offset (its top 8 bits past k = 8)
};

}  // namespace geoanchor::io::laz
