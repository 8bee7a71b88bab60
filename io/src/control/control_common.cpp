#include "control/control_common.hpp"

#include <Eigen/Cholesky>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <future>
#include <optional>
#include <system_error>
#include <thread>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/crs/unit_factors.hpp"

namespace geoanchor::io::detail {

void resolve_ellipsoids(geodesy::ControlSet& set, const ControlReadOptions& o, const bool uses_ellipsoid[2]) {
  const std::optional<geodesy::Frame>* frames[2] = {&set.source_frame, &set.target_frame};
  std::optional<geodesy::Ellipsoid> implied[2];
  for (int k = 0; k < 2; ++k) {
    if (*frames[k]) implied[k] = geodesy::implied_ellipsoid(**frames[k]);
  }
  for (int k = 0; k < 2; ++k) {
    geodesy::ControlInputForm& form = k == 0 ? set.source_input : set.target_input;
    if (o.ellipsoid) {
      if (uses_ellipsoid[k] && implied[k] && !(*implied[k] == *o.ellipsoid)) {
        throw Error(ErrorKind::usage, "E_ELLIPSOID",
                    set.source_name + ": --ellipsoid " + o.ellipsoid->name() + " contradicts the " +
                        (k == 0 ? "source" : "target") + " frame " + (*frames[k])->to_string() + ", which is on " +
                        implied[k]->name() + "; drop --ellipsoid (the frame says it) or correct the frame");
      }
      form.ellipsoid = *o.ellipsoid;
    } else {
      form.ellipsoid = implied[k] ? *implied[k] : implied[1 - k] ? *implied[1 - k] : geodesy::Ellipsoid::wgs84();
    }
    if (form.projection) form.projection->ellipsoid = form.ellipsoid;
  }
}

void adopt_crs(geodesy::ControlSet& set, bool source, const CrsColumns& columns, const std::string& where) {
  geodesy::ControlInputForm& form = source ? set.source_input : set.target_input;
  const geodesy::Ellipsoid before = form.ellipsoid;
  form = geodesy::ControlInputForm{};
  form.form = geodesy::CoordinateForm::crs;
  // The CRS's own ellipsoid (PROJ places the points on it); one geoanchor's
  // type cannot hold (a sphere) leaves the role's as it was resolved.
  try {
    form.ellipsoid = typed_ellipsoid(columns.crs.description().ellipsoid);
  } catch (const Error&) {
    form.ellipsoid = before;
  }
  form.crs_name = columns.crs.display_name();
  if (columns.orthometric) {
    form.height_type = geodesy::HeightKind::orthometric;
    form.height_column = columns.names[2];
    form.geoid_model = columns.crs.description().geoid_model;
  }
  const std::string& catalog = columns.crs.description().catalog_frame;
  auto& frame = source ? set.source_frame : set.target_frame;
  if (catalog.empty()) return;
  const auto& e = columns.crs.epoch();
  const geodesy::Frame of_crs =
      geodesy::Frame::parse(catalog + (e ? "@" + geodesy::format_decimal_year(*e) : ""), set.source_name + ": " + where);
  if (frame && frame->name() != of_crs.name()) {
    throw Error(ErrorKind::input, "E_FRAME_CONFLICT",
                set.source_name + ": the " + (source ? "source" : "target") + " frame " + frame->to_string() +
                    " contradicts its CRS " + columns.crs.display_name() + ", which is on " + of_crs.name());
  }
  if (!frame) frame = of_crs;
}

void positions_from_crs(geodesy::ControlSet& set, bool source, const CrsColumns& columns, const std::string& where,
                        const std::function<bool(std::size_t)>& has_covariance,
                        const std::function<std::string(const geodesy::ControlPoint&)>& name) {
  constexpr std::size_t kBatch = 4096;
  // The covariance is in metres along each axis. A linear axis (easting,
  // northing, height, X) is differenced over ±1 m of PROJ's conversion:
  // small against the curvature of any projection (the Jacobian's relative
  // error is of order (step/R)²). A latitude or longitude axis is the unit
  // vector north or east at the point, from its latitude and longitude:
  // exact, and defined at a pole, where a step in latitude would leave the
  // CRS's domain.
  constexpr double kStep_m = 1.0;
  const CrsDescription& d = columns.crs.description();
  const auto& axes = d.visualization_axes;
  const std::size_t dims = std::min<std::size_t>(3, axes.size());
  std::vector<std::size_t> linear;  // the axes differenced, in order
  std::optional<std::size_t> lat_axis, lon_axis;
  for (std::size_t k = 0; k < dims; ++k) {
    if (axes[k].unit_type != "angular") {
      linear.push_back(k);
    } else if (axes[k].direction == "north" || axes[k].direction == "south") {
      lat_axis = k;
    } else {
      lon_axis = k;
    }
  }
  if (lat_axis.has_value() != lon_axis.has_value()) {
    throw Error(ErrorKind::input, "E_CRS",
                set.source_name + ": " + where + ": the CRS " + columns.crs.display_name() +
                    " has one angular axis without the other; expected a latitude and a longitude");
  }
  // An axis pointing south or west counts the other way.
  const auto signed_si = [&](std::size_t k) {
    const bool reversed = axes[k].direction == "south" || axes[k].direction == "west";
    return reversed ? -axes[k].unit_to_si : axes[k].unit_to_si;
  };
  const double pm_rad = d.prime_meridian_deg * detail::kRadiansPerDegree;
  const std::size_t per_point = 2 * linear.size();  // neighbours of a point with a covariance
  CrsOperation to_ecef(columns.crs, columns.crs.geocentric(where), set.source_name + ": " + where);
  std::vector<double> a, b, c;
  std::vector<std::size_t> with_cov;
  std::vector<Eigen::Matrix3d> jacobians;  // d(ECEF, m) / d(metres along each CRS axis)
  for (std::size_t first = 0; first < set.points.size(); first += kBatch) {
    const std::size_t n = std::min(kBatch, set.points.size() - first);
    with_cov.clear();
    for (std::size_t i = 0; i < n; ++i) {
      if (has_covariance(first + i)) with_cov.push_back(i);
    }
    a.resize(n + per_point * with_cov.size()), b.resize(a.size()), c.resize(a.size());
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d& v = source ? set.points[first + i].source_as_read : set.points[first + i].target_as_read;
      a[i] = v.x(), b[i] = v.y(), c[i] = v.z();
    }
    jacobians.assign(with_cov.size(), Eigen::Matrix3d::Zero());
    for (std::size_t j = 0; j < with_cov.size(); ++j) {
      const std::size_t i = with_cov[j];
      const double as_read[3] = {a[i], b[i], c[i]};
      if (lat_axis) {
        const double lat = as_read[*lat_axis] * signed_si(*lat_axis);
        const double lon = as_read[*lon_axis] * signed_si(*lon_axis) + pm_rad;
        const Eigen::Vector3d east(-std::sin(lon), std::cos(lon), 0.0);
        const Eigen::Vector3d north(-std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat));
        jacobians[j].col(static_cast<Eigen::Index>(*lat_axis)) = (signed_si(*lat_axis) < 0 ? -1.0 : 1.0) * north;
        jacobians[j].col(static_cast<Eigen::Index>(*lon_axis)) = (signed_si(*lon_axis) < 0 ? -1.0 : 1.0) * east;
      }
      // Its neighbours, ±step on each linear axis.
      for (std::size_t k = 0; k < per_point; ++k) {
        const std::size_t at = n + per_point * j + k;
        a[at] = a[i], b[at] = b[i], c[at] = c[i];
        double* axis[3] = {&a[at], &b[at], &c[at]};
        *axis[linear[k / 2]] += (k % 2 == 0 ? 1.0 : -1.0) * kStep_m / axes[linear[k / 2]].unit_to_si;
      }
    }
    to_ecef.transform(a.data(), b.data(), c.data(), n, [&](std::size_t i) { return name(set.points[first + i]); });
    // The neighbours serve the Jacobian only: not counted as marks moved.
    to_ecef.transform(
        a.data() + n, b.data() + n, c.data() + n, a.size() - n,
        [&](std::size_t i) { return name(set.points[first + with_cov[i / per_point]]) + " (a neighbour for its covariance)"; },
        CrsOperation::Count::no);
    for (std::size_t i = 0; i < n; ++i) {
      (source ? set.points[first + i].source : set.points[first + i].target) = geodesy::EcefPosition(a[i], b[i], c[i]);
    }
    for (std::size_t j = 0; j < with_cov.size(); ++j) {
      for (std::size_t l = 0; l < linear.size(); ++l) {
        const std::size_t plus = n + per_point * j + 2 * l, minus = plus + 1;
        const Eigen::Vector3d diff(a[plus] - a[minus], b[plus] - b[minus], c[plus] - c[minus]);
        jacobians[j].col(static_cast<Eigen::Index>(linear[l])) = diff / (2.0 * kStep_m);
      }
      geodesy::ControlPoint& p = set.points[first + with_cov[j]];
      Eigen::Matrix3d& cov = source ? p.source_cov_m2 : p.target_cov_m2;
      cov = jacobians[j] * cov * jacobians[j].transpose();
    }
  }
  // What PROJ did, for the outputs to record.
  nlohmann::ordered_json record;
  record["crs"] = columns.crs.text();
  record["name"] = d.name;
  record["identifier"] = d.identifier.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(d.identifier);
  record["wkt2"] = columns.crs.wkt2();
  record["operation"] = nlohmann::ordered_json::parse(operation_record_json(to_ecef));
  geodesy::ControlInputForm& form = source ? set.source_input : set.target_input;
  form.crs_warnings = to_ecef.warnings();
  record["warnings"] = form.crs_warnings;
  form.crs_record_json = record.dump();
}

