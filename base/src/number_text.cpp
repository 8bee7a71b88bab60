#include "geoanchor/base/number_text.hpp"

#include <charconv>
#include <cmath>

namespace geoanchor {

std::optional<double> parse_finite_double(std::string_view text) {
  if (text.empty()) return std::nullopt;
  double v = 0.0;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(first, last, v, std::chars_format::general);
  if (ec != std::errc() || ptr != last || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string format_shortest(double v) {
  char buf[64];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  if (ec != std::errc()) return "nan";
  return std::string(buf, ptr);
}

std::string format_fixed(double v, int decimals) {
  char buf[512];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  if (ec != std::errc()) return "nan";
  return std::string(buf, ptr);
}

}  // namespace geoanchor
