#include "geoanchor/gui/palette.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace geoanchor::gui::palette {

Rgb diverging(double t) {
  // ColorBrewer PuOr, 5 classes, from −1 to +1.
  static constexpr std::array<Rgb, 5> kStops{{{94, 60, 153}, {178, 171, 210}, {247, 247, 247}, {253, 184, 99}, {230, 97, 1}}};
  if (!std::isfinite(t)) return kLeftOut;
  const double u = (std::clamp(t, -1.0, 1.0) + 1.0) * 2.0;  // 0..4
  const auto i = std::min<std::size_t>(static_cast<std::size_t>(u), 3);
  const double f = u - static_cast<double>(i);
  const auto mix = [f](std::uint8_t a, std::uint8_t b) {
    return static_cast<std::uint8_t>(std::lround(static_cast<double>(a) + f * (static_cast<double>(b) - static_cast<double>(a))));
  };
  return {mix(kStops[i].r, kStops[i + 1].r), mix(kStops[i].g, kStops[i + 1].g), mix(kStops[i].b, kStops[i + 1].b)};
}

}  // namespace geoanchor::gui::palette
