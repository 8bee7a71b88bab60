// The transform file of `adjust --estimate-helmert`: the estimated Helmert
// in the file's units and convention, its statistics, where it was observed
// and the map metadata contract.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "adjust_outputs.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "geoanchor/workflow/fit_export.hpp"

namespace geoanchor::workflow {

namespace adjust_detail {

HelmertInFileUnits helmert_in_file_units(const PreparedNetwork& prepared, const solver::AdjustmentResult& r) {
  static const char* const kNames[14] = {"tx_m",           "ty_m",           "tz_m",           "rx_arcsec",
                                         "ry_arcsec",      "rz_arcsec",      "ds_ppm",         "dtx_m_per_year",
                                         "dty_m_per_year", "dtz_m_per_year", "drx_arcsec_per_year",
                                         "dry_arcsec_per_year", "drz_arcsec_per_year", "dds_ppm_per_year"};
  constexpr double kArcsecPerRad = 180.0 / std::numbers::pi * 3600.0;
  const Eigen::Index n = r.helmert->parameters.size();
  Eigen::VectorXd factor(n);
  HelmertInFileUnits u;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index j = k % 7;
    factor(k) = j < 3 ? 1.0 : j < 6 ? (prepared.helmert_position_vector ? 1.0 : -1.0) * kArcsecPerRad : 1e6;
    u.names.emplace_back(kNames[k]);
  }
  u.value = factor.cwiseProduct(r.helmert->parameters);
  u.covariance = factor.asDiagonal() * r.helmert->covariance * factor.asDiagonal();
  return u;
}

}  // namespace adjust_detail

using namespace adjust_detail;

