// Least-squares adjustment of a survey network (network_adjustment.hpp):
// the driver. The problem is set up (whitening, the a-priori state, gross
// misclosures set aside), then adjusted pass after pass (Gauss–Newton with
// the datum defined on the first iteration, the minimum-norm solution of a
// free network, the statistics from the final factor), data snooping
// deciding whether another pass follows. Each step's concept is a file of
// its own (network_problem.hpp and the network_*.hpp beside it).

#include "geoanchor/solver/network_adjustment.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/parallel.hpp"
#include "network_approximate.hpp"
#include "network_canonical_order.hpp"
#include "network_data_snooping.hpp"
#include "network_candidates.hpp"
#include "network_datum.hpp"
#include "network_external_reliability.hpp"
#include "network_free_datum.hpp"
#include "network_helmert.hpp"
#include "network_measurement_statistics.hpp"
#include "network_model.hpp"
#include "network_normal_equations.hpp"
#include "network_problem.hpp"
#include "network_singularity.hpp"
#include "network_station_statistics.hpp"
#include "network_vce.hpp"
#include "point_statistics.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

using geodesy::MeasurementKind;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A network with no station, or no measurement that is not ignored.
void refuse_empty(const geodesy::Network& network) {
  if (network.stations.empty()) throw Error(ErrorKind::input, "E_NETWORK_EMPTY", network.source_name + ": no stations");
  if (std::all_of(network.measurements.begin(), network.measurements.end(), [](const auto& m) { return m.ignore; })) {
    throw Error(ErrorKind::input, "E_NETWORK_EMPTY",
                network.source_name + ": no measurement to adjust (" + std::to_string(network.measurements.size()) +
                    " read; each is ignored by its input or left out)");
  }
}

// An observation set whose parts are not one terrestrial value each, or
// whose value, stations or covariance are not its parts'
// (geodesy::make_observation_set makes them so).
void refuse_malformed_sets(const geodesy::Network& network) {
  for (const auto& m : network.measurements) {
    if (m.kind != MeasurementKind::observation_set) continue;
    const auto n = static_cast<Eigen::Index>(m.parts.size());
    bool ok = n > 0 && m.value.size() == n && m.covariance.rows() == n && m.covariance.cols() == n;
    std::size_t station = 0;
    for (Eigen::Index k = 0; ok && k < n; ++k) {
      const auto& part = m.parts[static_cast<std::size_t>(k)];
      ok = part.value.size() == 1 && part.value(0) == m.value(k) && part.kind != MeasurementKind::observation_set &&
           part.kind != MeasurementKind::gnss_baselines && part.kind != MeasurementKind::gnss_points;
      for (std::size_t s : part.stations) ok = ok && station < m.stations.size() && m.stations[station++] == s;
    }
    if (!ok || station != m.stations.size()) {
      throw Error(ErrorKind::input, "E_NETWORK_KIND",
                  m.source + ": observation set: its parts must be terrestrial observations of one value each, and its "
                  "value, stations and covariance theirs in order");
    }
  }
}

// A measurement with no measured value (network JSON "value": null) is a
// planned one: only a pre-analysis takes it. A pre-analysis needs every
// station's a-priori coordinates (the design is taken there).
void refuse_for_mode(const geodesy::Network& network, const AdjustOptions& o) {
  if (o.preanalysis) {
    for (const auto& s : network.stations) {
      if (!s.position_known) {
        throw Error(ErrorKind::input, "E_PREANALYSIS_POSITION",
                    s.source + ": station " + s.id + " has no a-priori coordinates: a pre-analysis takes the design at "
                    "the a-priori coordinates; give them");
      }
    }
    return;
  }
  if (!o.candidates.empty()) {
    throw Error(ErrorKind::usage, "E_OPTION", "candidate measurements (--candidates) are ranked by a pre-analysis only: give --preanalysis");
  }
  for (const auto& m : network.measurements) {
    if (!m.value_known && !m.ignore) {
      throw Error(ErrorKind::input, "E_VALUE_MISSING",
                  m.source + ": " + geodesy::to_string(m.kind) + ": no measured value: only a pre-analysis "
                  "(--preanalysis) takes a planned measurement; give its value");
    }
  }
}

