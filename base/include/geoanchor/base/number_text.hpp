#pragma once
// Strict number <-> text conversion shared by every parser and writer.
// Locale-independent (std::from_chars / std::to_chars).

#include <optional>
#include <string>
#include <string_view>

namespace geoanchor {

// The whole of `text` as a finite double: no leading '+', no spaces, no
// decimal comma, no "nan"/"inf". std::nullopt otherwise.
std::optional<double> parse_finite_double(std::string_view text);

// The shortest decimal text that reads back to exactly `v`.
std::string format_shortest(double v);

// `v` with exactly `decimals` digits after the point.
std::string format_fixed(double v, int decimals);

}  // namespace geoanchor
