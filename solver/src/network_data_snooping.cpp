// Data snooping in a network adjustment (network_data_snooping.hpp).

#include "network_data_snooping.hpp"

#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "fit_common.hpp"
#include "geoanchor/base/number_text.hpp"
#include "network_canonical_order.hpp"
#include "network_snooping.hpp"
#include "snooping.hpp"

namespace geoanchor::solver {

using geodesy::MeasurementKind;

namespace {

std::string name_of(const geodesy::Network& net, const AdjustedMeasurement& am) {
  return net.measurements[am.index].source + " (" + geodesy::to_string(net.measurements[am.index].kind) + ")";
}

std::string describe(const AdjustedMeasurement& am, double alpha_point) {
  return "measurement test " + fmt(am.statistic, 4) + " (χ²(" + std::to_string(am.test_dof) + "), p = " +
         fmt(am.p_value, 3) + " < " + format_shortest(alpha_point) + "); max |w| " + format_fixed(am.w_max, 2);
}

// The measurements that fail their test (positions in result.measurements)
// in the order of their content (`keys`, measurement_key), so that the
// cofactors' solves are batched the same for any order of the input.
std::vector<std::size_t> failing_by_content(const NetworkProblem& p, const AdjustmentResult& result, std::vector<std::string>& keys) {
  const auto& net = p.net;
  const auto& o = p.o;
  std::vector<std::size_t> failing;  // positions in result.measurements
  keys.assign(result.measurements.size(), std::string());
  const std::vector<std::size_t> set_rank = set_ranks(p.set_order);
  for (std::size_t k = 0; k < result.measurements.size(); ++k) {
    if (!result.measurements[k].fails_test(o.alpha_point)) continue;
    failing.push_back(k);
    const auto& m = net.measurements[result.measurements[k].index];
    keys[k] = measurement_key(net, m, direction_set_rank(m, set_rank));
  }
  std::stable_sort(failing.begin(), failing.end(), [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });
  return failing;
}

// Per direction set, how many measurements in the adjustment have a
// direction in it.
std::vector<std::size_t> set_users(const NetworkProblem& p) {
  std::vector<std::size_t> users(p.net.direction_sets.size(), 0);
  for (std::size_t mi = 0; mi < p.net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    std::vector<std::size_t> sets;
    for (const auto& part : geodesy::parts_of(p.net.measurements[mi])) {
      if (part.set && std::find(sets.begin(), sets.end(), *part.set) == sets.end()) sets.push_back(*part.set);
    }
    for (std::size_t s : sets) ++users[s];
  }
  return users;
}

// An orthonormal basis (k × (k − m)) of what a candidate's whitened rows
// leave beside the m unknowns only it observes (an observation set's own
// direction-set orientations: a common turn of its directions), or none
// (m = 0). Its residual has no redundancy along those (Q(t, t) and every
// Q(i, t) vanish there) and they leave with it, so snooping tests and
// removes it over the rest.
std::optional<Eigen::MatrixXd> beside_own_unknowns(const NetworkProblem& p, const MeasurementRows& r,
                                                   const std::vector<std::size_t>& users) {
  std::vector<Eigen::Index> own;
  for (std::size_t j = 0; j < r.unknowns.size(); ++j) {
    const auto [set, component] = p.layout.owner[static_cast<std::size_t>(r.unknowns[j])];
    if (component == 3 && users[set] == 1) own.push_back(static_cast<Eigen::Index>(j));
  }
  if (own.empty()) return std::nullopt;
  Eigen::MatrixXd g(r.a.rows(), static_cast<Eigen::Index>(own.size()));
  for (std::size_t j = 0; j < own.size(); ++j) g.col(static_cast<Eigen::Index>(j)) = r.a.col(own[j]);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  const Eigen::MatrixXd full = qr.householderQ() * Eigen::MatrixXd::Identity(g.rows(), g.rows());
  return Eigen::MatrixXd(full.rightCols(g.rows() - g.cols()));
}

// The failing measurements as snooping's candidates (their whitened
// residuals, cofactors and keys), their rows given to `cofactors`.
std::vector<SnoopingCandidate> snooping_candidates(const NetworkProblem& p, const NormalFactor& f, const AdjustmentResult& result,
                                                   const std::vector<std::size_t>& failing, std::vector<std::string>& keys,
                                                   NetworkCofactors& cofactors) {
  std::vector<SnoopingCandidate> candidates(failing.size());
  const std::vector<std::size_t> users = set_users(p);
  for (std::size_t c = 0; c < failing.size(); ++c) {
    const AdjustedMeasurement& am = result.measurements[failing[c]];
    const std::size_t mi = am.index;
    MeasurementRows r = p.linearize(mi);
    const std::size_t nu = r.unknowns.size();
    Eigen::MatrixXd q(static_cast<Eigen::Index>(nu), static_cast<Eigen::Index>(nu));
    if (!f.inverse_block(r.unknowns.data(), nu, q.data())) {
      throw std::logic_error("adjust_network: a measurement's unknowns are off the factor's pattern");
    }
    candidates[c].v = p.whitening[mi] * am.residual;
    if (const auto e = beside_own_unknowns(p, r, users)) {
      candidates[c].v = (e->transpose() * candidates[c].v).eval();
      r.a = (e->transpose() * r.a).eval();
    }
    const Eigen::Index k = r.a.rows();
    candidates[c].q = Eigen::MatrixXd::Identity(k, k) - r.a * q * r.a.transpose();
    candidates[c].key = std::move(keys[failing[c]]);
    cofactors.add(std::move(r.unknowns), std::move(r.a));
  }
  return candidates;
}

// The sequence's ranks and passes_after in the measurements, and a warning
// for each that fails but cannot be removed or told apart from others.
void record_sequence(const NetworkProblem& p, const SnoopingSequence& seq, const std::vector<std::size_t>& failing,
                     SnoopingRecord& record, AdjustmentResult& result) {
  const auto& net = p.net;
  const std::size_t removed = record.removed;
  const auto measurement_of = [&](std::size_t c) -> AdjustedMeasurement& { return result.measurements[failing[c]]; };
  for (std::size_t k = 0; k < seq.removals.size(); ++k) {
    AdjustedMeasurement& am = measurement_of(seq.removals[k].candidate);
    am.snooping_rank = removed + k + 1;
    record.rank_of[am.index] = am.snooping_rank;
  }
  for (std::size_t c = 0; c < failing.size(); ++c) {
    measurement_of(c).passes_after_rank =
        seq.passes_after[c] >= 0 ? removed + static_cast<std::size_t>(seq.passes_after[c]) + 1 : 0;
  }
  const std::string stops = "; data snooping stops there (the weaker failing measurements may fail because of it, so "
                            "none is removed in its place)";
  for (std::size_t c : seq.not_removable) {
    const AdjustedMeasurement& am = measurement_of(c);
    result.warnings.push_back(name_of(net, am) + " fails its " + describe(am, p.o.alpha_point) +
                              " but cannot be removed: the rest of the network does not determine all of what it measures" +
                              stops);
  }
  for (const auto& group : seq.inseparable) {
    std::string names;
    for (std::size_t c : group) names += (names.empty() ? "" : ", ") + name_of(net, measurement_of(c));
    result.warnings.push_back(
        names + " fail their measurement tests and cannot be told apart: with " + name_of(net, measurement_of(group.front())) +
        " removed the others could no longer be tested along the direction they share (their residuals are correlated by "
        "±1 there); one of them is wrong, none is removed" + stops);
  }
}

// Why data snooping stops (or would stop) at its limit: `worst` would still
// fail with the sequence's removals out.
std::string stopped_at_limit(const NetworkProblem& p, const SnoopingSequence& seq, const AdjustedMeasurement& worst,
                             const SnoopingRecord& record, std::size_t limit) {
  const auto& o = p.o;
  const std::size_t removed = record.removed, countable = record.countable;
  const SnoopingTest& worst_test = seq.still_failing.front();
  const std::size_t sequenced = removed + seq.removals.size();
  return "data snooping " + std::string(o.remove_outliers ? "stopped" : "would stop") + " after removing " +
         std::to_string(o.remove_outliers ? removed : sequenced) + " of " + std::to_string(countable) + " measurements" +
         (seq.hopeless ? " (" + std::to_string(seq.still_failing.size()) + " fail, more than the " +
                             std::to_string(limit - std::min(limit, sequenced)) + " removals left under the limit, and the last " +
                             std::to_string(kHopelessWindow) + " removals explained almost none of the others)"
                       : " (the limit is " + format_shortest(100.0 * o.max_outlier_share) + " %, --max-outlier-share)") +
         ": " + name_of(p.net, worst) + " would still fail its measurement test with those out (" + fmt(worst_test.statistic, 4) +
         ", χ²(" + std::to_string(worst_test.dof) + "), p = " + fmt(worst_test.p_value, 3) + "; as adjusted: " +
         describe(worst, o.alpha_point) + "); " + std::to_string(seq.still_failing.size()) +
         " measurements would fail then. So many failures mean the data or the model is wrong (frames, units, heights, "
         "station names), not a few blunders";
}

// The sequence's removals taken out of the adjustment (--remove-outliers),
// each with why.
void remove_sequenced(NetworkProblem& p, const SnoopingSequence& seq, const std::vector<std::size_t>& failing, SnoopingRecord& record,
                      AdjustmentResult& result) {
  const auto& net = p.net;
  for (const SnoopingTest& x : seq.removals) {
    const AdjustedMeasurement& am = result.measurements[failing[x.candidate]];
    const std::size_t mi = am.index;
    record.outlier_why[mi] = "data snooping (rank " + std::to_string(am.snooping_rank) + "): " + describe(am, p.o.alpha_point) +
                             (x.statistic != am.statistic
                                  ? " (with the measurements removed before it: " + fmt(x.statistic, 4) + ", p = " +
                                        fmt(x.p_value, 3) + ")"
                                  : std::string());
    p.active[mi] = false;
    const auto kind = net.measurements[mi].kind;
    p.pattern_only[mi] = kind == MeasurementKind::gnss_baselines || kind == MeasurementKind::gnss_points;
    record.removed_last_pass.push_back(mi);
  }
  record.removed += seq.removals.size();
  result.removed_per_pass.push_back(seq.removals.size());
}

}  // namespace

bool snoop_network(NetworkProblem& p, const NormalFactor& f, SnoopingRecord& record, AdjustmentResult& result, int jobs) {
  const auto& o = p.o;
  const auto snooping_t0 = Clock::now();
  std::vector<std::string> keys;
  const std::vector<std::size_t> failing = failing_by_content(p, result, keys);
  if (failing.empty()) return false;
  NetworkCofactors cofactors(f, p.layout.count, jobs);
  const std::vector<SnoopingCandidate> candidates = snooping_candidates(p, f, result, failing, keys, cofactors);
  const std::size_t limit = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::floor(o.max_outlier_share * static_cast<double>(record.countable))));
  SnoopingLimits limits;
  limits.alpha = o.alpha_point;
  limits.max_removals = limit > record.removed ? limit - record.removed : 0;
  const SnoopingSequence seq = snooping_sequence(candidates, cofactors, limits);
  result.seconds.snooping += since(snooping_t0);
  record_sequence(p, seq, failing, record, result);
  // Past the limit: with --remove-outliers the measurements up to it
  // go first (the next pass refuses, with them out), unless the
  // sequence found the failures hopeless (then it refuses now); else
  // named.
  if (seq.limit_reached && (!o.remove_outliers || seq.removals.empty() || seq.hopeless)) {
    const std::string why = stopped_at_limit(p, seq, result.measurements[failing[seq.still_failing.front().candidate]], record, limit);
    if (o.remove_outliers) result.refused_because = why;
    result.warnings.push_back(why);
    return false;
  }
  if (o.remove_outliers && !seq.removals.empty()) {
    remove_sequenced(p, seq, failing, record, result);
    return true;
  }
  return false;
}

}  // namespace geoanchor::solver