io::TransformFile helmert_transform_file(const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                                         const solver::AdjustOptions& o, const std::string& generator) {
  if (!prepared.helmert || !r.helmert) throw std::logic_error("helmert_transform_file: no Helmert was estimated");
  const solver::HelmertGroup& g = *prepared.helmert;
  const bool pv = prepared.helmert_position_vector;
  const HelmertInFileUnits u = helmert_in_file_units(prepared, r);
  const Eigen::Index n = u.value.size();
  const Eigen::VectorXd& value = u.value;
  const Eigen::MatrixXd& cov = u.covariance;
  io::TransformFile t;
  t.model = g.rates ? io::TransformModel::helmert14 : io::TransformModel::helmert7;
  t.rotation_model = geodesy::RotationModel::small_angle;
  t.source_frame = prepared.helmert_frame;
  t.target_frame = prepared.network.frame;
  auto seven = [&](Eigen::Index at, auto h) {
    h.t_m = value.segment<3>(at);
    h.rx = geodesy::Angle::arcseconds(value(at + 3));
    h.ry = geodesy::Angle::arcseconds(value(at + 4));
    h.rz = geodesy::Angle::arcseconds(value(at + 5));
    h.ds = geodesy::ScaleDifference::ppm(value(at + 6));
    return h;
  };
  auto rates = [&](auto h) {
    h.dt_m_per_year = value.segment<3>(7);
    h.drx_per_year = geodesy::Angle::arcseconds(value(10));
    h.dry_per_year = geodesy::Angle::arcseconds(value(11));
    h.drz_per_year = geodesy::Angle::arcseconds(value(12));
    h.dds_per_year = geodesy::ScaleDifference::ppm(value(13));
    return h;
  };
  if (g.rates) {
    t.reference_epoch = geodesy::DecimalYear{g.reference_epoch};
    if (pv) {
      geodesy::Helmert14<geodesy::PositionVector> h;
      h.at_reference_epoch = seven(0, geodesy::Helmert7<geodesy::PositionVector>{});
      h.rates = rates(geodesy::Helmert7Rates<geodesy::PositionVector>{});
      h.reference_epoch = *t.reference_epoch;
      t.helmert = h;
    } else {
      geodesy::Helmert14<geodesy::CoordinateFrame> h;
      h.at_reference_epoch = seven(0, geodesy::Helmert7<geodesy::CoordinateFrame>{});
      h.rates = rates(geodesy::Helmert7Rates<geodesy::CoordinateFrame>{});
      h.reference_epoch = *t.reference_epoch;
      t.helmert = h;
    }
  } else if (pv) {
    t.helmert = seven(0, geodesy::Helmert7<geodesy::PositionVector>{});
  } else {
    t.helmert = seven(0, geodesy::Helmert7<geodesy::CoordinateFrame>{});
  }
  io::FitRecord f;
  for (Eigen::Index k = 0; k < n; ++k) {
    f.sigmas.emplace_back(u.names[static_cast<std::size_t>(k)], std::sqrt(std::max(0.0, cov(k, k))));
    f.correlation_names.push_back(u.names[static_cast<std::size_t>(k)]);
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    std::vector<double> row;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double d = std::sqrt(cov(i, i) * cov(j, j));
      row.push_back(i == j ? 1.0 : d > 0.0 ? std::clamp(cov(i, j) / d, -1.0, 1.0) : 0.0);
    }
    f.correlation.push_back(row);
  }
  f.sigmas_scaled_by_sigma0 = false;
  record_statistics(f, r.sigma0, r.dof, o.alpha, o.alpha_point, r.global_test);
  f.warnings = r.warnings;
  for (const auto& note : prepared.notes) {
    if (note.rfind("warning: ", 0) == 0) f.warnings.push_back(note.substr(9));
  }
  f.generator = generator;
  // The group's stations that the final adjustment used, in the group's
  // datum (taken back through the estimate, at the reference epoch): where
  // the transformation was observed, in its source frame.
  std::vector<bool> used(prepared.network.measurements.size(), false);
  for (const auto& am : r.measurements) used[am.index] = am.used;
  std::vector<geodesy::EcefPosition> marks;
  std::vector<bool> seen(r.stations.size(), false);
  const std::optional<geodesy::DecimalYear> at = t.reference_epoch;
  for (std::size_t mi : g.measurements) {
    if (!used[mi]) continue;
    for (std::size_t s : prepared.network.measurements[mi].stations) {
      if (seen[s]) continue;
      seen[s] = true;
      marks.push_back(t.apply(geodesy::EcefPosition(r.stations[s].position), at, true, "the group's stations"));
    }
  }
  if (!marks.empty()) f.extent = io::ControlExtent::of(marks);
  f.gnss_solutions = adjust_solution_record(prepared, r);
  t.fit = std::move(f);
  // The map metadata contract: the target side is the network's frame.
  using T = io::MapMetadataBuilder::Text;
  io::MapMetadataBuilder b("the transform file of adjust --estimate-helmert");
  const std::string derived = "the adjustment (the network's frame)";
  if (t.target_frame) {
    b.frame(t.target_frame->name(), derived);
    if (t.target_frame->epoch()) b.coordinate_epoch(t.target_frame->epoch()->year, derived);
  }
  const std::string& ellipsoid = prepared.network.ellipsoid.name();
  b.text(T::horizontal_crs,
         "geographic (latitude, longitude) on " + ellipsoid + (t.target_frame ? " in " + t.target_frame->to_string() : ""),
         derived);
  b.text(T::vertical_datum, "ellipsoid " + ellipsoid, derived);
  if (prepared.solution_policy) {
    geodesy::SolutionCounts c;
    for (const auto& m : prepared.network.measurements) {
      if (m.solution) ++c.count[geodesy::solution_index(*m.solution)];
    }
    b.gnss_solution_counts(c, "computed from the solution types of " + std::to_string(c.total()) + " GNSS measurements");
  }
  b.text(T::coordinate_storage, "float64 (JSON numbers at full precision)", "the transform file's format");
  t.metadata = b.metadata();
  return t;
}

}  // namespace geoanchor::workflow