// Pre-analysis: each measurement's value replaced by its value computed at
// the a-priori coordinates (orientations and Helmert parameters zero), so
// that the misclosures are zero and the measured values, if any, are never
// read.
geodesy::Network planned_values(const geodesy::Network& network, const AdjustOptions& o) {
  geodesy::Network planned = network;
  const geodesy::GeocentricConverter geocentric(network.ellipsoid);
  std::vector<StationState> states;
  states.reserve(network.stations.size());
  for (std::size_t s = 0; s < network.stations.size(); ++s) {
    states.push_back(station_state(network, geocentric, network.stations[s].position, s, o.geoid));
  }
  const std::vector<double> orientations(network.direction_sets.size(), 0.0);
  const ModelContext ctx{network, o, states, orientations};
  for (auto& m : planned.measurements) {
    if (m.ignore) continue;
    m.value = evaluate(m, ctx).computed;
    m.value_known = true;
    for (std::size_t k = 0; k < m.parts.size(); ++k) {
      m.parts[k].value = m.value.segment(static_cast<Eigen::Index>(k), 1);
      m.parts[k].value_known = true;
    }
  }
  return planned;
}

// Whitening of each measurement's covariance, on threads (each its own;
// the first failure in the measurements' order is the one reported).
void whiten_measurements(NetworkProblem& p, int jobs) {
  const auto& net = p.net;
  p.whitening.resize(net.measurements.size());
  p.active.assign(net.measurements.size(), false);
  p.pattern_only.assign(net.measurements.size(), false);
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) p.active[mi] = !net.measurements[mi].ignore;
  for_chunks(net.measurements.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
    for (std::size_t mi = begin; mi < end; ++mi) {
      const auto& m = net.measurements[mi];
      if (m.ignore) continue;
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m.covariance, Eigen::EigenvaluesOnly);
      const double smallest = eig.eigenvalues().size() ? eig.eigenvalues()(0) : 0.0;
      const double largest = eig.eigenvalues().size() ? eig.eigenvalues().maxCoeff() : 0.0;
      if (!(smallest > 1e-15 * std::max(largest, 1e-300)) || !std::isfinite(largest)) {
        throw Error(ErrorKind::input, "E_COVARIANCE",
                    m.source + ": " + geodesy::to_string(m.kind) + ": the covariance is not positive definite (smallest "
                    "eigenvalue " + format_shortest(smallest) + ", largest " + format_shortest(largest) + ")");
      }
      const Eigen::LLT<Eigen::MatrixXd> llt(m.covariance);
      p.whitening[mi] = llt.matrixL().solve(Eigen::MatrixXd::Identity(m.covariance.rows(), m.covariance.cols()));
    }
  });
}

// --free: the input's station constraints are set aside (said so).
void set_constraints_aside(NetworkProblem& p, AdjustmentResult& result) {
  const auto& net = p.net;
  const auto& o = p.o;
  p.free = o.free;
  p.aside = o.free;
  if (p.free) {
    std::size_t held = 0;
    for (const auto& s : net.stations) held += s.constraint.any() ? 1u : 0u;
    if (held > 0) {
      result.warnings.push_back("--free: the constraints of " + std::to_string(held) +
                                " station(s) in the input are set aside; the datum is the inner constraints'");
    }
  }
}

// The state: a-priori positions; orientations from the first direction of each set.
void initial_state(NetworkProblem& p) {
  const auto& net = p.net;
  const auto& o = p.o;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    p.states.push_back(station_state(net, p.geocentric, net.stations[s].position, s, o.geoid));
  }
  p.orientations.assign(net.direction_sets.size(), 0.0);
  if (o.helmert) begin_helmert_group(p);
  std::vector<bool> seeded(net.direction_sets.size(), false);
  const ModelContext ctx{net, o, p.states, p.orientations};
  for (std::size_t mi : p.order) {
    if (net.measurements[mi].ignore) continue;
    for (const auto& m : geodesy::parts_of(net.measurements[mi])) {  // an observation set's directions too
      if (m.kind != MeasurementKind::direction || !m.set || seeded[*m.set]) continue;
      const Evaluation ev = evaluate(m, ctx);  // computed = bearing − 0
      p.orientations[*m.set] = ev.computed(0) - m.value(0);
      seeded[*m.set] = true;
    }
  }
}

