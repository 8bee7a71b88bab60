#include "network_options.hpp"

#include <CLI/CLI.hpp>

#include "geoanchor/base/error.hpp"
#include "option_parsing.hpp"

namespace geoanchor::cli {

std::vector<CLI::Option*> add_network_options(CLI::App* cmd, NetworkOptions& o) {
  return {
      cmd->add_option("--sinex-frame", o.sinex_frame,
                      "The frame of SINEX inputs' estimates (SINEX names none), a catalog frame, e.g. ITRF2014; their epoch is REF_EPOCH"),
      cmd->add_option("--frame", o.frame, "The adjustment's frame and epoch, e.g. GDA2020, ITRF2020@2024.5 (default: the inputs')"),
      cmd->add_option("--constrain", o.constrain,
                      "ID=CCC[,SIGMA_M]: hold station ID's latitude, longitude, height (C) or leave them free (F); with SIGMA_M held "
                      "with that standard deviation"),
      cmd->add_flag("--free", o.free, "Free network: the datum by inner constraints (no station held)"),
      cmd->add_option("--inner-constraints", o.inner, "With --free: the stations the inner constraints are over, ID,ID,... (default: all)"),
      cmd->add_option("--confidence", o.confidence, "Confidence of the global test and of the error ellipses (default 0.95)")
          ->check(finite_range(0.5, 0.9999)),
      cmd->add_option("--alpha", o.alpha, "Significance of the w-tests and data snooping (default 0.001)")->check(finite_range(1e-9, 0.5)),
      cmd->add_option("--max-outlier-share", o.max_outlier_share,
                      "--remove-outliers: refuse when data snooping would remove more than this share of the measurements (default 0.10)")
          ->check(finite_range(0.0, 0.5)),
      cmd->add_flag("--remove-outliers", o.remove_outliers,
                    "Remove the measurements that fail their test by iterative data snooping, strongest evidence first, and "
                    "adjust again (default: flag them and remove none)"),
      cmd->add_flag("--no-snooping", o.no_snooping, "Remove no measurement (the default; kept for scripts): failing ones are flagged"),
      cmd->add_flag("--solution-weighting", o.solution_weighting,
                    "Adjust GNSS measurements whose 'solution' is float, dgps, sbas or standalone with their covariances "
                    "scaled by 10², 25², 75² or 250² (default: left out; dead_reckoned always is)"),
      cmd->add_option("--geoid", o.geoid,
                      "Geoid for orthometric heights, levelled height differences and deflections of the vertical: EGM96, EGM96-NGA, a grid name PROJ finds or a PATH (GTX, GeoTIFF, an AUSGeoid-style NTv2 grid with deflections, or DynAdjust's per-station .geo file)"),
      cmd->add_option("--refraction", o.refraction, "Coefficient of refraction for zenith angles (default: the inputs' own, a STAR*NET .REFRACTION, else 0; 0.13 is typical by day)")
          ->check(finite_range(-1.0, 1.0)),
      cmd->add_option("--convergence", o.convergence_m, "Stop when no station moves more than this (m; default 1e-5)")
          ->check(finite_range(1e-9, 1.0)),
      cmd->add_option("--max-iterations", o.max_iterations, "Iteration limit (default 25)")->check(integer_range(1, 1000)),
      cmd->add_option("--estimate-helmert", o.estimate_helmert,
                      "GROUP[:helmert7|helmert14]: a Helmert from the datum of a group of GNSS measurements (their 'group', or an input "
                      "file) to the network's frame, estimated with the stations"),
  };
}

workflow::AdjustRequest network_request(const std::vector<std::string>& inputs, const NetworkOptions& o,
                                        const std::optional<std::string>& helmert_convention) {
  if (o.inner && !o.free) throw Error(ErrorKind::usage, "E_OPTION", "--inner-constraints: only with --free");
  if (o.free && !o.constrain.empty()) throw Error(ErrorKind::usage, "E_OPTION", "--free with --constrain: give one datum");
  workflow::AdjustRequest request;
  request.inputs = inputs;
  request.frame = o.frame;
  request.sinex_frame = o.sinex_frame;
  request.constrain = o.constrain;
  request.estimate_helmert = o.estimate_helmert;
  request.convention = helmert_convention;
  request.solutions = o.solution_weighting ? geodesy::SolutionPolicy::weight : geodesy::SolutionPolicy::exclude;
  auto& so = request.options;
  so.alpha = 1.0 - o.confidence;
  so.confidence = o.confidence;
  so.alpha_point = o.alpha;
  so.max_outlier_share = o.max_outlier_share;
  if (o.remove_outliers && o.no_snooping) {
    throw Error(ErrorKind::usage, "E_OPTION", "--remove-outliers and --no-snooping: give one (--no-snooping removes none, the default)");
  }
  so.data_snooping = true;
  so.remove_outliers = o.remove_outliers;
  so.refraction_k = o.refraction.value_or(0.0);
  request.refraction_given = o.refraction.has_value();
  so.convergence_m = o.convergence_m;
  so.max_iterations = o.max_iterations;
  so.free = o.free;
  if (o.inner) {
    std::string id;
    for (char c : *o.inner + ",") {
      if (c == ',') {
        if (!id.empty()) so.inner_constraint_stations.push_back(id);
        id.clear();
      } else {
        id += c;
      }
    }
  }
  if (o.geoid) {
    const workflow::NetworkGeoid g = workflow::parse_network_geoid(*o.geoid, "--geoid");
    so.geoid = g.grid;
    request.station_geoid = g.stations;
  }
  return request;
}

NetworkSession open_network(const std::vector<std::string>& inputs, const NetworkOptions& o,
                            const std::optional<std::string>& helmert_convention) {
  const workflow::AdjustRequest request = network_request(inputs, o, helmert_convention);
  NetworkSession s{workflow::prepare_network(request), request.options, nullptr};
  s.options.helmert = s.prepared.helmert;
  s.options.refraction_k = s.prepared.refraction_k;
  s.model = std::make_unique<gui::NetworkModel>(s.prepared.network, s.options);
  s.model->wait();
  return s;
}

}  // namespace geoanchor::cli
