// The layered chunk kind (LASzip's compressor 3, point formats 6-8; see
// laz_chunk.hpp): POINT14 v3 in nine layers, RGB14 / RGBNIR14 v3, BYTE14
// v3, each layer its own arithmetic-coded stream.
//
// Each of the four scanner channels has its own context (models and last
// point); a context starts, when its channel first appears in a chunk,
// from the last point of the channel before it.

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

// Return-number contexts of POINT14 (r and n of 4 bits), as POINT10's
// (laz_pointwise.cpp): six map contexts, eight levels
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
    gps.reset(get<std::uint64_t>(from + 22));
    for (auto& m : mx) m.reset();
    for (auto& m : my) m.reset();
    heights.fill(get<std::int32_t>(from + 8));
    intensities.fill(get<std::uint16_t>(from + 12));
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

    const bool source_changed = get<std::uint16_t>(item + 20) != get<std::uint16_t>(last + 20);
    const bool gps_changed = get<std::uint64_t>(item + 22) != get<std::uint64_t>(last + 22);
    const bool scan_changed = get<std::int16_t>(item + 18) != get<std::int16_t>(last + 18);
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

    const auto dx = static_cast<std::int32_t>(get<std::uint32_t>(item) - get<std::uint32_t>(last));
    cur->dx.encode(xy, cur->mx[slot].get(), dx, n == 1);
    cur->mx[slot].add(dx);
    const auto dy = static_cast<std::int32_t>(get<std::uint32_t>(item + 4) - get<std::uint32_t>(last + 4));
    cur->dy.encode(xy, cur->my[slot].get(), dy, (n == 1) + y_context(cur->dx.k()));
    cur->my[slot].add(dy);
    const auto z = get<std::int32_t>(item + 8);
    cur->z.encode(*e[kZ], cur->heights[l], z, (n == 1) + z_context((cur->dx.k() + cur->dy.k()) / 2));
    cur->heights[l] = z;

    const std::uint32_t cls = item[16], last_cls = last[16];
    changed[kClassification] = changed[kClassification] || cls != last_cls;
    e[kClassification]->encode_symbol(cur->classification.at(((last_cls & 0x1Fu) << 1) + (cpr == 3)), cls);

    const std::uint32_t flags = flags_of(item), last_flags = flags_of(last);
    changed[kFlags] = changed[kFlags] || flags != last_flags;
    e[kFlags]->encode_symbol(cur->flags.at(last_flags), flags);

    const auto intensity = get<std::uint16_t>(item + 12);
    changed[kIntensity] = changed[kIntensity] || intensity != get<std::uint16_t>(last + 12);
    const std::size_t islot = (cpr << 1) | std::uint32_t{gps_changed};
    cur->intensity.encode(*e[kIntensity], cur->intensities[islot], intensity, cpr);
    cur->intensities[islot] = intensity;

    if (scan_changed) {
      changed[kScanAngle] = true;
      cur->scan_angle.encode(*e[kScanAngle], get<std::int16_t>(last + 18), get<std::int16_t>(item + 18), gps_changed);
    }
    changed[kUserData] = changed[kUserData] || item[17] != last[17];
    e[kUserData]->encode_symbol(cur->user_data.at(last[17] / 4u), item[17]);
    if (source_changed) {
      changed[kPointSource] = true;
      cur->source.encode(*e[kPointSource], get<std::uint16_t>(last + 20), get<std::uint16_t>(item + 20), 0);
    }
    if (gps_changed) {
      changed[kGpsTime] = true;
      cur->gps.encode(*e[kGpsTime], get<std::uint64_t>(item + 22));
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
    store(last, get<std::uint32_t>(last) + static_cast<std::uint32_t>(dx));
    const std::int32_t dy = cur->dy.decode(xy, cur->my[slot].get(), (n == 1) + y_context(cur->dx.k()));
    cur->my[slot].add(dy);
    store(last + 4, get<std::uint32_t>(last + 4) + static_cast<std::uint32_t>(dy));
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
      store(last + 18, static_cast<std::uint16_t>(cur->scan_angle.decode(d[kScanAngle], get<std::int16_t>(last + 18), gps_changed)));
    }
    if (present[kUserData]) last[17] = low_byte(d[kUserData].decode_symbol(cur->user_data.at(last[17] / 4u)));
    if (present[kPointSource] && (sym & 32)) {
      store(last + 20, static_cast<std::uint16_t>(cur->source.decode(d[kPointSource], get<std::uint16_t>(last + 20), 0)));
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
    for (std::size_t k = 0; k < 3; ++k) last[k] = get<std::uint16_t>(item + 2 * k);
    if (nir_) {
      const auto v = get<std::uint16_t>(item + 6);
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
    for (std::size_t k = 0; k < 3; ++k) c.last[k] = get<std::uint16_t>(from + 2 * k);
    c.last[3] = nir_ ? get<std::uint16_t>(from + 6) : 0;
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

class LayeredCoder final : public ChunkCoder {
 public:
  LayeredCoder(const ChunkLayout& layout, bool decoding) : layout_(layout), point_(decoding) {
    if (layout.rgb) colour_.emplace(layout.nir, decoding);
    if (layout.extra_bytes) bytes_.emplace(layout.extra_bytes, decoding);
  }

  void encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out) override {
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

  std::size_t decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out) override {
    const std::size_t len = layout_.record_length;
    const std::size_t layers = layer_count();
    if (size < len + 4 * (1 + layers)) throw StreamOverrun{};
    std::memcpy(out, data, len);
    // The chunk's own point count must be the one the header and the chunk
    // table give it: fewer would drop the rest silently (issue 40 point 8).
    const auto stored = get<std::uint32_t>(data + len);
    if (stored != n) throw ChunkCountMismatch{stored};
    const std::uint8_t* at = data + len + 4;
    std::vector<std::size_t> sizes(layers);
    std::size_t total = len + 4 * (1 + layers);
    for (std::size_t k = 0; k < layers; ++k, at += 4) {
      sizes[k] = get<std::uint32_t>(at);
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

std::unique_ptr<ChunkCoder> make_layered_coder(const ChunkLayout& layout, bool decoding) {
  return std::make_unique<LayeredCoder>(layout, decoding);
}

}  // namespace geoanchor::io::laz
