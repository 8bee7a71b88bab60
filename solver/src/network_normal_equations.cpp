// The normal equations of a network adjustment (network_normal_equations.hpp).

#include "network_normal_equations.hpp"

#include <algorithm>

#include "geoanchor/base/parallel.hpp"
#include "network_singularity.hpp"

namespace geoanchor::solver {

using geodesy::MeasurementKind;

namespace {

// The upper triangle of a measurement's AᵀA over its unknowns.
void push_upper(NormalEquations& n, const std::vector<Index>& unknowns, const Eigen::MatrixXd& ata) {
  for (std::size_t i = 0; i < unknowns.size(); ++i) {
    for (std::size_t j = 0; j < unknowns.size(); ++j) {
      if (unknowns[i] > unknowns[j]) continue;
      n.entries.push_back({unknowns[i], unknowns[j], ata(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))});
    }
  }
}

constexpr std::size_t kAssemblyBlock = 1 << 16;

}  // namespace

NormalEquations assemble(const NetworkProblem& p, bool matrix, int jobs) {
  NormalEquations n;
  n.b = Eigen::VectorXd::Zero(p.layout.count);
  struct Contribution {
    std::vector<Index> unknowns;
    Eigen::MatrixXd ata;
    Eigen::VectorXd atl;
    std::size_t rows = 0;
  };
  std::vector<std::size_t> active;
  for (std::size_t mi : p.order) {
    if (p.active[mi]) active.push_back(mi);
  }
  if (matrix) n.entries.reserve(21 * active.size());  // a baseline's 6 unknowns: 21 entries
  std::vector<Contribution> block;
  for (std::size_t first = 0; first < active.size(); first += kAssemblyBlock) {
    const std::size_t count = std::min(kAssemblyBlock, active.size() - first);
    block.resize(count);
    for_chunks(count, kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        MeasurementRows r = p.linearize(active[first + k]);
        Contribution& c = block[k];
        c.rows = static_cast<std::size_t>(r.l.size());
        c.atl = r.a.transpose() * r.l;
        if (matrix) c.ata = r.a.transpose() * r.a;
        c.unknowns = std::move(r.unknowns);
      }
    });
    for (const Contribution& c : block) {
      n.rows += c.rows;
      for (std::size_t i = 0; i < c.unknowns.size(); ++i) n.b(c.unknowns[i]) += c.atl(static_cast<Eigen::Index>(i));
      if (matrix) push_upper(n, c.unknowns, c.ata);
    }
  }
  if (matrix && !p.pattern_only.empty()) {
    for (std::size_t mi = 0; mi < p.net.measurements.size(); ++mi) {
      if (!p.pattern_only[mi] || p.active[mi]) continue;
      const auto& st = p.net.measurements[mi].stations;
      if (!std::all_of(st.begin(), st.end(), [&](std::size_t s) { return p.station_used[s]; })) continue;
      const MeasurementRows r = p.linearize(mi);
      push_upper(n, r.unknowns, Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(r.unknowns.size()), static_cast<Eigen::Index>(r.unknowns.size())));
    }
  }
  for (const auto& q : p.pseudo_observations()) {
    const double w = p.pseudo_weight(q.unknown);
    if (matrix) n.entries.push_back({q.unknown, q.unknown, w * w});
    n.b(q.unknown) += w * q.l;
    ++n.rows;
  }
  return n;
}

bool constant_jacobian(const NetworkProblem& p) {
  if (p.free || p.o.helmert) return false;
  for (std::size_t mi = 0; mi < p.net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    const auto k = p.net.measurements[mi].kind;
    if (k != MeasurementKind::gnss_baselines && k != MeasurementKind::gnss_points) return false;
  }
  return true;
}

NormalFactor factor_or_explain(const NetworkProblem& p, const NormalEquations& n, std::optional<NormalFactor> previous) {
  Index failed = -1;
  auto f = NormalFactor::factor(p.layout.count, n.entries, p.o.dense ? NormalFactor::Mode::dense : NormalFactor::Mode::sparse,
                                &failed, std::move(previous), p.o.memory_budget_bytes, resolve_jobs(p.o.jobs));
  if (!f) explain_singularity(p, n, failed);
  return std::move(*f);
}

}  // namespace geoanchor::solver
