// Where a tile's points reach: outside the transform's control network and
// from the ENU/NED origins (refused past --max-extrapolation), and the
// propagated uncertainty at the tile's corners.
#include "apply_tile.hpp"

#include <cmath>
#include <span>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/workflow/audit.hpp"
#include "geoanchor/workflow/transform_checks.hpp"
#include "geoanchor/workflow/uncertainty.hpp"

namespace geoanchor::workflow::apply_detail {

using geodesy::DecimalYear;
using io::ArrayFrame;
using nlohmann::json;

namespace {

// The largest horizontal distance of a batch from its origin (e, n or n, e).
double farthest(std::span<const double> a, std::span<const double> b) {
  double d2 = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double h2 = a[i] * a[i] + b[i] * b[i];
    if (!(h2 <= d2)) d2 = h2;  // NaN propagates to the refusal below
  }
  return std::sqrt(d2);
}

json enu_sigma_json(const Eigen::Matrix3d& cov_ecef, const geodesy::LocalOrigin& at) {
  const Eigen::Matrix3d r = geodesy::enu_from_ecef_rotation(at.point.lat, at.point.lon);
  const Eigen::Matrix3d c = r * cov_ecef * r.transpose();
  return json{{"sigma_e_m", std::sqrt(std::max(c(0, 0), 0.0))},
              {"sigma_n_m", std::sqrt(std::max(c(1, 1), 0.0))},
              {"sigma_u_m", std::sqrt(std::max(c(2, 2), 0.0))}};
}

}  // namespace

PointReach::PointReach(const TilePlan& p, const std::optional<io::TransformFile>& t, const std::unique_ptr<io::CrsOperation>& before) {
  const auto local = [](const ArrayFrame& f) {
    return (f.kind == io::CoordinateKind::enu || f.kind == io::CoordinateKind::ned) && f.origin.has_value();
  };
  extent = t && t->fit && t->fit->extent ? &*t->fit->extent : nullptr;
  if (extent) to_source_ecef.emplace(p.in.coordinates, std::nullopt, false, std::nullopt, ArrayFrame{});
  local_in = local(p.in.coordinates) && !before, local_out = local(p.out.coordinates);
}

void PointReach::watch(io::TileApplyOptions& ao) {
  if (extent || local_in) {
    ao.inspect_input = [this](std::span<const double> a, std::span<const double> b, std::span<const double> c) {
      if (local_in) record(from_origin_m[0], farthest(a, b));
      if (!extent) return;
      std::vector<double> x(a.begin(), a.end()), y(b.begin(), b.end()), z(c.begin(), c.end());
      (void)to_source_ecef->apply(x, y, z);
      record(worst_m, extent->max_distance_m(x, y, z));
    };
  }
  if (local_out) {
    ao.inspect_output = [this](std::span<const double> a, std::span<const double> b, std::span<const double>) {
      record(from_origin_m[1], farthest(a, b));
    };
  }
}

void PointReach::record(double& worst, double d) {
  const std::lock_guard<std::mutex> lock(m);
  if (!(d <= worst)) worst = d;
}

void TileRunner::check_origin_distances(const TilePlan& p, const PointReach& reach, const std::string& tile,
                                        std::vector<std::string>& warnings) const {
  const bool local_in = reach.local_in, local_out = reach.local_out;
  std::pair<double, std::string> tangent{0.0, ""};
  for (int end = 0; end < 2; ++end) {
    if (!(end == 0 ? local_in : local_out)) continue;
    const geodesy::LocalOrigin& origin = *(end == 0 ? p.in.coordinates : p.out.coordinates).origin;
    const double d = reach.from_origin_m[end];
    const std::string which = end == 0 ? "input's" : "output's";
    if (!(d <= o_.max_extrapolation_m)) {
      throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                  tile + ": the tile's points lie up to " + format_fixed(d / 1000.0, 3) + " km from the " + which +
                      " ENU/NED origin " + format_fixed(origin.point.lat.deg(), 9) + ", " + format_fixed(origin.point.lon.deg(), 9) +
                      " (limit --max-extrapolation " + format_shortest(o_.max_extrapolation_m) +
                      " m): latitude and longitude swapped, or the wrong origin?; nothing was written");
    }
    const double departure = tangent_plane_departure_m(d, origin.point.lat.deg(), origin.ellipsoid);
    if (departure > AuditLimits{}.tangent_plane_m && departure > tangent.first) {
      tangent = {departure, tile + ": the tile's points lie up to " + format_fixed(d / 1000.0, 3) + " km from the " + which +
                                " ENU/NED origin, where the tangent plane departs " + format_fixed(departure, 3) +
                                " m from the ellipsoid (d²/2R): a map this large is better kept in a projection"};
    }
  }
  if (!tangent.second.empty()) warnings.push_back(tangent.second);  // once: the farther of the two planes
}

// The transform's implausible parameters (issue 12 point 7): in the
// sidecar, and printed once for the run (ApplyResult::warnings), not here.
std::vector<std::string> TileRunner::transform_warnings_of(const TilePlan& p, const io::TileApplyResult& res, TileOutcome& r) const {
  std::vector<std::string> transform_warnings;
  if (t_) {
    std::optional<EpochSpan> span;
    if (t_->time_dependent() && res.epoch_range) {
      span = EpochSpan{DecimalYear{(*res.epoch_range)[0]}, DecimalYear{(*res.epoch_range)[1]}};
    } else if (t_->time_dependent() && p.epoch) {
      span = EpochSpan{*p.epoch, *p.epoch};
    }
    if (span) r.transform_epochs_year = std::make_pair(span->first.year, span->last.year);
    transform_warnings = implausible_transform_warnings(*t_, *o_.transform, span);
  }
  return transform_warnings;
}