void apply_caller_frames(geodesy::ControlSet& set, const ControlReadOptions& o) {
  for (const bool source : {true, false}) {
    // A role read through a CRS has the CRS's datum for its frame: a flag
    // may add the epoch of the points' observation, never another frame.
    const geodesy::ControlInputForm& form = source ? set.source_input : set.target_input;
    const auto& caller = source ? o.source_frame.replace : o.target_frame.replace;
    const auto& frame = source ? set.source_frame : set.target_frame;
    if (form.form != geodesy::CoordinateForm::crs || !caller) continue;
    const char* flag = source ? "--source-frame" : "--target-frame";
    const std::string role = source ? "source" : "target";
    if (!frame) {
      throw Error(ErrorKind::usage, "E_FRAME_CONFLICT",
                  set.source_name + ": " + flag + " " + caller->to_string() + " names the " + role + " frame, but the " +
                      role + " coordinates are in the CRS " + form.crs_name +
                      ", whose datum is no frame of geoanchor's catalog and is moved by PROJ as that datum; drop the flag");
    }
    if (caller->name() != frame->name() ||
        (frame->epoch() && !(caller->epoch() && caller->epoch()->year == frame->epoch()->year))) {
      throw Error(ErrorKind::usage, "E_FRAME_CONFLICT",
                  set.source_name + ": " + flag + " " + caller->to_string() + " contradicts the " + role + " CRS " +
                      form.crs_name + ", whose frame is " + frame->to_string() + "; drop the flag or give that frame");
    }
  }
  for (const auto& [caller, frame] : {std::pair{&o.source_frame, &set.source_frame}, std::pair{&o.target_frame, &set.target_frame}}) {
    if (caller->replace) {
      *frame = caller->replace;
    } else if (!*frame && caller->fallback) {
      *frame = caller->fallback;
    }
  }
}

