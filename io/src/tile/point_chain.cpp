#include "geoanchor/io/tile/point_chain.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric_batch.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io {
namespace {

using geodesy::AffineMap;

bool is_local(CoordinateKind k) { return k == CoordinateKind::enu || k == CoordinateKind::ned; }

// NED <-> ENU is an axis permutation with a sign: its own inverse.
AffineMap ned_from_enu_map() {
  Eigen::Matrix3d p;
  p << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  return AffineMap(p, Eigen::Vector3d::Zero());
}

void require_frame(const ArrayFrame& f, const char* which) {
  if (is_local(f.kind) && !f.origin) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISSING", std::string(which) + ": ENU/NED coordinates need their origin");
  }
  if (f.kind == CoordinateKind::projected && !f.projection) {
    throw Error(ErrorKind::usage, "E_PROJECTION_MISSING", std::string(which) + ": easting/northing need their projection");
  }
}

}  // namespace

std::optional<AffineMap> PointChain::affine_ecef_from(const ArrayFrame& f) {
  switch (f.kind) {
    case CoordinateKind::ecef: return AffineMap::identity();
    case CoordinateKind::enu: return geodesy::LocalTangentPlane(*f.origin).ecef_from_enu_map();
    case CoordinateKind::ned:
      return geodesy::compose(geodesy::LocalTangentPlane(*f.origin).ecef_from_enu_map(), ned_from_enu_map());
    default: return std::nullopt;
  }
}

PointChain::PointChain(const ArrayFrame& from, const std::optional<TransformFile>& transform, bool inverse,
                       std::optional<geodesy::DecimalYear> epoch, const ArrayFrame& to)
    : from_(from), to_(to), transform_(transform), inverse_(inverse), epoch_(epoch), from_geocentric_(from.ellipsoid),
      to_geocentric_(to.ellipsoid) {
  require_frame(from_, "input");
  require_frame(to_, "output");
  if (is_local(from_.kind)) from_plane_.emplace(*from_.origin);
  if (is_local(to_.kind)) to_plane_.emplace(*to_.origin);
  if (from_.kind == CoordinateKind::projected) from_tm_.emplace(*from_.projection);
  if (to_.kind == CoordinateKind::projected) to_tm_.emplace(*to_.projection);
  // A 14-parameter transform without an epoch can only run point by point
  // at the points' own epochs (apply_at_epochs); apply() refuses it.
  // Fuse when every step is affine.
  const auto in = affine_ecef_from(from_);
  const auto out = affine_ecef_from(to_);
  ecef_in_ = in;
  ecef_out_ = out;
  if (transform_ && transform_->time_dependent() && !epoch_) return;  // per-point epochs only
  if (!in || (transform_ && transform_->site_calibration)) return;
  AffineMap middle = AffineMap::identity();
  if (transform_) {
    const AffineMap forward = transform_->target_from_source(epoch_, "transform");
    middle = inverse_ ? forward.inverse() : forward;
  }
  if (out) {
    fused_ = geodesy::compose(out->inverse(), geodesy::compose(middle, *in));
  } else {
    to_output_ecef_ = geodesy::compose(middle, *in);
  }
}

geodesy::EcefPosition PointChain::to_ecef(double a, double b, double c, std::size_t i, ChainReport& report) const {
  switch (from_.kind) {
    case CoordinateKind::ecef: return geodesy::EcefPosition(a, b, c);
    case CoordinateKind::geodetic:
      return from_geocentric_.ecef_from_geodetic(
          {geodesy::Angle::degrees(a), geodesy::Angle::degrees(b), geodesy::EllipsoidalHeight{c}});
    case CoordinateKind::enu: return from_plane_->ecef_from_enu({Eigen::Vector3d(a, b, c), *from_.origin});
    case CoordinateKind::ned:
      return from_plane_->ecef_from_enu(geodesy::enu_from_ned({Eigen::Vector3d(a, b, c), *from_.origin}));
    case CoordinateKind::projected: {
      geodesy::TmOutcome how;
      const auto g = from_tm_->try_inverse({a, b, geodesy::EllipsoidalHeight{c}, from_tm_->definition()}, &how);
      if (!g) {
        if (!report.first_refused) {
          report.first_refused = i;
          report.refusal = "input easting/northing " + format_shortest(a) + ", " + format_shortest(b) +
                           ": outside the projection's domain: " + from_tm_->explain(how);
        }
        const double nan = std::numeric_limits<double>::quiet_NaN();
        return geodesy::EcefPosition(nan, nan, nan);
      }
      if (const auto& z = from_tm_->definition().utm) {
        if (const auto band = geodesy::utm_band_check(*z, *g); geodesy::outside_band_margin(band)) {
          report.input_band.add(*z, *g, band, i, "");
        }
      }
      return from_geocentric_.ecef_from_geodetic(*g);
    }
  }
  return geodesy::EcefPosition();
}

