#include "control_common.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <vector>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"

namespace geoanchor::io::detail {

RoleConverter::RoleConverter(const ControlReadOptions& options) : options_(options), geocentric_(options.ellipsoid) {
  if (options_.origin) plane_.emplace(*options_.origin);
  if (options_.src_projection) src_grid_.emplace(*options_.src_projection);
  if (options_.dst_projection) dst_grid_.emplace(*options_.dst_projection);
}

geodesy::ControlInputForm input_form(CoordinateKind kind, const std::optional<geodesy::ProjectionDef>& projection) {
  geodesy::ControlInputForm f;
  switch (kind) {
    case CoordinateKind::geodetic: f.form = geodesy::CoordinateForm::geodetic; break;
    case CoordinateKind::enu: f.form = geodesy::CoordinateForm::enu; break;
    case CoordinateKind::projected:
      f.form = geodesy::CoordinateForm::projected;
      f.projection = projection;
      break;
    default: f.form = geodesy::CoordinateForm::ecef; break;
  }
  return f;
}

void RoleConverter::convert(const RoleValues& v, bool others_have_sigmas, const RoleFail& fail,
                            geodesy::EcefPosition& position, Eigen::Matrix3d& cov_m2) const {
  Eigen::Matrix3d local_to_ecef = Eigen::Matrix3d::Identity();  // axes of the covariance -> ECEF
  switch (v.kind) {
    case CoordinateKind::ecef: position = geodesy::EcefPosition(v.a, v.b, v.c); break;
    case CoordinateKind::geodetic: {
      if (std::fabs(v.a) > 90.0) fail(RoleField::first, "latitude not in [-90, 90] degrees");
      if (std::fabs(v.b) > 180.0) fail(RoleField::second, "longitude not in [-180, 180] degrees");
      const geodesy::GeodeticPosition g{geodesy::Angle::degrees(v.a), geodesy::Angle::degrees(v.b),
                                        geodesy::EllipsoidalHeight{v.c}};
      position = geocentric_.ecef_from_geodetic(g);
      local_to_ecef = geodesy::enu_from_ecef_rotation(g.lat, g.lon).transpose();
      break;
    }
    case CoordinateKind::enu:
      if (!plane_) {
        throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                    "ENU control coordinates need their nominal origin: give --origin LAT,LON,H");
      }
      position = plane_->ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d(v.a, v.b, v.c), *options_.origin});
      local_to_ecef = plane_->enu_from_ecef_rotation().transpose();
      break;
    case CoordinateKind::projected: {
      const auto& grid = v.source ? src_grid_ : dst_grid_;
      if (!grid) fail(RoleField::first, "projected control coordinates need their grid (--src-zone/--src-tm, --dst-zone/--dst-tm)");
      geodesy::TmOutcome how;
      const auto inverse =
          grid->try_inverse(geodesy::ProjectedPosition{v.a, v.b, geodesy::EllipsoidalHeight{v.c}, grid->definition()}, &how);
      if (!inverse) fail(RoleField::first, "not a position on the declared grid: " + grid->explain(how));
      const geodesy::GeodeticPosition g = *inverse;
      position = geocentric_.ecef_from_geodetic(g);
      local_to_ecef = geodesy::enu_from_ecef_rotation(g.lat, g.lon).transpose();
      break;
    }
    default: fail(RoleField::first, "control sets take ECEF, geodetic, ENU or projected coordinates");
  }
  Eigen::Matrix3d local = Eigen::Matrix3d::Identity();  // unit weight when the set gives no sigmas at all
  if (v.sigma_m) {
    if (!(*v.sigma_m > 0.0)) fail(RoleField::sigma, "must be > 0 (a standard deviation in metres)");
    local = Eigen::Matrix3d::Identity() * *v.sigma_m * *v.sigma_m;
  } else if (v.cov_m2) {
    const auto& c = *v.cov_m2;
    local << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
    if (Eigen::LLT<Eigen::Matrix3d>(local).info() != Eigen::Success || !(local.diagonal().minCoeff() > 0.0)) {
      fail(RoleField::covariance, "covariance is not positive definite");
    }
  } else if (others_have_sigmas) {
    local.setZero();  // the other frame carries the uncertainty
  }
  cov_m2 = local_to_ecef * local * local_to_ecef.transpose();
}

void refuse_duplicate_ids(const geodesy::ControlSet& set,
                          const std::function<std::string(const geodesy::ControlPoint&)>& where_new,
                          const std::function<std::string(const geodesy::ControlPoint&)>& where_of) {
  const auto& pts = set.points;
  const auto epoch_of = [](const geodesy::ControlPoint& p) { return p.epoch ? p.epoch->year : -1.0; };
  const auto same = [&](std::size_t a, std::size_t b) { return pts[a].id == pts[b].id && epoch_of(pts[a]) == epoch_of(pts[b]); };
  // Sorted by a hash of (id, epoch), 16 bytes a point, so that 10⁶ points
  // sort in cache; equal keys have equal hashes, and within a run of equal
  // hashes the points are compared themselves.
  std::vector<std::pair<std::size_t, std::size_t>> keyed(pts.size());  // (hash, index)
  for (std::size_t i = 0; i < pts.size(); ++i) {
    keyed[i] = {std::hash<std::string>{}(pts[i].id) ^ (std::hash<double>{}(epoch_of(pts[i])) * 0x9e3779b97f4a7c15ULL), i};
  }
  std::sort(keyed.begin(), keyed.end());
  std::optional<std::pair<std::size_t, std::size_t>> first_repeat;  // (earlier, repeat), the repeat first in the file
  for (std::size_t k = 0; k < keyed.size();) {
    std::size_t end = k + 1;
    while (end < keyed.size() && keyed[end].first == keyed[k].first) ++end;
    // Indices ascend within the run: each point's earliest equal is its first.
    for (std::size_t b = k + 1; b < end; ++b) {
      for (std::size_t a = k; a < b; ++a) {
        if (!same(keyed[a].second, keyed[b].second)) continue;
        if (!first_repeat || keyed[b].second < first_repeat->second) first_repeat = std::make_pair(keyed[a].second, keyed[b].second);
        break;
      }
    }
    k = end;
  }
  if (!first_repeat) return;
  const geodesy::ControlPoint& first = pts[first_repeat->first];
  const geodesy::ControlPoint& p = pts[first_repeat->second];
  const double d = std::max((first.source.m - p.source.m).norm(), (first.target.m - p.target.m).norm());
  throw Error(ErrorKind::input, "E_DUPLICATE_ID",
              where_new(p) + ": id=" + p.id + ": duplicate of " + where_of(first) + (p.epoch ? " at the same epoch" : "") +
                  " (coordinates differ by " + format_shortest(d) + " m); ids must be unique per epoch");
}

}  // namespace geoanchor::io::detail
