#pragma once
// `geoanchor fit`: a datum transform from control points, with statistics.
// See docs/commands/fit.md.

#include <optional>
#include <string>
#include <vector>

#include "option_parsing.hpp"

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct FitCommandOptions {
  std::string control;  // a path, or "-" for standard input
  std::string src, dst;  // or two files, one frame each (--src, --dst)
  bool allow_unmatched = false;  // --src marks without a counterpart in --dst are left out, not refused
  std::string model;
  std::optional<std::string> convention;
  std::string rotation_model = "small_angle";
  std::optional<std::string> reference_epoch;
  std::optional<std::string> pivot;
  bool compare = false;
  std::optional<std::string> tm;  // site-calibration grid
  std::optional<std::string> robust;
  bool vce = false;
  bool fix_yaw = false;
  bool with_scale = false;
  std::optional<std::string> origin;
  ControlGridOptions grids;  // easting/northing columns
  std::optional<std::string> ellipsoid;  // default: each frame's (io::ControlReadOptions::ellipsoid)
  std::optional<std::string> source_frame, target_frame;
  std::optional<std::string> geoid;  // EGM96 | EGM96-NGA: reads H_src_m/H_dst_m (JSON H_m) as h = H + N
  double alpha = 0.05;
  double alpha_point = 0.001;
  bool no_snooping = false;      // the default (flag, remove none): kept for scripts
  bool remove_outliers = false;  // iterative data snooping removes the failing marks
  double max_outlier_share = 0.10;
  bool scale_by_sigma0 = false;
  bool accept_failed_global_test = false;
  // GNSS solution types (a `solution` column): float and worse are left out
  // unless weighted (geodesy::solution_sigma_factor).
  bool solution_weighting = false;
  std::optional<std::string> survey_metadata;  // geoanchor.survey/1 file for the transform's metadata contract
  std::string output;  // empty: no file; "-": the transform file on standard output
  bool overwrite = false;
  bool json = false;   // the report as JSON on standard output
  std::vector<std::string> argv;
};

CLI::App* add_fit_command(CLI::App& app, FitCommandOptions& options);
// Returns the exit code (0, or 4 when the fit is refused after reporting).
int run_fit(const FitCommandOptions& options);

}  // namespace geoanchor::cli
