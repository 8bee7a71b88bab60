// A network adjustment's results per measurement, and the global test
// (network_measurement_statistics.hpp).

#include "network_measurement_statistics.hpp"

#include <Eigen/LU>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "geoanchor/base/parallel.hpp"
#include "point_statistics.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Q over unknowns that may share no other measurement (off the factor's
// pattern): by solves for their columns, into q (nu × nu).
void cofactor_by_solves(const NetworkProblem& p, const NormalFactor& f, const std::vector<Index>& unknowns, Eigen::MatrixXd& q) {
  const std::size_t nu = unknowns.size();
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(p.layout.count, static_cast<Eigen::Index>(nu));
  for (std::size_t a = 0; a < nu; ++a) e(unknowns[a], static_cast<Eigen::Index>(a)) = 1.0;
  const Eigen::MatrixXd z = f.solve(e);
  for (std::size_t a = 0; a < nu; ++a) {
    for (std::size_t b = 0; b < nu; ++b) {
      q(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = z(unknowns[a], static_cast<Eigen::Index>(b));
    }
  }
  q = (0.5 * (q + q.transpose())).eval();
}

// Measurement mi's results into `am`. False (am unfinished) for a
// measurement left out whose unknowns are off the factor's pattern when
// `defer_left_out`: it needs solves, which the caller makes on its own
// thread.
bool measure(const NetworkProblem& p, const NormalFactor& f, const MeasurementRecord& c, std::size_t mi, AdjustedMeasurement& am,
             bool defer_left_out) {
  const auto& m = p.net.measurements[mi];
  const bool in = p.active[mi];
  const bool was_outlier = !in && !c.outlier_why[mi].empty();
  // An outlier is tested against the adjustment (its prediction) where its stations are in it.
  bool testable = in;
  if (was_outlier) {
    testable = true;
    for (std::size_t s : m.stations) testable = testable && p.station_used[s];
    for (const auto& part : geodesy::parts_of(m)) {
      if (part.set) testable = testable && p.layout.orientation[*part.set] >= 0;  // its set still has an orientation
    }
  }
  am = AdjustedMeasurement{};
  am.index = mi;
  am.used = in;
  am.outlier = was_outlier;
  am.removed_because = c.outlier_why[mi];
  am.snooping_rank = c.rank_of[mi];
  am.observed = m.value;
  am.sigma = m.covariance.diagonal().cwiseSqrt();
  const Eigen::Index k = m.value.size();
  if (!testable) {
    am.adjusted = am.residual = am.residual_sigma = am.w = am.mdb = Eigen::VectorXd::Constant(k, kNaN);
    am.redundancy = Eigen::VectorXd::Zero(k);
    return true;
  }
  const MeasurementRows r = p.linearize(mi);
  am.residual = -misclosure(m, r.computed);  // adjusted − observed
  am.adjusted = adjusted_value(m, am.residual);
  // A Q Aᵀ over the measurement's unknowns, from the selected inverse.
  const std::size_t nu = r.unknowns.size();
  Eigen::MatrixXd q(static_cast<Eigen::Index>(nu), static_cast<Eigen::Index>(nu));
  bool on_pattern = in;
  if (!in) {
    // A measurement left out keeps its place in the pattern while
    // snooping reuses the analysis (NetworkProblem::pattern_only): read there.
    on_pattern = f.inverse_block(r.unknowns.data(), nu, q.data());
    if (!on_pattern && defer_left_out) return false;
  }
  if (!on_pattern) cofactor_by_solves(p, f, r.unknowns, q);
  if (in && !f.inverse_block(r.unknowns.data(), nu, q.data())) {
    throw std::logic_error("adjust_network: a measurement's unknowns are off the factor's pattern");
  }
  const Eigen::MatrixXd aqa = r.a * q * r.a.transpose();
  const Eigen::MatrixXd qv = in ? Eigen::MatrixXd(Eigen::MatrixXd::Identity(k, k) - aqa)
                                : Eigen::MatrixXd(Eigen::MatrixXd::Identity(k, k) + aqa);
  const ObservationTest t = test_observation(am.residual, p.whitening[mi], qv, Eigen::MatrixXd::Identity(k, k), in, 1.0,
                                             c.lambda0);
  am.w = t.w;
  am.redundancy = t.redundancy;
  am.mdb = t.mdb;
  am.w_max = t.w_max;
  am.statistic = t.statistic;
  am.test_dof = t.dof;
  am.p_value = t.p_value;
  am.log_p = t.log_p;
  // σ of the residual: W⁻¹ Q_v W⁻ᵀ.
  const Eigen::MatrixXd w_inv = p.whitening[mi].inverse();
  am.residual_sigma = (w_inv * qv * w_inv.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  return true;
}

// vᵀPv in the canonical order.
double weighted_residual_squares(const NetworkProblem& p, const std::vector<std::size_t>& listed,
                                 const std::vector<AdjustedMeasurement>& measured) {
  const auto& net = p.net;
  double vtpv = 0.0;
  std::vector<std::size_t> slot_of(net.measurements.size(), listed.size());
  for (std::size_t slot = 0; slot < listed.size(); ++slot) slot_of[listed[slot]] = slot;
  for (std::size_t mi : p.order) {
    if (slot_of[mi] == listed.size()) continue;
    const auto& am = measured[slot_of[mi]];
    if (am.used) vtpv += (p.whitening[am.index] * am.residual).squaredNorm();
  }
  return vtpv;
}

}  // namespace

void measurement_statistics(const NetworkProblem& p, const NormalFactor& f, const MeasurementRecord& record,
                            AdjustmentResult& result, int jobs) {
  const auto& net = p.net;
  std::vector<std::size_t> listed;  // the measurements reported (ignored ones left out)
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    if (!net.measurements[mi].ignore) listed.push_back(mi);
  }
  std::vector<AdjustedMeasurement> measured(listed.size());
  std::vector<char> deferred(listed.size(), 0);
  for_chunks(listed.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
    for (std::size_t slot = begin; slot < end; ++slot) {
      if (!measure(p, f, record, listed[slot], measured[slot], true)) deferred[slot] = 1;
    }
  });
  for (std::size_t slot = 0; slot < listed.size(); ++slot) {
    if (deferred[slot]) measure(p, f, record, listed[slot], measured[slot], false);
  }
  double vtpv = weighted_residual_squares(p, listed, measured);
  result.measurements = std::move(measured);
  for (const auto& q : p.pseudo_observations()) vtpv += q.l * q.l;
  result.vtpv = vtpv;
  result.variance_factor = result.dof > 0 ? std::optional<double>(vtpv / result.dof) : std::nullopt;
  result.sigma0 = result.variance_factor ? std::optional<double>(std::sqrt(*result.variance_factor)) : std::nullopt;
  result.global_test = global_test(vtpv, result.dof, p.o.alpha, true);
}

}  // namespace geoanchor::solver
