#include "option_parsing.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <limits>

#include "geoanchor/base/number_text.hpp"

namespace geoanchor::cli {
namespace {

// The one implementation of the numeric checks: `lo_open` excludes lo,
// hi = +infinity means no upper bound, `integer` asks for a whole number.
CLI::Validator number_check(double lo, double hi, bool lo_open, bool integer) {
  std::string range;
  if (std::isinf(hi)) {
    range = std::string(lo_open ? "> " : ">= ") + format_shortest(lo);
  } else {
    range = std::string("in ") + (lo_open ? "(" : "[") + format_shortest(lo) + ", " + format_shortest(hi) + "]";
  }
  const std::string expected = std::string(integer ? "an integer " : "a finite number ") + range;
  auto check = [=](std::string& text) -> std::string {
    const auto v = parse_finite_double(text);
    if (!v) return "value " + text + " is not a finite number; expected " + expected;
    if (integer && *v != std::floor(*v)) return "value " + text + " is not an integer; expected " + expected;
    if (!(lo_open ? *v > lo : *v >= lo) || !(*v <= hi)) return "value " + text + " is out of range; expected " + expected;
    return std::string();
  };
  return CLI::Validator(check, expected, "FINITE");
}

}  // namespace

CLI::Validator finite_range(double lo, double hi) { return number_check(lo, hi, false, false); }
CLI::Validator finite_positive() { return number_check(0.0, std::numeric_limits<double>::infinity(), true, false); }
CLI::Validator integer_range(long long lo, long long hi) {
  return number_check(static_cast<double>(lo), static_cast<double>(hi), false, true);
}

void add_control_grid_options(CLI::App& cmd, ControlGridOptions& o) {
  cmd.add_option("--src-zone", o.src_zone, "UTM zone of easting_src_m/northing_src_m (e.g. 32N)");
  cmd.add_option("--src-tm", o.src_tm, "Transverse Mercator LAT0,LON0,K0,FE,FN of easting_src_m/northing_src_m");
  cmd.add_option("--dst-zone", o.dst_zone, "UTM zone of easting_dst_m/northing_dst_m");
  cmd.add_option("--dst-tm", o.dst_tm, "Transverse Mercator of easting_dst_m/northing_dst_m");
  cmd.add_option("--src-crs", o.src_crs,
                 "CRS of the source coordinates, read through PROJ (EPSG:n, EPSG:h+v, WKT, PROJJSON, @FILE, a frame "
                 "name; CRS@EPOCH): columns easting_src_<unit>, lat_src_deg, h_src_<unit>… (default: the file's "
                 "'# source_crs = …')");
  cmd.add_option("--dst-crs", o.dst_crs, "CRS of the target coordinates (as --src-crs; the file's '# target_crs = …')");
}

}  // namespace geoanchor::cli