void PointChain::project(double lat_deg, double lon_deg, double h_m, double& a, double& b, double& c, std::size_t i,
                         ChainReport& report) const {
  const geodesy::GeodeticPosition g{geodesy::Angle::degrees(lat_deg), geodesy::Angle::degrees(lon_deg),
                                    geodesy::EllipsoidalHeight{h_m}};
  geodesy::TmOutcome how;
  const auto q = to_tm_->try_forward(g, &how);
  if (!q) {
    // A non-finite point from an earlier step is not the projection's doing:
    // the caller names it as non-finite.
    if (!report.first_refused && how.refusal != geodesy::TmRefusal::non_finite) {
      report.first_refused = i;
      report.refusal = "outside the output projection's domain: " + to_tm_->explain(how);
    }
    a = b = std::numeric_limits<double>::quiet_NaN();
    c = h_m;
    return;
  }
  if (const auto& z = to_tm_->definition().utm) {
    if (const auto band = geodesy::utm_band_check(*z, g); geodesy::outside_band_margin(band)) {
      report.output_band.add(*z, g, band, i, "");
    }
  }
  a = q->easting_m, b = q->northing_m, c = q->h.m;
}

void PointChain::from_ecef(const geodesy::EcefPosition& x, double& a, double& b, double& c, std::size_t i,
                           ChainReport& report) const {
  switch (to_.kind) {
    case CoordinateKind::ecef: a = x.m.x(), b = x.m.y(), c = x.m.z(); return;
    case CoordinateKind::geodetic: {
      const auto g = to_geocentric_.geodetic_from_ecef(x);
      a = g.lat.deg(), b = g.lon.deg(), c = g.h.m;
      return;
    }
    case CoordinateKind::enu: {
      const Eigen::Vector3d e = to_plane_->enu_from_ecef(x).enu_m;
      a = e.x(), b = e.y(), c = e.z();
      return;
    }
    case CoordinateKind::ned: {
      const Eigen::Vector3d n = geodesy::ned_from_enu(to_plane_->enu_from_ecef(x)).ned_m;
      a = n.x(), b = n.y(), c = n.z();
      return;
    }
    case CoordinateKind::projected: {
      const auto g = to_geocentric_.geodetic_from_ecef(x);
      project(g.lat.deg(), g.lon.deg(), g.h.m, a, b, c, i, report);
      return;
    }
  }
}

namespace {

// One affine map over arrays, in place: a plain loop (Eigen's Affine ×
// Matrix3Xd goes through GEMM and a temporary, about 10× slower).
void apply_affine(const geodesy::AffineMap& m, std::span<double> a, std::span<double> b, std::span<double> c) {
  const std::size_t n = std::min({a.size(), b.size(), c.size()});
  const Eigen::Matrix3d& l = m.linear();
  const Eigen::Vector3d& t = m.translation_m();
  for (std::size_t i = 0; i < n; ++i) {
    const double x = a[i], y = b[i], z = c[i];
    a[i] = l(0, 0) * x + l(0, 1) * y + l(0, 2) * z + t(0);
    b[i] = l(1, 0) * x + l(1, 1) * y + l(1, 2) * z + t(1);
    c[i] = l(2, 0) * x + l(2, 1) * y + l(2, 2) * z + t(2);
  }
}

}  // namespace