RoleConverter::RoleConverter(const ControlReadOptions& options, const geodesy::ControlSet& set)
    : options_(options), src_geocentric_(set.source_input.ellipsoid), dst_geocentric_(set.target_input.ellipsoid) {
  if (options_.origin) {
    src_origin_ = dst_origin_ = options_.origin;
    src_origin_->ellipsoid = set.source_input.ellipsoid;
    dst_origin_->ellipsoid = set.target_input.ellipsoid;
    src_plane_.emplace(*src_origin_);
    dst_plane_.emplace(*dst_origin_);
  }
  if (options_.src_projection) {
    auto p = *options_.src_projection;
    p.ellipsoid = set.source_input.ellipsoid;
    src_grid_.emplace(p);
  }
  if (options_.dst_projection) {
    auto p = *options_.dst_projection;
    p.ellipsoid = set.target_input.ellipsoid;
    dst_grid_.emplace(p);
  }
}

geodesy::ControlInputForm input_form(CoordinateKind kind, const std::optional<geodesy::ProjectionDef>& projection,
                                     const std::string& height_column, const geodesy::GeoidGrid* geoid) {
  geodesy::ControlInputForm f;
  if (!height_column.empty() && geoid) {
    f.height_type = geodesy::HeightKind::orthometric;
    f.height_column = height_column;
    f.geoid_model = geoid->model_name();
  }
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

void refuse_orthometric_without_geoid(const std::string& where) {
  throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
              where + ": orthometric height (H, above the geoid): reading it as the ellipsoidal height a control point "
                      "needs takes the geoid model: give --geoid EGM96 (h = H + N), or give ellipsoidal heights as h");
}

