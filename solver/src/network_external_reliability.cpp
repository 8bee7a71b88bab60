// External reliability (network_external_reliability.hpp).

#include "network_external_reliability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstddef>
#include <string>
#include <vector>

#include "network_helmert.hpp"

namespace geoanchor::solver {

namespace {

// Right-hand sides per solve: enough to use the factor's blocks, few
// enough that the batch stays under ~160 MB at 10⁵ stations.
Eigen::Index batch_columns(Index unknowns) {
  constexpr double kBatchBytes = 160e6;
  const double fit = kBatchBytes / (8.0 * static_cast<double>(std::max<Index>(unknowns, 1)));
  return static_cast<Eigen::Index>(std::clamp(fit, 1.0, 64.0));
}

// One column's effect: its largest over the stations.
ExternalReliability largest_effect(const NetworkProblem& p, const Eigen::VectorXd& dx, const Eigen::MatrixXd& helmert_j) {
  ExternalReliability e;
  e.effect_m = e.horizontal_m = e.vertical_m = 0.0;
  for (std::size_t s = 0; s < p.layout.station.size(); ++s) {
    const auto& u = p.layout.station[s];
    Eigen::Vector3d along = Eigen::Vector3d::Zero();  // along the unknowns' axes
    bool any = false;
    for (int k = 0; k < 3; ++k) {
      const Index at = u[static_cast<std::size_t>(k)];
      if (at >= 0) {
        along(k) = dx(at);
        any = true;
      }
    }
    if (!any) continue;
    // In the local axes (AdjustedStation::covariance_local_m2's).
    const Eigen::Vector3d c = p.states[s].local_from_xyz * (p.states[s].axes.transpose() * along);
    const double horizontal = std::hypot(c(0), c(1));
    const double vertical = std::abs(c(2));
    const double length = std::hypot(horizontal, vertical);
    // NaN-propagating: a NaN length is taken (never silently dropped).
    if (!(length <= e.effect_m)) {
      e.effect_m = length;
      e.station = s;
    }
    if (!(horizontal <= e.horizontal_m)) {
      e.horizontal_m = horizontal;
      e.horizontal_station = s;
    }
    if (!(vertical <= e.vertical_m)) {
      e.vertical_m = vertical;
      e.vertical_station = s;
    }
  }
  if (helmert_j.size() > 0) {
    Eigen::VectorXd about_pivot(static_cast<Eigen::Index>(p.layout.helmert.size()));
    for (std::size_t k = 0; k < p.layout.helmert.size(); ++k) about_pivot(static_cast<Eigen::Index>(k)) = dx(p.layout.helmert[k]);
    e.helmert = helmert_j * about_pivot;
  }
  return e;
}

}  // namespace

void external_reliability(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result) {
  const Index n = p.layout.count;
  Eigen::MatrixXd helmert_j;
  if (!p.layout.helmert.empty()) helmert_j = geocentric_form(p.helmert, p.helmert_pivot, p.o.helmert->rates).j;
  const bool transform = inner.e.size() > 0;  // free: S = I − D M Eᵀ
  // The columns: (measurement slot, component), each Aᵢᵀ Wᵢᵀ Wᵢ (mdb e_k).
  struct Column {
    std::size_t slot;
    Eigen::Index component;
  };
  // In the canonical order (network_canonical_order.hpp): the solves are
  // batched, and a batch's composition must not depend on the order the
  // input lists the measurements in (the same bits for any order).
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> slot_of(p.net.measurements.size(), kNone);
  for (std::size_t slot = 0; slot < result.measurements.size(); ++slot) slot_of[result.measurements[slot].index] = slot;
  std::vector<Column> columns;
  for (const std::size_t mi : p.order) {
    const std::size_t slot = slot_of[mi];
    if (slot == kNone) continue;
    auto& am = result.measurements[slot];
    if (!am.used) continue;
    am.external.assign(static_cast<std::size_t>(am.mdb.size()), ExternalReliability{});
    for (Eigen::Index k = 0; k < am.mdb.size(); ++k) {
      if (std::isfinite(am.mdb(k))) columns.push_back({slot, k});
    }
  }
  if (columns.size() > kExternalReliabilityMaxComponents) {
    for (auto& am : result.measurements) am.external.clear();
    result.warnings.push_back("external reliability left out: " + std::to_string(columns.size()) +
                              " measurement components, past " + std::to_string(kExternalReliabilityMaxComponents) +
                              " (one solve with the factor each; docs/commands/adjust.md#external-reliability)");
    return;
  }
  const Eigen::Index batch = batch_columns(n);
  Eigen::MatrixXd rhs;
  std::size_t last_slot = result.measurements.size();
  MeasurementRows rows;
  for (std::size_t first = 0; first < columns.size(); first += static_cast<std::size_t>(batch)) {
    const std::size_t count = std::min(columns.size() - first, static_cast<std::size_t>(batch));
    rhs.setZero(n, static_cast<Eigen::Index>(count));
    for (std::size_t c = 0; c < count; ++c) {
      const Column& col = columns[first + c];
      const auto& am = result.measurements[col.slot];
      if (col.slot != last_slot) {
        rows = p.linearize(am.index);
        last_slot = col.slot;
      }
      const Eigen::MatrixXd& w = p.whitening[am.index];
      // Aᵀ P ∇l = (W A)ᵀ W ∇l, ∇l = mdb e_k.
      const Eigen::VectorXd whitened_bias = w.col(col.component) * am.mdb(col.component);
      const Eigen::VectorXd g = rows.a.transpose() * whitened_bias;
      for (std::size_t k = 0; k < rows.unknowns.size(); ++k) rhs(rows.unknowns[k], static_cast<Eigen::Index>(c)) += g(static_cast<Eigen::Index>(k));
    }
    Eigen::MatrixXd dx = f.solve(rhs);
    if (transform) dx -= p.defect * (inner.m * (inner.e.transpose() * dx));
    for (std::size_t c = 0; c < count; ++c) {
      const Column& col = columns[first + c];
      result.measurements[col.slot].external[static_cast<std::size_t>(col.component)] =
          largest_effect(p, dx.col(static_cast<Eigen::Index>(c)), helmert_j);
    }
  }
}

}  // namespace geoanchor::solver