// Gross misclosures at the a-priori coordinates (GNU Gama's tol-abs):
// set aside before the adjustment, each named; returns why, per measurement.
std::vector<std::string> set_aside_gross_misclosures(NetworkProblem& p, AdjustmentResult& result) {
  const auto& net = p.net;
  const auto& o = p.o;
  std::vector<std::string> gross_why(net.measurements.size());
  if (net.gross_misclosure_m > 0.0) {
    const ModelContext ctx{net, o, p.states, p.orientations};
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (!p.active[mi]) continue;
      if (!p.helmert_slot.empty() && p.helmert_slot[mi] >= 0) continue;  // in a datum of its own, not yet known
      const auto& m = net.measurements[mi];
      Evaluation ev;
      try {
        ev = evaluate(m, ctx);
      } catch (const Error&) {
        continue;  // its geometry is judged by the adjustment
      }
      const Eigen::VectorXd w = misclosure(m, ev.computed);
      // Each observation's (an observation set's: the largest of its parts').
      double gross = 0.0;
      Eigen::Index row = 0;
      for (const auto& part : geodesy::parts_of(m)) {
        double length = 1.0;
        if (is_angular(part.kind) && part.stations.size() >= 2) {
          length = 0.0;
          for (std::size_t k = 1; k < part.stations.size(); ++k) {
            length = std::max(length, (p.states[part.stations[k]].x - p.states[part.stations[0]].x).norm());
          }
        }
        gross = std::max(gross, w.segment(row, part.value.size()).cwiseAbs().maxCoeff() * length);
        row += part.value.size();
      }
      if (gross > net.gross_misclosure_m) {
        p.active[mi] = false;
        gross_why[mi] = "misclosure " + fmt_m(gross) + " at the a-priori coordinates exceeds the input's tolerance " +
                        fmt_m(net.gross_misclosure_m);
        result.warnings.push_back(m.source + " (" + geodesy::to_string(m.kind) + "): set aside before the adjustment: " +
                                  gross_why[mi]);
      }
    }
  }
  return gross_why;
}

// A station whose every measurement misses by more than the tolerance
// has wrong a-priori coordinates, not only gross measurements: refused,
// never left out of the results.
void refuse_stations_all_gross(const NetworkProblem& p) {
  const auto& net = p.net;
  std::vector<int> before(net.stations.size(), 0), after(net.stations.size(), 0);
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    if (net.measurements[mi].ignore) continue;
    for (std::size_t st : net.measurements[mi].stations) {
      ++before[st];
      if (p.active[mi]) ++after[st];
    }
  }
  for (std::size_t st = 0; st < net.stations.size(); ++st) {
    if (before[st] > 0 && after[st] == 0) {
      throw Error(ErrorKind::input, "E_GROSS_MISCLOSURE",
                  net.stations[st].source + ": every measurement of station " + net.stations[st].id +
                      " misses by more than the input's tolerance " + fmt_m(net.gross_misclosure_m) +
                      " at its a-priori coordinates: check them (or its measurements)");
    }
  }
}

// What the passes of the adjustment share.
struct Passes {
  Passes(NetworkProblem& problem, AdjustmentResult& adjustment) : p(problem), result(adjustment) {}
  NetworkProblem& p;
  AdjustmentResult& result;
  int jobs = 1;
  double lambda0 = 0.0;  // the measurement tests' (PointTestLevels)
  SnoopingRecord snooping;
  std::vector<std::string> base_warnings;  // the setup's: each pass states its own after them
  std::optional<NormalFactor> last_factor;
  UnknownLayout last_layout;  // the last pass's unknowns
  std::vector<std::string> datum_warnings;  // the datum's weakly defined combinations (each pass that probes it)
};

