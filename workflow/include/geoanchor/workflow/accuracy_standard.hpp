#pragma once
// Accuracy standards (adjust --standard NAME|FILE; docs/standards.md): a
// standard's criteria read from a JSON file (schema
// geoanchor.accuracy-standard/1; the shipped ones in data/standards/), and
// the verdict of each pair of stations (AdjustmentResult::relative) and
// each station against them. A criterion is judged at the standard's own
// confidence (ALTA/NSPS: 95 %), whatever adjust --confidence is; the
// precisions are the adjustment's (from the a-priori weights, σ0 = 1).

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::workflow {

// What a criterion measures.
enum class StandardQuantity {
  relative_ellipse_semi_major,  // the semi-major axis of the relative error ellipse of a pair, at the confidence
  relative_up,                  // the half-width of the two-sided interval of a pair's up difference, at the confidence
  ellipse_semi_major,           // the semi-major axis of a station's error ellipse, at the confidence
  up,                           // the half-width of a station's up interval, at the confidence
};
// The distance a relative criterion's ppm term is of.
enum class StandardDistance { spatial, horizontal };

// allowed = constant_m + ppm × 10⁻⁶ × distance (ppm: relative criteria only).
struct StandardCriterion {
  StandardQuantity quantity = StandardQuantity::relative_ellipse_semi_major;
  double confidence = 0.95;
  double constant_m = 0.0;
  double ppm = 0.0;
  StandardDistance distance = StandardDistance::spatial;
  std::string definition;  // the standard's own words for the quantity
};

struct AccuracyStandard {
  std::string name, title, source;
  std::string file;  // where it was read
  std::optional<StandardCriterion> relative_horizontal, relative_vertical, positional_horizontal, positional_vertical;
};

// The folder of the standards shipped with the program: $GEOANCHOR_DATA_DIR/
// standards, else share/geoanchor/standards beside the executable's bin/
// (an installed program), else the source tree's data/standards (a build
// tree). Throws geoanchor::Error (io, E_READ) naming where it looked.
std::filesystem::path standards_folder();
// The names of the shipped standards (their files' stems), sorted.
std::vector<std::string> standard_names();

// A standard from its text. Throws geoanchor::Error (input, E_STANDARD)
// naming `source`, the key and the value: malformed JSON, an unknown key,
// a missing field, a value of the wrong type, a number that is not finite
// or out of range (confidence in (0, 1), constant_m ≥ 0, ppm ≥ 0), a
// quantity that does not belong to its criterion, no criterion.
AccuracyStandard parse_standard(std::string_view text, const std::string& source);
// --standard NAME|FILE: a path (it has a '/' or ends in .json) is read as
// given; else the shipped standard of that name (unknown: E_OPTION, usage,
// listing the names).
AccuracyStandard load_standard(const std::string& name_or_file);

// One criterion's verdict: achieved and allowed (metres), PASS when
// achieved ≤ allowed; margin = allowed − achieved.
struct Verdict {
  double achieved_m = 0.0, allowed_m = 0.0;
  bool pass() const { return achieved_m <= allowed_m; }
  double margin_m() const { return allowed_m - achieved_m; }
};

struct StandardVerdicts {
  // Per r.relative (horizontal, vertical) and per r.stations (used ones);
  // nullopt where the standard has no such criterion (or the station is
  // not in the adjustment).
  std::vector<std::optional<Verdict>> pair_horizontal, pair_vertical;
  std::vector<std::optional<Verdict>> station_horizontal, station_vertical;
  std::size_t pass = 0, fail = 0;  // over every verdict
  // The smallest margin and where: "pair" (index into r.relative) or
  // "station" (index into r.stations), and which criterion.
  std::optional<Verdict> worst;
  std::string worst_kind, worst_criterion;
  std::size_t worst_index = 0;
};

StandardVerdicts judge_standard(const AccuracyStandard& standard, const solver::AdjustmentResult& r);

// "relative_horizontal" … ; the quantity's key; the criterion in words
// ("semi-major axis of the 95 % relative error ellipse <= 20 mm + 50 ppm of
// the spatial distance").
const char* quantity_key(StandardQuantity q);
std::string criterion_text(const StandardCriterion& c);

}  // namespace geoanchor::workflow