void check_physical_positions(const geodesy::ControlSet& set, const std::function<std::string(const geodesy::ControlPoint&)>& where) {
  // Each role's own ellipsoid is within a few hundred metres of GRS80's, far
  // inside the range's kilometres.
  const geodesy::Ellipsoid e = geodesy::Ellipsoid::grs80();
  for (const auto& p : set.points) {
    for (const bool source : {true, false}) {
      const geodesy::EcefPosition& x = source ? p.source : p.target;
      const std::string problem = geodesy::physical_ecef_problem(x.m, e);
      if (problem.empty()) continue;
      throw Error(ErrorKind::input, "E_ECEF_RANGE",
                  where(p) + ": " + p.id + ": its " + (source ? "source" : "target") + " " + problem +
                      ": a unit, a swapped column or a placeholder?");
    }
  }
}

void check_frame_epochs(const geodesy::ControlSet& set, const ControlReadOptions& o, const std::string& source_where,
                        const std::string& target_where) {
  const bool every_point_dated =
      !set.points.empty() && std::all_of(set.points.begin(), set.points.end(), [](const auto& p) { return p.epoch.has_value(); });
  if (every_point_dated) return;
  const std::string other_way = ", or an epoch for every point";
  if (set.source_frame && !o.source_frame.replace) {
    geodesy::require_epoch_if_dynamic(*set.source_frame, source_where, ErrorKind::input, other_way);
  }
  if (set.target_frame && !o.target_frame.replace) {
    geodesy::require_epoch_if_dynamic(*set.target_frame, target_where, ErrorKind::input, other_way);
  }
}