// Stations reached by the measurements; the rest are left out. A network
// in parts that no measurement joins is refused, naming them; the
// unknowns are laid out.
void begin_pass(NetworkProblem& p) {
  const auto& net = p.net;
  const std::string where = net.source_name;
  p.station_used.assign(net.stations.size(), false);
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    for (std::size_t s : net.measurements[mi].stations) p.station_used[s] = true;
  }
  std::size_t components = 0;
  const auto component = components_of(p, components);
  if (components > 1) {
    std::map<std::size_t, std::vector<std::string>> members;
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (p.station_used[s]) members[component[s]].push_back(net.stations[s].id);
    }
    std::string list;
    for (const auto& [k, ids] : members) {
      list += (list.empty() ? "" : "; ") + std::to_string(ids.size()) + " station" + (ids.size() == 1 ? "" : "s") + " (" +
              ids.front() + (ids.size() > 1 ? ", " + ids[1] : "") + (ids.size() > 2 ? ", …" : "") + ")";
    }
    throw Error(ErrorKind::input, "E_NETWORK_DISCONNECTED",
                where + ": the network falls into " + std::to_string(components) +
                    " parts that no measurement joins: " + list + "; adjust them separately or join them");
  }
  p.layout = make_layout(p);
  // Every component of every station measured is held, and no direction
  // set or Helmert is estimated: nothing to adjust (it ran out of memory
  // on an empty factor before).
  if (p.layout.count == 0) {
    throw Error(ErrorKind::input, "E_NETWORK_NOTHING_TO_ESTIMATE",
                where + ": every station the measurements reach is held in all its components and nothing else is "
                        "estimated: there is nothing to adjust; free a station (its constraint F, or --constrain ID=FFF)");
  }
}

// A GNSS network (linear, its matrix the same at every state) that lost
// a few measurements to data snooping and no unknown: they are taken
// out of the last factor and its selected inverse (a downdate) instead
// of factoring and inverting again (NormalFactor::downdate). Whether it was.
bool downdate_removed(Passes& s, bool same_unknowns) {
  NetworkProblem& p = s.p;
  AdjustmentResult& result = s.result;
  const std::vector<std::size_t>& removed_last_pass = s.snooping.removed_last_pass;
  std::optional<NormalFactor>& last_factor = s.last_factor;
  bool downdated = false;
  if (!removed_last_pass.empty() && p.o.snooping_downdates && last_factor && same_unknowns) {
  const auto t0 = Clock::now();
  std::vector<MeasurementRows> taken;
  Eigen::Index rows = 0;
  for (std::size_t mi : removed_last_pass) {
    taken.push_back(p.linearize(mi));
    rows += taken.back().l.size();
  }
  if (last_factor->downdated_rows() + rows <= last_factor->downdate_rows_worth()) {
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(p.layout.count, rows);
    Eigen::Index column = 0;
    for (const MeasurementRows& r : taken) {
      for (Eigen::Index i = 0; i < r.a.rows(); ++i, ++column) {
        for (std::size_t k = 0; k < r.unknowns.size(); ++k) b(r.unknowns[k], column) = r.a(i, static_cast<Eigen::Index>(k));
      }
    }
    downdated = last_factor->downdate(b, s.jobs);
    result.passes_downdated += downdated ? 1 : 0;
  }
  result.seconds.downdate += since(t0);
  }
  return downdated;
}

