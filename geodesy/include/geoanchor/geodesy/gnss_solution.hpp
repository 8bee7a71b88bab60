#pragma once
// The GNSS solution type of a surveyed position: how its receiver (or the
// post-processing) resolved it. Control sets carry it per mark (a `solution`
// column or key), network inputs per GNSS measurement, LAS tiles per point
// (an extra-bytes attribute "gnss_solution", uint8, the codes below).
//
// Order, best first (docs/commands/fit.md#gnss-solution-types):
//   fixed          carrier phase, ambiguities fixed in real time (RTK fixed)    ~ 1-2 cm
//   ppk            carrier phase, post-processed kinematic                     ~ 1-2 cm
//   float          carrier phase, ambiguities not fixed (RTK float)             ~ 0.1-0.5 m
//   dgps           code differential (DGNSS)                                   ~ 0.5-1 m
//   sbas           satellite-based augmentation (EGNOS, WAAS)                  ~ 1-2 m
//   standalone     single point positioning, no correction                     ~ 2-5 m
//   dead_reckoned  no GNSS position at all (inertial or odometry)              unbounded
// `fixed` ranks above `ppk` because it states that the ambiguities were
// fixed; `ppk` states the processing, whose fix the label alone does not
// certify. Both are ambiguity-resolved carrier phase in practice and both
// are kept by default; `float` and worse are excluded from fits and
// adjustments unless weighted on request (kSolutionSigmaFactor).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace geoanchor::geodesy {

enum class GnssSolution : std::uint8_t {
  fixed = 1,
  ppk = 2,
  floating = 3,  // written "float"
  dgps = 4,
  sbas = 5,
  standalone = 6,
  dead_reckoned = 7,
};

inline constexpr std::size_t kGnssSolutionCount = 7;

// Best first; the index into per-class tables (solution_index).
inline constexpr std::array<GnssSolution, kGnssSolutionCount> kGnssSolutions = {
    GnssSolution::fixed, GnssSolution::ppk,        GnssSolution::floating,     GnssSolution::dgps,
    GnssSolution::sbas,  GnssSolution::standalone, GnssSolution::dead_reckoned};

// 0 for fixed … 6 for dead_reckoned (the order above).
constexpr std::size_t solution_index(GnssSolution s) { return static_cast<std::size_t>(s) - 1; }

// "fixed", "ppk", "float", "dgps", "sbas", "standalone", "dead_reckoned".
constexpr std::string_view to_string(GnssSolution s) {
  switch (s) {
    case GnssSolution::fixed: return "fixed";
    case GnssSolution::ppk: return "ppk";
    case GnssSolution::floating: return "float";
    case GnssSolution::dgps: return "dgps";
    case GnssSolution::sbas: return "sbas";
    case GnssSolution::standalone: return "standalone";
    case GnssSolution::dead_reckoned: return "dead_reckoned";
  }
  return "?";
}

// The list of values, for messages: "fixed, ppk, float, dgps, sbas, standalone, dead_reckoned".
inline std::string gnss_solution_names() {
  std::string out;
  for (const auto s : kGnssSolutions) out += (out.empty() ? "" : ", ") + std::string(to_string(s));
  return out;
}

// Exactly one of the names above (lower case, as written); nullopt otherwise.
constexpr std::optional<GnssSolution> parse_gnss_solution(std::string_view text) {
  for (const auto s : kGnssSolutions) {
    if (to_string(s) == text) return s;
  }
  return std::nullopt;
}

// The LAS extra-bytes code (uint8): 1 fixed … 7 dead_reckoned; any other
// code (0 included) is no solution type and is refused where it is read.
constexpr std::optional<GnssSolution> gnss_solution_from_code(unsigned code) {
  if (code < 1 || code > kGnssSolutionCount) return std::nullopt;
  return static_cast<GnssSolution>(code);
}

// Ambiguity-fixed carrier phase, in real time or post-processed: what the
// "RTK-fixed share" of the map metadata counts (fixed and ppk).
constexpr bool is_rtk_fixed(GnssSolution s) { return s == GnssSolution::fixed || s == GnssSolution::ppk; }

// Whether fits and adjustments use the class by default (fixed, ppk).
constexpr bool kept_by_default(GnssSolution s) { return is_rtk_fixed(s); }

// With weighting (fit/adjust --solution-weighting), the class's standard
// deviations are multiplied by this factor (its weight divided by the
// square): the ratio of the class's typical horizontal accuracy to an
// RTK-fixed position's 2 cm — float 0.2 m, dgps 0.5 m, sbas 1.5 m,
// standalone 5 m. 0 for dead_reckoned: no factor bounds the drift of a
// position without GNSS, so it stays excluded even then.
constexpr double solution_sigma_factor(GnssSolution s) {
  switch (s) {
    case GnssSolution::fixed: return 1.0;
    case GnssSolution::ppk: return 1.0;
    case GnssSolution::floating: return 10.0;
    case GnssSolution::dgps: return 25.0;
    case GnssSolution::sbas: return 75.0;
    case GnssSolution::standalone: return 250.0;
    case GnssSolution::dead_reckoned: return 0.0;
  }
  return 0.0;
}

// How fits and adjustments treat the classes below ppk.
enum class SolutionPolicy {
  exclude,  // default: float and worse are not used (tested against the result, as use = 0 marks)
  weight,   // float, dgps, sbas, standalone used with sigmas × solution_sigma_factor; dead_reckoned excluded
};

constexpr std::string_view to_string(SolutionPolicy p) { return p == SolutionPolicy::exclude ? "exclude" : "weight"; }

// Whether a mark of class `s` enters the fit under `p`, and the factor on
// its sigmas (1 when it is not weighted, also when it is left out: a mark
// left out is still tested against the fit with its own sigmas).
constexpr bool used_under(GnssSolution s, SolutionPolicy p) {
  return kept_by_default(s) || (p == SolutionPolicy::weight && solution_sigma_factor(s) > 0.0);
}
constexpr double sigma_factor_under(GnssSolution s, SolutionPolicy p) {
  return kept_by_default(s) || !used_under(s, p) ? 1.0 : solution_sigma_factor(s);
}

// Counts per class, in the order of kGnssSolutions.
struct SolutionCounts {
  std::array<std::uint64_t, kGnssSolutionCount> count{};
  std::uint64_t total() const {
    std::uint64_t n = 0;
    for (const auto c : count) n += c;
    return n;
  }
  std::uint64_t rtk_fixed() const {
    return count[solution_index(GnssSolution::fixed)] + count[solution_index(GnssSolution::ppk)];
  }
  // 100 × rtk_fixed / total; nullopt without any count.
  std::optional<double> rtk_fixed_percent() const {
    const std::uint64_t n = total();
    if (n == 0) return std::nullopt;
    return 100.0 * static_cast<double>(rtk_fixed()) / static_cast<double>(n);
  }
};

}  // namespace geoanchor::geodesy
