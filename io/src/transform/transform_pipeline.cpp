// A transform file's transform as PROJ text: its EPSG method code, its PROJ
// pipeline (ECEF in, ECEF out), and where a stated pipeline differs from
// the one its model gives.

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "transform/transform_common.hpp"

namespace geoanchor::io {

using geodesy::CoordinateFrame;
using geodesy::PositionVector;
using detail::without_fit_record;

std::string epsg_method(const TransformFile& t) {
  // EPSG's Helmert methods are the small-angle formulas: finite rotations
  // have none (fit.md "Exports").
  if (t.enu_origin || t.site_calibration || t.rotation_model == geodesy::RotationModel::exact) return "";
  const bool pv = t.convention_name() == PositionVector::name;
  if (t.model == TransformModel::translation3) return "EPSG:1031";
  if (t.model == TransformModel::molodensky_badekas) return pv ? "EPSG:1061" : "EPSG:1034";
  if (t.time_dependent()) return pv ? "EPSG:1053" : "EPSG:1056";
  return pv ? "EPSG:1033" : "EPSG:1032";
}

namespace {
std::string topocentric(const geodesy::LocalOrigin& o) {
  const std::string ell = o.ellipsoid == geodesy::Ellipsoid::grs80() ? "+ellps=GRS80"
                          : o.ellipsoid == geodesy::Ellipsoid::wgs84() ? "+ellps=WGS84"
                                                                       : "+a=" + format_shortest(o.ellipsoid.a_m()) + " +rf=" + format_shortest(o.ellipsoid.rf());
  return "+proj=topocentric " + ell + " +lat_0=" + format_shortest(o.point.lat.deg()) + " +lon_0=" + format_shortest(o.point.lon.deg()) +
         " +h_0=" + format_shortest(o.point.h.m);
}
}  // namespace

std::string proj_pipeline(const TransformFile& t) {
  if (t.site_calibration) {
    // ECEF -> grid E, N and h is one affine map (local ENU, then the
    // similarity and the plane), composed once; then inverse TM and cart.
    // (PROJ refuses topocentric's cartesian output flowing into tmerc.)
    const auto& sc = *t.site_calibration;
    const auto& p = sc.params();
    const double k = 1.0 + p.scale.unitless(), a = k * std::cos(p.rotation.rad()), b = k * std::sin(p.rotation.rad());
    Eigen::Matrix3d l;
    l << a, -b, 0.0, b, a, 0.0, p.slope_e, p.slope_n, 1.0;
    const geodesy::AffineMap local_to_grid(
        l, Eigen::Vector3d(p.shift_e_m, p.shift_n_m, p.vertical_shift_m - p.slope_n * p.centroid_n_m - p.slope_e * p.centroid_e_m));
    const geodesy::AffineMap m =
        geodesy::compose(local_to_grid, geodesy::LocalTangentPlane(sc.local_origin()).enu_from_ecef_map());
    const auto& g = sc.grid();
    const std::string ell = g.ellipsoid == geodesy::Ellipsoid::grs80() ? "+ellps=GRS80"
                            : g.ellipsoid == geodesy::Ellipsoid::wgs84() ? "+ellps=WGS84"
                                                                         : "+a=" + format_shortest(g.ellipsoid.a_m()) + " +rf=" + format_shortest(g.ellipsoid.rf());
    std::string out = "+proj=pipeline +step +proj=affine";
    const char* off[3] = {"xoff", "yoff", "zoff"};
    for (int r = 0; r < 3; ++r) out += std::string(" +") + off[r] + "=" + format_shortest(m.translation_m()(r));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) out += " +s" + std::to_string(r + 1) + std::to_string(c + 1) + "=" + format_shortest(m.linear()(r, c));
    }
    return out + " +step +inv +proj=tmerc " + ell + " +lat_0=" + format_shortest(g.tm.lat0.deg()) + " +lon_0=" + format_shortest(g.tm.lon0.deg()) +
           " +k=" + format_shortest(g.tm.k0) + " +x_0=" + format_shortest(g.tm.false_easting_m) + " +y_0=" + format_shortest(g.tm.false_northing_m) +
           " +step +proj=cart " + ell;
  }
  if (t.enu_origin) {
    // ECEF -> map ENU at the nominal origin -> turn and scale -> ECEF from the corrected origin.
    const auto& c = *t.enu_origin;
    const double k = 1.0 + c.ds.unitless(), cy = std::cos(c.yaw.rad()), sy = std::sin(c.yaw.rad());
    return "+proj=pipeline +step " + topocentric(c.nominal) + " +step +proj=affine +s11=" + format_shortest(k * cy) + " +s12=" +
           format_shortest(-k * sy) + " +s13=0 +s21=" + format_shortest(k * sy) + " +s22=" + format_shortest(k * cy) + " +s23=0 +s31=0 +s32=0 +s33=" +
           format_shortest(k) + " +step +inv " + topocentric(geodesy::corrected_origin(c.nominal, c.shift_enu_m));
  }
  if (t.pivot_m && t.rotation_model == geodesy::RotationModel::exact) {
    // PROJ's molobadekas has no exact form: write the geocentric equivalent.
    TransformFile g = without_fit_record(t);
    const geodesy::AffineMap m = t.target_from_source(std::nullopt, "");
    std::visit([&](auto& h) {
      using H = std::decay_t<decltype(h)>;
      if constexpr (std::is_same_v<H, geodesy::Helmert7<PositionVector>> ||
                    std::is_same_v<H, geodesy::Helmert7<CoordinateFrame>>) {
        h.t_m = m.translation_m();
      }
    }, g.helmert);
    g.pivot_m.reset();
    g.model = TransformModel::helmert7;
    return proj_pipeline(g);
  }
  std::string out = t.pivot_m ? "+proj=pipeline +step +proj=molobadekas" : "+proj=pipeline +step +proj=helmert";
  auto add = [&](const char* key, double v) { out += std::string(" +") + key + "=" + format_shortest(v); };
  auto add7 = [&](const auto& p) {
    add("x", p.t_m.x());
    add("y", p.t_m.y());
    add("z", p.t_m.z());
    add("rx", p.rx.arcsec());
    add("ry", p.ry.arcsec());
    add("rz", p.rz.arcsec());
    add("s", p.ds.ppm());
  };
  std::visit([&](const auto& h) {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert14<PositionVector>> ||
                  std::is_same_v<H, geodesy::Helmert14<CoordinateFrame>>) {
      add7(h.at_reference_epoch);
      add("dx", h.rates.dt_m_per_year.x());
      add("dy", h.rates.dt_m_per_year.y());
      add("dz", h.rates.dt_m_per_year.z());
      add("drx", h.rates.drx_per_year.arcsec());
      add("dry", h.rates.dry_per_year.arcsec());
      add("drz", h.rates.drz_per_year.arcsec());
      add("ds", h.rates.dds_per_year.ppm());
      add("t_epoch", h.reference_epoch.year);
    } else {
      add7(h);
    }
  }, t.helmert);
  if (t.pivot_m) {
    add("px", t.pivot_m->x());
    add("py", t.pivot_m->y());
    add("pz", t.pivot_m->z());
  }
  out += " +convention=" + std::string(t.convention_name());
  if (t.rotation_model == geodesy::RotationModel::exact) out += " +exact";
  return out;
}

namespace detail {

// Where two PROJ strings differ: the first step or parameter that does, or
// nullopt when they say the same (numbers equal to 1e-12 relative, as
// written and read back by format_shortest).
std::optional<std::string> pipeline_difference(const std::string& stated, const std::string& expected) {
  const auto tokens = [](const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string w; in >> w;) out.push_back(w);
    return out;
  };
  const auto a = tokens(stated), b = tokens(expected);
  for (std::size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    const std::string x = i < a.size() ? a[i] : "(nothing)", y = i < b.size() ? b[i] : "(nothing)";
    if (x == y) continue;
    const auto eq_x = x.find('='), eq_y = y.find('=');
    if (eq_x != std::string::npos && eq_y != std::string::npos && x.substr(0, eq_x) == y.substr(0, eq_y)) {
      const auto u = parse_finite_double(x.substr(eq_x + 1)), v = parse_finite_double(y.substr(eq_y + 1));
      constexpr double kSameNumber = 1e-12;
      if (u && v && std::fabs(*u - *v) <= kSameNumber * std::max({1.0, std::fabs(*u), std::fabs(*v)})) continue;
    }
    return "it has " + x + " where they give " + y;
  }
  return std::nullopt;
}

}  // namespace detail

}  // namespace geoanchor::io