void PointChain::finish_from_output_ecef(std::span<double> a, std::span<double> b, std::span<double> c,
                                         ChainReport& report) const {
  const std::size_t n = std::min({a.size(), b.size(), c.size()});
  if (ecef_out_) {
    apply_affine(ecef_out_->inverse(), a, b, c);
    return;
  }
  geodesy::geodetic_from_ecef_batch(to_.ellipsoid, a.first(n), b.first(n), c.first(n));
  if (to_.kind == CoordinateKind::projected) {
    for (std::size_t i = 0; i < n; ++i) project(a[i], b[i], c[i], a[i], b[i], c[i], i, report);
  }
}

ChainReport PointChain::apply_at_epochs(std::span<double> a, std::span<double> b, std::span<double> c,
                                        std::span<const double> epochs) const {
  const std::size_t n = std::min({a.size(), b.size(), c.size(), epochs.size()});
  if (!transform_ || !transform_->time_dependent()) return apply(a.first(n), b.first(n), c.first(n));
  ChainReport report;
  if (n == 0) return report;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(epochs[i])) {
      throw Error(ErrorKind::input, "E_EPOCH", "point " + std::to_string(i + 1) + " of a chunk has no finite epoch");
    }
  }
  const auto [lo_it, hi_it] = std::minmax_element(epochs.begin(), epochs.begin() + static_cast<std::ptrdiff_t>(n));
  const double lo = *lo_it, hi = *hi_it;
  auto middle_at = [&](double year) {
    const AffineMap forward = transform_->target_from_source(geodesy::DecimalYear{year}, "transform");
    return inverse_ ? forward.inverse() : forward;
  };
  if (ecef_in_) {
    // Input -> output ECEF at both ends, interpolated per point.
    const AffineMap m0 = geodesy::compose(middle_at(lo), *ecef_in_);
    const AffineMap m1 = geodesy::compose(middle_at(hi), *ecef_in_);
    const double span = hi - lo;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d x(a[i], b[i], c[i]);
      const Eigen::Vector3d p0 = m0.apply(x);
      const double w = span > 0.0 ? (epochs[i] - lo) / span : 0.0;
      const Eigen::Vector3d p = p0 + w * (m1.apply(x) - p0);
      a[i] = p.x(), b[i] = p.y(), c[i] = p.z();
    }
    finish_from_output_ecef(a.first(n), b.first(n), c.first(n), report);
    return report;
  }
  for (std::size_t i = 0; i < n; ++i) {
    geodesy::EcefPosition x = to_ecef(a[i], b[i], c[i], i, report);
    x = transform_->apply(x, geodesy::DecimalYear{epochs[i]}, inverse_, "transform");
    from_ecef(x, a[i], b[i], c[i], i, report);
  }
  return report;
}

ChainReport PointChain::apply(std::span<double> a, std::span<double> b, std::span<double> c) const {
  const std::size_t n = std::min({a.size(), b.size(), c.size()});
  ChainReport report;
  if (transform_ && transform_->time_dependent() && !epoch_) {
    throw Error(ErrorKind::usage, "E_EPOCH_MISSING",
                "a 14-parameter transform needs the observation epoch of the points; the reference epoch is never "
                "substituted");
  }
  if (fused_) {
    apply_affine(*fused_, a.first(n), b.first(n), c.first(n));
    return report;
  }
  if (to_output_ecef_) {
    apply_affine(*to_output_ecef_, a.first(n), b.first(n), c.first(n));
    finish_from_output_ecef(a.first(n), b.first(n), c.first(n), report);
    return report;
  }
  for (std::size_t i = 0; i < n; ++i) {
    geodesy::EcefPosition x = to_ecef(a[i], b[i], c[i], i, report);
    if (transform_) x = transform_->apply(x, epoch_, inverse_, "transform");
    from_ecef(x, a[i], b[i], c[i], i, report);
  }
  return report;
}

}  // namespace geoanchor::io