double RoleConverter::convert(const RoleValues& v, bool others_have_sigmas, const RoleFail& fail,
                              geodesy::EcefPosition& position, Eigen::Matrix3d& cov_m2) const {
  Eigen::Matrix3d local_to_ecef = Eigen::Matrix3d::Identity();  // axes of the covariance -> ECEF
  const geodesy::GeoidGrid* geoid = v.source ? options_.src_geoid : options_.dst_geoid;
  double undulation_m = 0.0;
  // h = H + N at the point's latitude and longitude, for orthometric input.
  const auto to_ellipsoidal = [&](geodesy::GeodeticPosition& g) {
    if (!v.orthometric) return;
    if (!geoid) fail(RoleField::third, "orthometric height without a geoid model: give --geoid EGM96 (h = H + N)");
    undulation_m = geoid->undulation_m(g.lat, g.lon);
    if (!std::isfinite(undulation_m)) fail(RoleField::third, "the point lies outside the grid of " + geoid->model_name());
    g.h.m += undulation_m;
  };
  switch (v.kind) {
    case CoordinateKind::ecef: position = geodesy::EcefPosition(v.a, v.b, v.c); break;
    case CoordinateKind::geodetic: {
      if (std::fabs(v.a) > 90.0) fail(RoleField::first, "latitude not in [-90, 90] degrees");
      if (std::fabs(v.b) > 180.0) fail(RoleField::second, "longitude not in [-180, 180] degrees");
      geodesy::GeodeticPosition g{geodesy::Angle::degrees(v.a), geodesy::Angle::degrees(v.b),
                                  geodesy::EllipsoidalHeight{v.c}};
      to_ellipsoidal(g);
      position = (v.source ? src_geocentric_ : dst_geocentric_).ecef_from_geodetic(g);
      local_to_ecef = geodesy::enu_from_ecef_rotation(g.lat, g.lon).transpose();
      break;
    }
    case CoordinateKind::enu: {
      const auto& plane = v.source ? src_plane_ : dst_plane_;
      if (!plane) {
        throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                    "ENU control coordinates need their nominal origin: give --origin LAT,LON,H");
      }
      position = plane->ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d(v.a, v.b, v.c), v.source ? *src_origin_ : *dst_origin_});
      local_to_ecef = plane->enu_from_ecef_rotation().transpose();
      break;
    }
    case CoordinateKind::projected: {
      const auto& grid = v.source ? src_grid_ : dst_grid_;
      if (!grid) fail(RoleField::first, "projected control coordinates need their grid (--src-zone/--src-tm, --dst-zone/--dst-tm)");
      geodesy::TmOutcome how;
      const auto inverse =
          grid->try_inverse(geodesy::ProjectedPosition{v.a, v.b, geodesy::EllipsoidalHeight{v.c}, grid->definition()}, &how);
      if (!inverse) fail(RoleField::first, "not a position on the declared grid: " + grid->explain(how));
      geodesy::GeodeticPosition g = *inverse;
      to_ellipsoidal(g);
      position = (v.source ? src_geocentric_ : dst_geocentric_).ecef_from_geodetic(g);
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
  return undulation_m;
}

void refuse_duplicate_ids(const geodesy::ControlSet& set,
                          const std::function<std::string(const geodesy::ControlPoint&)>& where_new,
                          const std::function<std::string(const geodesy::ControlPoint&)>& where_of) {
  const auto& pts = set.points;
  const auto epoch_of = [](const geodesy::ControlPoint& p) { return p.epoch ? p.epoch->year : -1.0; };
  const auto same = [&](std::size_t a, std::size_t b) { return pts[a].id == pts[b].id && epoch_of(pts[a]) == epoch_of(pts[b]); };
  // Sorted by a hash of (id, epoch), 16 bytes a point, so that 10⁶ points
  // sort in cache; equal keys have equal hashes, and within a run of equal
  // hashes the points are compared themselves. Two halves are hashed and
  // sorted at once, then merged (10⁶ points: 0.09 s on one core).
  std::vector<std::pair<std::size_t, std::size_t>> keyed(pts.size());  // (hash, index)
  const auto sort_range = [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) {
      keyed[i] = {std::hash<std::string>{}(pts[i].id) ^ (std::hash<double>{}(epoch_of(pts[i])) * 0x9e3779b97f4a7c15ULL), i};
    }
    std::sort(keyed.begin() + static_cast<std::ptrdiff_t>(first), keyed.begin() + static_cast<std::ptrdiff_t>(last));
  };
  constexpr std::size_t kParallelFrom = 65536;  // points; fewer sort in a few milliseconds
  const std::size_t half = pts.size() / 2;
  if (pts.size() < kParallelFrom || std::thread::hardware_concurrency() < 2) {
    sort_range(0, pts.size());
  } else {
    std::future<void> upper;
    try {
      upper = std::async(std::launch::async, sort_range, half, pts.size());
    } catch (const std::system_error&) {  // no thread to be had: this one sorts both halves
      upper = std::async(std::launch::deferred, sort_range, half, pts.size());
    }
    sort_range(0, half);
    upper.get();
    std::inplace_merge(keyed.begin(), keyed.begin() + static_cast<std::ptrdiff_t>(half), keyed.end());
  }
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