// Gauss–Newton. Each factorization hands its analysis to the next (the
// pattern is the first pass's, while the measurements snooping removes
// keep their place as zeros). The datum is defined on the first iteration
// of a pass with new unknowns; refused when it does not converge.
void gauss_newton(Passes& s, bool same_unknowns, bool downdated) {
  NetworkProblem& p = s.p;
  AdjustmentResult& result = s.result;
  const auto& net = p.net;
  const auto& o = p.o;
  bool converged = false;
  double largest = 0.0;
  std::size_t largest_at = 0;
  int iteration = 0;
  for (iteration = 1; iteration <= o.max_iterations; ++iteration) {
    // A normal matrix that cannot have changed is not factored again.
    const bool same_matrix = (iteration > 1 || downdated) && s.last_factor && constant_jacobian(p);
    auto t0 = Clock::now();
    NormalEquations n = assemble(p, !same_matrix, s.jobs);
    result.seconds.assemble += since(t0);
    if (iteration == 1 && !same_unknowns) {
      const auto datum_t0 = Clock::now();
      define_datum(p, s.datum_warnings, s.jobs);
      result.seconds.datum += since(datum_t0);
      check_station_blocks(p, n);
    } else if (p.free && p.defect.cols() > 0) {
      // The same combinations of the motions, at the moved positions.
      p.defect = datum_vectors(p, p.layout).named * p.defect_motions;
    }
    hold_defect(p, n);
    t0 = Clock::now();
    if (!same_matrix) s.last_factor = factor_or_explain(p, n, std::move(s.last_factor));
    result.seconds.factor += since(t0);
    t0 = Clock::now();
    const Eigen::VectorXd dx = s.last_factor->solve(n.b);
    result.seconds.solve += since(t0);
    if (!dx.allFinite()) explain_singularity(p, n, -1);
    const auto [moved, at] = apply_corrections(p, dx);
    largest = moved;
    largest_at = at;
    if (moved < o.convergence_m) {
      converged = true;
      break;
    }
  }
  result.iterations += std::min(iteration, o.max_iterations);
  result.largest_correction_m = largest;
  if (!converged) {
    throw Error(ErrorKind::rejected, "E_NOT_CONVERGED",
                net.source_name + ": the adjustment did not converge in " + std::to_string(o.max_iterations) +
                    " iterations: the last moved " +
                    (largest_at < net.stations.size() ? "station " + net.stations[largest_at].id
                                                      : "the Helmert of group " + o.helmert->name + " (at the surface)") +
                    " by " + fmt_m(largest) +
                    " (threshold " + format_shortest(o.convergence_m) + " m); check the a-priori coordinates and units");
  }
}

// The factor's size, the unknowns, observations and degrees of freedom.
void record_factor(const NetworkProblem& p, const NormalFactor& f, std::size_t rows, AdjustmentResult& result) {
  result.factor_nonzeros = f.factor_nonzeros();
  result.unknowns = static_cast<std::size_t>(p.layout.count);
  result.observations = rows;
  const int defect = p.free ? static_cast<int>(p.defect.cols()) : 0;
  result.dof = static_cast<int>(rows) - static_cast<int>(p.layout.count) + defect;
}

// The statistics at the solution (with the last iteration's factor
// when the matrix is the same): the factor with its selected inverse, and
// the unknowns, observations and degrees of freedom.
NormalFactor factor_at_solution(Passes& s, bool downdated) {
  NetworkProblem& p = s.p;
  AdjustmentResult& result = s.result;
  const auto& net = p.net;
  const bool same_matrix = s.last_factor && constant_jacobian(p);
  auto t0 = Clock::now();
  NormalEquations n;
  if (same_matrix) {
    // Nothing to assemble: the matrix is factored, b is not needed (and a
    // GNSS network is not free: no defect to hold).
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (p.active[mi]) n.rows += static_cast<std::size_t>(net.measurements[mi].value.size());
    }
    n.rows += p.pseudo_observations().size();
  } else {
    n = assemble(p, true, s.jobs);
    hold_defect(p, n);
  }
  result.seconds.assemble += since(t0);
  t0 = Clock::now();
  NormalFactor f = same_matrix ? std::move(*s.last_factor) : factor_or_explain(p, n, std::move(s.last_factor));
  result.seconds.factor += since(t0);
  t0 = Clock::now();
  if (!downdated) f.select_inverse(s.jobs);  // (a downdate updated it)
  result.seconds.select_inverse += since(t0);
  record_factor(p, f, n.rows, result);
  return f;
}

// Pre-analysis: the design at the a-priori coordinates (the misclosures
// zero, planned_values), the datum defined, one factorization and its
// selected inverse; no iteration.
NormalFactor preanalysis_factor(Passes& s) {
  NetworkProblem& p = s.p;
  AdjustmentResult& result = s.result;
  auto t0 = Clock::now();
  NormalEquations n = assemble(p, true, s.jobs);
  result.seconds.assemble += since(t0);
  const auto datum_t0 = Clock::now();
  define_datum(p, s.datum_warnings, s.jobs);
  result.seconds.datum += since(datum_t0);
  check_station_blocks(p, n);
  hold_defect(p, n);
  t0 = Clock::now();
  NormalFactor f = factor_or_explain(p, n, std::nullopt);
  result.seconds.factor += since(t0);
  t0 = Clock::now();
  f.select_inverse(s.jobs);
  result.seconds.select_inverse += since(t0);
  record_factor(p, f, n.rows, result);
  result.iterations = 0;
  result.converged = true;
  return f;
}

