#pragma once
// The colour coders of both chunk kinds: RGB (RGB12 v2, and the RGB layer
// of RGB14/RGBNIR14 v3) and NIR (RGBNIR14 v3).

#include <array>
#include <cstddef>
#include <cstdint>

#include "laz_entropy.hpp"
#include "laz_item_common.hpp"

namespace geoanchor::io::laz {

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
inline std::uint32_t encode_rgb(RangeEncoder& e, RgbModels& m, const std::uint16_t* last, const std::uint8_t* item) {
  const std::uint16_t c[3] = {get<std::uint16_t>(item), get<std::uint16_t>(item + 2), get<std::uint16_t>(item + 4)};
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

inline void decode_rgb(RangeDecoder& d, RgbModels& m, const std::uint16_t* last, std::uint16_t* c) {
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

inline std::uint32_t encode_nir(RangeEncoder& e, NirModels& m, std::uint16_t last, std::uint16_t v) {
  const std::uint32_t sym = std::uint32_t{lo8(last) != lo8(v)} | (std::uint32_t{hi8(last) != hi8(v)} << 1);
  e.encode_symbol(m.used, sym);
  if (sym & 1) e.encode_symbol(m.low, low_byte(static_cast<std::uint32_t>(lo8(v) - lo8(last))));
  if (sym & 2) e.encode_symbol(m.high, low_byte(static_cast<std::uint32_t>(hi8(v) - hi8(last))));
  return sym;
}

inline std::uint16_t decode_nir(RangeDecoder& d, NirModels& m, std::uint16_t last) {
  const std::uint32_t sym = d.decode_symbol(m.used);
  const std::uint32_t l = sym & 1 ? low_byte(d.decode_symbol(m.low) + static_cast<std::uint32_t>(lo8(last)))
                                  : static_cast<std::uint32_t>(lo8(last));
  const std::uint32_t h = sym & 2 ? low_byte(d.decode_symbol(m.high) + static_cast<std::uint32_t>(hi8(last)))
                                  : static_cast<std::uint32_t>(hi8(last));
  return static_cast<std::uint16_t>(l | (h << 8));
}

}  // namespace geoanchor::io::laz
