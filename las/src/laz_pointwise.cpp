// The pointwise chunk kind (LASzip's compressor 2, point formats 0-3; see
// laz_chunk.hpp): POINT10 v2, GPSTIME11 v2, RGB12 v2, BYTE v2, each point
// coding its items in turn in one arithmetic-coded stream.

#include <array>
#include <cstring>
#include <optional>

#include "laz_chunk_kinds.hpp"
#include "laz_entropy.hpp"
#include "laz_gps_time.hpp"
#include "laz_item_common.hpp"
#include "laz_rgb.hpp"

namespace geoanchor::io::laz {
namespace {

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
    const auto intensity = get<std::uint16_t>(item + 12);
    const auto source = get<std::uint16_t>(item + 18);
    const auto last_source = get<std::uint16_t>(last_ + 18);
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
    const auto z = get<std::int32_t>(item + 8);
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
        store(last_ + 18, static_cast<std::uint16_t>(source_.decode(d, get<std::uint16_t>(last_ + 18), 0)));
      }
    }
    const std::int32_t dx = dx_.decode(d, mx_[m].get(), n == 1);
    mx_[m].add(dx);
    store(last_, wrap_add(get<std::int32_t>(last_), dx));
    const std::int32_t dy = dy_.decode(d, my_[m].get(), (n == 1) + y_context(dx_.k()));
    my_[m].add(dy);
    store(last_ + 4, wrap_add(get<std::int32_t>(last_ + 4), dy));
    const std::int32_t z = z_.decode(d, heights_[l], (n == 1) + z_context((dx_.k() + dy_.k()) / 2));
    heights_[l] = z;
    store(last_ + 8, z);
    std::memcpy(out, last_, 20);
  }

 private:
  std::int32_t difference(const std::uint8_t* item, std::size_t at) const {
    return static_cast<std::int32_t>(get<std::uint32_t>(item + at) - get<std::uint32_t>(last_ + at));
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

class PointwiseCoder final : public ChunkCoder {
 public:
  PointwiseCoder(const ChunkLayout& layout, bool decoding)
      : layout_(layout), decoding_(decoding), point_(decoding) {
    if (layout.gps_time) gps_.emplace(true, decoding);
    if (layout.rgb) rgb_.emplace(decoding);
    if (layout.extra_bytes) bytes_.emplace(layout.extra_bytes, decoding);
  }

  void encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out) override {
    const std::size_t len = layout_.record_length;
    out.insert(out.end(), records, records + len);
    reset(records);
    RangeEncoder e(out);
    for (std::size_t i = 1; i < n; ++i) {
      const std::uint8_t* rec = records + i * len;
      point_.encode(e, rec);
      std::size_t at = 20;
      if (gps_) {
        gps_->encode(e, get<std::uint64_t>(rec + at));
        at += 8;
      }
      if (rgb_) {
        encode_rgb(e, *rgb_, last_rgb_.data(), rec + at);
        for (std::size_t k = 0; k < 3; ++k) last_rgb_[k] = get<std::uint16_t>(rec + at + 2 * k);
        at += 6;
      }
      if (bytes_) bytes_->encode(e, rec + at);
    }
    e.finish();
  }

  std::size_t decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out) override {
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
      gps_->reset(get<std::uint64_t>(first + at));
      at += 8;
    }
    if (rgb_) {
      rgb_->reset();
      for (std::size_t k = 0; k < 3; ++k) last_rgb_[k] = get<std::uint16_t>(first + at + 2 * k);
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

}  // namespace

std::unique_ptr<ChunkCoder> make_pointwise_coder(const ChunkLayout& layout, bool decoding) {
  return std::make_unique<PointwiseCoder>(layout, decoding);
}

}  // namespace geoanchor::io::laz