// Pre-analysis: what needs measured values is not stated (NaN: the
// outputs leave it empty); no σ0, no global test.
void blank_measured(AdjustmentResult& result) {
  for (auto& am : result.measurements) {
    const Eigen::Index k = am.observed.size();
    am.observed = am.adjusted = am.residual = am.w = Eigen::VectorXd::Constant(k, kNaN);
    am.w_max = am.statistic = am.p_value = am.log_p = kNaN;
  }
  result.vtpv = 0.0;
  result.variance_factor.reset();
  result.sigma0.reset();
  result.global_test = GlobalTest{};
  result.global_test.applicable = false;
  result.preanalysis = true;
}

// The datum in words, and the warnings every result ends with: stations
// left out, the datum's weak combinations, little redundancy, a failed
// global test.
void conclude(const NetworkProblem& p, const std::vector<std::string>& datum_warnings, AdjustmentResult& result) {
  const auto& net = p.net;
  const std::size_t d = static_cast<std::size_t>(p.defect.cols());
  result.datum_by_minimum_norm = p.free && d > 0;
  result.datum_defect = p.defect_names;
  result.datum = datum_in_words(p);
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!p.station_used[s]) {
      result.warnings.push_back("station " + net.stations[s].id + " (" + net.stations[s].source +
                                ") is reached by no measurement in the adjustment: left out");
    }
  }
  result.warnings.insert(result.warnings.end(), datum_warnings.begin(), datum_warnings.end());
  if (result.dof <= 0) {
    result.warnings.push_back("no redundancy (dof = " + std::to_string(result.dof) +
                              "): σ0, the global test and the measurement tests are undefined");
  } else if (result.dof <= 5) {
    result.warnings.push_back("low redundancy (dof = " + std::to_string(result.dof) +
                              "): the global test and the w-tests have little power");
  }
  const auto& g = result.global_test;
  if (g.applicable && !g.passed) {
    result.warnings.push_back(std::string("global test ") +
                              (g.failed_high() ? "FAILED high: the residuals are larger than the a-priori "
                                                                "standard deviations allow"
                                                              : "low: the residuals are smaller than the a-priori standard "
                                                                "deviations suggest (too pessimistic?)") +
                              (result.variance_factor ? " (variance factor " + format_fixed(*result.variance_factor, 4) + ")" : std::string()));
  }
  result.converged = true;
}

// One pass: the network adjusted and tested. False when data snooping
// removed measurements (--remove-outliers) and the network is to be
// adjusted again without them; true when the result is complete.
bool adjust_pass(Passes& s) {
  NetworkProblem& p = s.p;
  AdjustmentResult& result = s.result;
  result.warnings = s.base_warnings;  // each pass states its own
  ++result.passes;
  begin_pass(p);
  // A later pass of a GNSS network (linear, its matrix the same at every
  // state) with the same unknowns: data snooping took measurements out,
  // no station. Its datum is the last pass's (the translations, held by
  // the same constraints: the network stays whole), not probed again.
  const bool same_unknowns = result.passes > 1 && p.layout == s.last_layout && constant_jacobian(p);
  const bool downdated = downdate_removed(s, same_unknowns);
  s.snooping.removed_last_pass.clear();
  s.last_layout = p.layout;
  begin_inner_constraints(p);
  const bool planned = p.o.preanalysis;
  if (!planned) gauss_newton(s, same_unknowns, downdated);
  std::optional<NormalFactor> first;
  if (planned) first = preanalysis_factor(s);
  const InnerConstraints inner = to_minimum_norm(p);
  NormalFactor f = planned ? std::move(*first) : factor_at_solution(s, downdated);
  auto t0 = Clock::now();
  measurement_statistics(p, f, MeasurementRecord{s.snooping.outlier_why, s.snooping.rank_of, s.lambda0}, result, s.jobs);
  if (planned) blank_measured(result);
  result.seconds.measurements += since(t0);
  if (!planned && p.o.data_snooping && result.dof > 0 && snoop_network(p, f, s.snooping, result, s.jobs)) {
    s.last_factor = std::move(f);  // its analysis serves the next pass (the same pattern)
    return false;                  // adjust again without them
  }
  if (p.o.external_reliability) {
    t0 = Clock::now();
    external_reliability(p, f, inner, result);
    result.seconds.external += since(t0);
  }
  t0 = Clock::now();
  station_statistics(p, f, inner, result, s.jobs);
  result.seconds.stations += since(t0);
  if (planned && !p.o.candidates.empty()) rank_candidates(p, f, inner, result);
  conclude(p, s.datum_warnings, result);
  return true;
}