TileCorners tile_corners(const TilePlan& p, const io::TileApplyResult& res, const std::unique_ptr<io::CrsOperation>& before,
                         const std::string& tile, std::vector<std::string>& warnings) {
  ArrayFrame ecef;
  const io::PointChain to_ecef(p.in.coordinates, std::nullopt, false, std::nullopt, ecef);
  std::vector<double> a, b, c;
  for (int k = 0; k < 9; ++k) {
    const bool centre = k == 8;
    a.push_back(centre ? 0.5 * (res.in_min[0] + res.in_max[0]) : (k & 1 ? res.in_max[0] : res.in_min[0]));
    b.push_back(centre ? 0.5 * (res.in_min[1] + res.in_max[1]) : (k & 2 ? res.in_max[1] : res.in_min[1]));
    c.push_back(centre ? 0.5 * (res.in_min[2] + res.in_max[2]) : (k & 4 ? res.in_max[2] : res.in_min[2]));
  }
  if (before) before->estimate(a.data(), b.data(), c.data(), a.size());  // the tile's CRS to its geocentric
  const io::ChainReport corners = to_ecef.apply(a, b, c);
  // A bounding-box corner may lie outside the input projection's domain
  // even when every point lies inside it: measure from the others, and say so.
  std::vector<std::size_t> usable;
  for (std::size_t k = 0; k < 9; ++k) {
    if (std::isfinite(a[k]) && std::isfinite(b[k]) && std::isfinite(c[k])) usable.push_back(k);
  }
  if (usable.empty()) {
    throw Error(ErrorKind::input, "E_PROJECTION_DOMAIN",
                tile + ": no corner of the tile's bounding box lies in its projection's domain (" + corners.refusal +
                    "): its extent outside the control network cannot be measured; nothing was written");
  }
  if (usable.size() < 9) {
    warnings.push_back(tile + ": " + std::to_string(9 - usable.size()) +
                       " of the bounding box's corners lie outside the input projection's domain (" + corners.refusal +
                       "); the extrapolation and uncertainty are measured at the other corners");
  }
  return TileCorners{std::move(a), std::move(b), std::move(c), std::move(usable)};
}

json TileRunner::extrapolation_record(const PointReach& reach, const std::string& tile, std::vector<std::string>& warnings) const {
  json extrapolation = nullptr;
  const double worst = reach.worst_m;
  if (!std::isfinite(worst)) {
    throw Error(ErrorKind::input, "E_EXTRAPOLATION", tile + ": the distance outside the control network of " + *o_.transform +
                                                         " cannot be computed; nothing was written");
  }
  extrapolation = {{"distance_outside_control_m", worst}, {"limit_m", o_.max_extrapolation_m}};
  if (worst > o_.max_extrapolation_m) {
    throw Error(ErrorKind::rejected, "E_EXTRAPOLATION",
                tile + ": the tile reaches " + format_fixed(worst, 1) +
                    " m outside the control network of " + *o_.transform + " (limit --max-extrapolation " +
                    format_shortest(o_.max_extrapolation_m) + " m); nothing was written");
  }
  if (worst > io::ControlExtent::kOnHull_m) {
    warnings.push_back(tile + ": the tile reaches " + format_fixed(worst, 1) +
                       " m outside the control network: the transform is extrapolated there");
  }
  return extrapolation;
}

json TileRunner::propagated_uncertainty(const TilePlan& p, const io::TileApplyResult& res, const TileCorners& corners) const {
  const std::vector<double>&a = corners.a, &b = corners.b, &c = corners.c;
  const std::vector<std::size_t>& usable = corners.usable;
  json uncertainty = nullptr;
  // The worst corner's propagated uncertainty, in ENU at the tile's centre.
  // With per-point epochs: at the middle of their range.
  std::optional<DecimalYear> at = p.epoch;
  if (!at && res.epoch_range) at = DecimalYear{0.5 * ((*res.epoch_range)[0] + (*res.epoch_range)[1])};
  std::optional<Eigen::Matrix3d> worst;
  for (std::size_t k : usable) {
    const auto cov = propagated_covariance_m2(*t_, geodesy::EcefPosition(a[k], b[k], c[k]), at, o_.inverse);
    if (!cov) continue;
    if (!cov->allFinite()) {
      throw Error(ErrorKind::input, "E_TRANSFORM_SIGMAS",
                  *o_.transform + ": the propagated uncertainty of the tile is not finite (the file's sigmas or "
                                  "correlation do not cover its parameters); nothing was written");
    }
    if (!worst || cov->trace() > worst->trace()) worst = cov;
  }
  if (worst) {
    const geodesy::GeocentricConverter g(geodesy::Ellipsoid::wgs84());
    geodesy::LocalOrigin centre;
    const std::size_t mid = std::isfinite(a[8]) && std::isfinite(b[8]) && std::isfinite(c[8]) ? 8 : usable.front();
    centre.point = g.geodetic_from_ecef(geodesy::EcefPosition(a[mid], b[mid], c[mid]));
    uncertainty = enu_sigma_json(*worst, centre);
    uncertainty["at"] = "the tile's bounding-box corner with the largest propagated variance";
    uncertainty["scaled_by_sigma0"] = t_->fit->sigmas_scaled_by_sigma0;
  }
  return uncertainty;
}

}  // namespace geoanchor::workflow::apply_detail
