#pragma once
// `geoanchor adjust` as a library (docs/commands/adjust.md): the inputs
// read into one network, brought to the adjustment's frame and epoch
// through the frame catalog, the command line's constraints applied; the
// adjustment (solver/network_adjustment.hpp); and what it becomes on disk:
// the adjusted stations as a control set CSV with its sidecar, the
// measurements with their statistics, the report as text and JSON.

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/io/network/station_geoid.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "geoanchor/workflow/accuracy_standard.hpp"

namespace geoanchor::workflow {

struct AdjustRequest {
  std::vector<std::string> inputs;      // files, or "-"
  std::optional<std::string> frame;     // --frame NAME[@EPOCH]
  std::optional<std::string> sinex_frame;  // --sinex-frame NAME: the frame of SINEX inputs
  std::vector<std::string> constrain;   // --constrain ID=CCC[,SIGMA_M]
  // --estimate-helmert GROUP[:helmert7|helmert14] and its --convention
  // (position_vector | coordinate_frame: the written file's; required).
  std::optional<std::string> estimate_helmert;
  std::optional<std::string> convention;
  // GNSS measurements with a solution type (network JSON "solution"):
  // float and worse are left out (ignored), or weighted (--solution-weighting:
  // covariance × geodesy::solution_sigma_factor²; dead_reckoned left out).
  geodesy::SolutionPolicy solutions = geodesy::SolutionPolicy::exclude;
  solver::AdjustOptions options;
  // options.refraction_k was given (--refraction): an input's own
  // coefficient (geodesy::Network::refraction_k) must then agree with it.
  bool refraction_given = false;
  // adjust --geoid FILE.geo: DynAdjust's per-station N, ξ, η (the grid, if
  // any, is options.geoid).
  std::shared_ptr<const io::StationGeoidTable> station_geoid;
  // --relative connected|all|radius:R_M|pairs:FILE (relative_options) and
  // --standard NAME|FILE (accuracy_standard.hpp).
  std::string relative = "connected";
  std::optional<std::string> standard;
  // adjust --candidates FILE (with --preanalysis): candidate measurements,
  // read as one more input (any network format); prepare_network takes
  // them out of the network into PreparedNetwork::candidates.
  std::optional<std::string> candidates;
};

struct PreparedNetwork {
  geodesy::Network network;
  std::vector<std::string> notes;  // what was done to it (frame changes, constraints), for the report
  // --estimate-helmert: the group (its measurements stay in their own
  // datum: no frame step), the frame they are in, the written convention.
  std::optional<solver::HelmertGroup> helmert;
  std::optional<geodesy::Frame> helmert_frame;
  bool helmert_position_vector = true;
  // GNSS solution types: the policy (set when a measurement has a type)
  // and the measurements it left out.
  std::optional<geodesy::SolutionPolicy> solution_policy;
  std::vector<std::size_t> solution_excluded;
  // The coefficient of refraction to adjust with: the inputs' own
  // (STAR*NET .REFRACTION), else the request's options.refraction_k.
  double refraction_k = 0.0;
  // The pairs of --relative over this network (the caller puts them in
  // AdjustOptions::relative), its text for the reports, and --standard.
  solver::RelativeOptions relative;
  std::string relative_spec = "connected";
  std::shared_ptr<const AccuracyStandard> standard;
  // AdjustRequest::candidates: the file's measurements (their stations and
  // direction sets indices into `network`'s), for AdjustOptions::candidates;
  // as read (no frame step, no variance scale: their values are not used).
  std::vector<geodesy::NetworkMeasurement> candidates;
};

// Per GNSS solution type, the measurements that state it, those adjusted
// in the end (not left out, not removed by data snooping) and those left
// out for their type; nullopt when no measurement states one. `only`
// restricts it to some measurements (a Helmert group's).
std::optional<io::GnssSolutionRecord> adjust_solution_record(const PreparedNetwork& prepared,
                                                             const solver::AdjustmentResult& r,
                                                             const std::vector<std::size_t>* only = nullptr);

// The group of --estimate-helmert GROUP: the measurements whose `group`
// is GROUP, else those of the input file GROUP. Each must be a GNSS
// baseline or point cluster, all in one frame (helmert7: at one epoch;
// helmert14: each with its epoch, at two epochs or more; the reference
// epoch is their mean).
//
// Throws geoanchor::Error: reading (io::read_network), a --frame or
// measurement frame the catalog cannot reach (naming the measurement), a
// change of epoch in a dynamic frame (which needs velocities: refused
// naming the measurement), an ellipsoidal network without a frame, a
// --constrain that names no station or is malformed, a --refraction that
// differs from the inputs' own coefficient (usage).
PreparedNetwork prepare_network(const AdjustRequest& request);

// adjust --relative SPEC over the network's stations: connected (the pairs
// a measurement joins), all, radius:R_M (every pair within R metres
// horizontally; R finite and positive), pairs:FILE (a CSV with the header
// `from,to` and a pair of station ids per row; docs/commands/adjust.md).
// Throws geoanchor::Error: a SPEC of none of these forms, `all` for more
// than solver::kMaxAllRelativePairs pairs (usage, E_OPTION, naming the
// count); a pairs file that cannot be read (io, E_READ), without the
// header, with an unknown id or a station paired with itself (input,
// E_PAIRS, naming file, line and id).
solver::RelativeOptions relative_options(const std::string& spec, const geodesy::Network& net);

// adjust --relative-output: one row per pair of r.relative (header in
// docs/commands/adjust.md), with the standard's verdicts when
// prepared.standard is set. Every field finite.
std::string relative_csv(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o);

// The adjusted stations as CSV: a network on the ellipsoid
//   id,x_m,y_m,z_m,lat_deg,lon_deg,h_m,sigma_e_m,sigma_n_m,sigma_u_m,
//   corr_en,corr_eu,corr_nu,ellipse_a_m,ellipse_b_m,ellipse_azimuth_deg,
//   ellipse_conf_a_m,ellipse_conf_b_m,constraint
// with "# frame = …" above the header; a local network its own axes
// (x_m, y_m, z_m as present, sigma_x_m, …). Sigmas from the a-priori
// weights (σ0 = 1). Stations no measurement reaches are left out.
std::string stations_csv(const geodesy::Network& net, const solver::AdjustmentResult& r, const solver::AdjustOptions& o);

// The adjusted stations and their joint covariance as SINEX 2.02 (the
// adjustment run with AdjustOptions::joint_covariance). Throws
// geoanchor::Error (usage) for a local network or a frame without epoch.
std::string stations_sinex(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const std::string& software);

// A pre-analysis's ranked candidates (AdjustmentResult::candidates), one
// row each, best first:
//   rank,source,kind,stations,measurements,criterion,worst_m,worst_station,improvement_m
// (criterion: semi_major_95 (the confidence in %) or sigma_up; worst_m
// the criterion's worst value with the candidate added; the first row's
// rank 1). Throws nothing.
std::string candidates_csv(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o);

// The criterion's name in the outputs: "semi_major_95", "sigma_up", or
// "custom" (AdjustOptions::candidate_criterion).
std::string candidate_criterion_name(const solver::AdjustOptions& o);

// One row per measurement component with its statistics, formatted on
// `jobs` threads (0: the machine's cores); the text does not depend on how
// many.
std::string measurements_csv(const geodesy::Network& net, const solver::AdjustmentResult& r, int jobs = 0);

// The estimated Helmert of --estimate-helmert as a transform file
// (docs/transform-file.md): from the group's frame to the network's, with
// its sigmas and correlations (σ0 = 1), the adjustment's statistics, and
// as control extent the hull of the group's stations.
io::TransformFile helmert_transform_file(const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                                         const solver::AdjustOptions& o, const std::string& generator);

// The report as text, and as a JSON document (schema
// geoanchor.adjust-report/1; `adjust --json` prints it whole). A summary
// leaves out the stations and the measurements, which the CSV files hold
// row by row: the stations' sidecar holds the summary (at 10⁶ stations the
// whole document is a gigabyte).
enum class ReportDetail { summary, full };
std::string report_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o);
nlohmann::ordered_json report_document(const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                                       const solver::AdjustOptions& o, ReportDetail detail = ReportDetail::full);

// The stations CSV's sidecar (schema geoanchor.stations/2) as JSON text
// (indented by 2): the report's summary (frame, datum, statistics, data
// snooping, outliers, warnings; report_document(…, summary)) with the
// number of stations in the CSV, the version, the command line and each
// input with its SHA-256 (none for standard input, a pipe or a FIFO, which
// cannot be read again).
std::string stations_sidecar_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o,
                                  const std::vector<std::string>& argv, const std::vector<std::string>& inputs,
                                  const std::string& version);

}  // namespace geoanchor::workflow