AdjustmentResult adjust_values_known(const geodesy::Network& network, const AdjustOptions& o);

// Stations with no a-priori coordinates: placed from the measurements
// (network_approximate.hpp), then the network adjusted; the result says so.
AdjustmentResult adjust_placed(const geodesy::Network& network, const AdjustOptions& o, std::size_t unplaced) {
  geodesy::Network placed = network;
  approximate_positions(placed);
  AdjustmentResult r = adjust_network(placed, o);
  // (Built anew rather than inserted at the front: GCC 12 at -O3 sees a
  // null dereference in the insertion once this is inlined.)
  std::vector<std::string> warnings{std::to_string(unplaced) + " station(s) had no a-priori coordinates: their "
                                    "approximate positions were computed from the measurements"};
  warnings.insert(warnings.end(), r.warnings.begin(), r.warnings.end());
  r.warnings = std::move(warnings);
  return r;
}

}  // namespace

AdjustmentResult adjust_network(const geodesy::Network& network, const AdjustOptions& o) {
  if (o.variance_components != AdjustOptions::VarianceGroups::none) {
    if (o.preanalysis) {
      throw Error(ErrorKind::usage, "E_OPTION", "--vce with --preanalysis: variance components are estimated from residuals, and a "
                                                "pre-analysis has none");
    }
    return adjust_with_variance_components(network, o, [](const geodesy::Network& n, const AdjustOptions& once) {
      return adjust_network(n, once);
    });
  }
  refuse_empty(network);
  refuse_malformed_sets(network);
  refuse_for_mode(network, o);
  if (o.preanalysis) return adjust_values_known(planned_values(network, o), o);
  return adjust_values_known(network, o);
}

namespace {

AdjustmentResult adjust_values_known(const geodesy::Network& network, const AdjustOptions& o) {
  std::size_t unplaced = 0;
  for (const auto& s : network.stations) unplaced += s.position_known ? 0u : 1u;
  if (unplaced > 0) return adjust_placed(network, o, unplaced);
  NetworkProblem p(network, o);
  const auto& net = network;
  p.set_order = canonical_set_order(net);
  p.order = canonical_order(net, p.set_order);
  AdjustmentResult result;
  const int jobs = resolve_jobs(o.jobs);
  whiten_measurements(p, jobs);
  set_constraints_aside(p, result);
  initial_state(p);
  const std::vector<std::string> gross_why = set_aside_gross_misclosures(p, result);
  if (net.gross_misclosure_m > 0.0) refuse_stations_all_gross(p);

  Passes passes(p, result);
  passes.jobs = jobs;
  passes.snooping.countable = static_cast<std::size_t>(std::count(p.active.begin(), p.active.end(), true));
  FitOptions levels_of;
  levels_of.alpha_point = o.alpha_point;
  levels_of.power = o.power;
  const PointTestLevels levels = point_test_levels(levels_of);
  result.w_critical = levels.w_critical;
  result.alpha_point = o.alpha_point;
  passes.lambda0 = levels.lambda0;
  passes.snooping.outlier_why = gross_why;
  passes.base_warnings = result.warnings;
  passes.snooping.rank_of.assign(net.measurements.size(), 0);  // data snooping's order (snooping_rank)
  while (!adjust_pass(passes)) {
  }
  return result;
}

}  // namespace

}  // namespace geoanchor::solver
