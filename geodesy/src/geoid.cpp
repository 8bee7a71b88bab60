#include "geoanchor/geodesy/geoid.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>

#include "geoanchor/base/error.hpp"

namespace geoanchor::geodesy {
namespace {

// .gtx is big-endian: swap on little-endian hosts.
template <class T>
T from_big_endian(const unsigned char* p) {
  unsigned char b[sizeof(T)];
  for (std::size_t i = 0; i < sizeof(T); ++i) b[i] = p[std::endian::native == std::endian::little ? sizeof(T) - 1 - i : i];
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

constexpr std::size_t kHeaderBytes = 40;  // lat0, lon0, dlat, dlon (float64), rows, cols (int32)

}  // namespace

GeoidGrid GeoidGrid::load_gtx(const std::filesystem::path& path, std::string model_name) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open geoid grid");
  const auto size = static_cast<std::size_t>(in.tellg());
  in.seekg(0);
  std::vector<unsigned char> bytes(size);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
    throw Error(ErrorKind::io, "E_READ", path.string() + ": read failed");
  }
  if (size < kHeaderBytes) {
    throw Error(ErrorKind::input, "E_GRID", path.string() + ": " + std::to_string(size) + " bytes, shorter than a .gtx header (40)");
  }
  GeoidGrid g;
  g.name_ = std::move(model_name);
  g.path_ = path;
  g.lat0_deg_ = from_big_endian<double>(&bytes[0]);
  g.lon0_deg_ = from_big_endian<double>(&bytes[8]);
  g.dlat_deg_ = from_big_endian<double>(&bytes[16]);
  g.dlon_deg_ = from_big_endian<double>(&bytes[24]);
  g.rows_ = from_big_endian<std::int32_t>(&bytes[32]);
  g.cols_ = from_big_endian<std::int32_t>(&bytes[36]);
  if (!(g.dlat_deg_ > 0 && g.dlon_deg_ > 0) || g.rows_ < 2 || g.cols_ < 2 || !(std::abs(g.lat0_deg_) <= 90.0)) {
    throw Error(ErrorKind::input, "E_GRID", path.string() + ": header (lat0 " + std::to_string(g.lat0_deg_) + ", spacing " +
                                                std::to_string(g.dlat_deg_) + "°, " + std::to_string(g.rows_) + " × " +
                                                std::to_string(g.cols_) + ") is not a .gtx grid");
  }
  const std::size_t n = static_cast<std::size_t>(g.rows_) * static_cast<std::size_t>(g.cols_);
  if (size != kHeaderBytes + 4 * n) {
    throw Error(ErrorKind::input, "E_GRID",
                path.string() + ": " + std::to_string(size) + " bytes; a " + std::to_string(g.rows_) + " × " +
                    std::to_string(g.cols_) + " .gtx grid has " + std::to_string(kHeaderBytes + 4 * n));
  }
  g.values_m_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float v = from_big_endian<float>(&bytes[kHeaderBytes + 4 * i]);
    g.values_m_[i] = v == -88.8888f ? std::numeric_limits<float>::quiet_NaN() : v;  // VDatum's no-data value
  }
  g.global_lon_ = std::abs(g.cols_ * g.dlon_deg_ - 360.0) < 1e-9;
  return g;
}

const GeoidGrid& GeoidGrid::egm96() {
  static std::once_flag once;
  static GeoidGrid grid;
  std::call_once(once, [] {
    std::vector<std::filesystem::path> dirs;
    for (const char* var : {"PROJ_DATA", "PROJ_LIB"}) {
      if (const char* v = std::getenv(var); v && *v) dirs.emplace_back(v);
    }
    dirs.emplace_back("/usr/share/proj");
    for (const auto& d : dirs) {
      if (std::filesystem::is_regular_file(d / "egm96_15.gtx")) {
        grid = load_gtx(d / "egm96_15.gtx", "EGM96 (15' grid, egm96_15.gtx)");
        return;
      }
    }
    throw Error(ErrorKind::io, "E_READ",
                "egm96_15.gtx: not found in $PROJ_DATA, $PROJ_LIB or /usr/share/proj (Debian package proj-data; run "
                "scripts/setup.sh)");
  });
  return grid;
}

const GeoidGrid& GeoidGrid::egm96_nga() {
  static std::once_flag once;
  static GeoidGrid grid;
  std::call_once(once, [] {
    grid = egm96();
    grid.name_ = "EGM96 (15' grid, egm96_15.gtx, NGA INTPT spline)";
    grid.interpolation_ = GeoidInterpolation::nga_spline;
  });
  return grid;
}

namespace {

// The natural cubic spline through y0..y3 at x = 0, 1, 2, 3 (zero second
// derivative at both ends), evaluated at 1 + u, u in [0, 1].
double natural_spline_middle(double y0, double y1, double y2, double y3, double u) {
  // Interior second derivatives: M0 + 4 M1 + M2 = 6 (y2 − 2 y1 + y0) and
  // M1 + 4 M2 + M3 = 6 (y3 − 2 y2 + y1), with M0 = M3 = 0.
  const double a = 6.0 * (y2 - 2.0 * y1 + y0), b = 6.0 * (y3 - 2.0 * y2 + y1);
  const double m1 = (4.0 * a - b) / 15.0, m2 = (4.0 * b - a) / 15.0;
  const double v = 1.0 - u;
  return v * y1 + u * y2 + (v * v * v - v) * m1 / 6.0 + (u * u * u - u) * m2 / 6.0;
}

}  // namespace

double GeoidGrid::spline_m(double y, double x) const {
  const auto r0 = static_cast<std::int32_t>(std::floor(y));
  const auto c0 = static_cast<std::int32_t>(std::floor(x));
  const auto at = [&](std::int32_t r, std::int32_t c) {
    // Rows beyond the grid's edge repeat the edge (NGA limits its spline to
    // |lat| ≤ 89°44'24"); columns wrap on a global grid and clamp otherwise.
    r = std::clamp(r, 0, rows_ - 1);
    c = global_lon_ ? (c % cols_ + cols_) % cols_ : std::clamp(c, 0, cols_ - 1);
    return static_cast<double>(values_m_[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(c)]);
  };
  double column[4];
  for (std::int32_t k = 0; k < 4; ++k) {
    const std::int32_t r = r0 - 1 + k;
    column[k] = natural_spline_middle(at(r, c0 - 1), at(r, c0), at(r, c0 + 1), at(r, c0 + 2), x - c0);
  }
  return natural_spline_middle(column[0], column[1], column[2], column[3], y - r0);
}

GeoidGrid GeoidGrid::from_evaluator(std::string model_name, std::filesystem::path path,
                                    std::function<double(double, double)> n_at) {
  GeoidGrid g;
  g.name_ = std::move(model_name);
  g.path_ = std::move(path);
  g.external_ = std::make_shared<const std::function<double(double, double)>>(std::move(n_at));
  return g;
}

namespace {

// The Catmull–Rom cubic through y0..y3 at x = 0, 1, 2, 3, evaluated at
// 1 + u, u in [0, 1]: the Hermite cubic between y1 and y2 whose end
// derivatives are the central differences (y2 − y0)/2 and (y3 − y1)/2.
double catmull_rom(double y0, double y1, double y2, double y3, double u) {
  return y1 + 0.5 * u * ((y2 - y0) + u * ((2.0 * y0 - 5.0 * y1 + 4.0 * y2 - y3) + u * (3.0 * (y1 - y2) + y3 - y0)));
}

}  // namespace

double GeoidGrid::sample(const std::vector<float>& field, double lat_deg, double lon_deg) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double y = (lat_deg - lat0_deg_) / dlat_deg_;
  double x = (lon_deg - lon0_deg_) / dlon_deg_;
  if (!std::isfinite(x) || !std::isfinite(y)) return nan;
  if (global_lon_) x = std::fmod(std::fmod(x, cols_) + cols_, cols_);
  if (y < 0 || y > rows_ - 1) return nan;
  if (!global_lon_ && (x < 0 || x > cols_ - 1)) return nan;
  const auto at = [&](std::int32_t r, std::int32_t c) {
    // Nodes past the edge repeat it; columns wrap on a global grid.
    r = std::clamp(r, 0, rows_ - 1);
    c = global_lon_ ? (c % cols_ + cols_) % cols_ : std::clamp(c, 0, cols_ - 1);
    return static_cast<double>(field[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(c)]);
  };
  const auto r0 = static_cast<std::int32_t>(std::floor(y));
  const auto c0 = static_cast<std::int32_t>(std::floor(x));
  const double fy = y - r0, fx = x - c0;
  switch (interpolation_) {
    case GeoidInterpolation::nga_spline:
      if (&field == &values_m_) return spline_m(y, x);
      break;
    case GeoidInterpolation::bicubic: {
      double column[4];
      for (std::int32_t k = 0; k < 4; ++k) {
        const std::int32_t r = r0 - 1 + k;
        column[k] = catmull_rom(at(r, c0 - 1), at(r, c0), at(r, c0 + 1), at(r, c0 + 2), fx);
      }
      return catmull_rom(column[0], column[1], column[2], column[3], fy);
    }
    case GeoidInterpolation::bilinear:
      break;
  }
  return (1 - fy) * ((1 - fx) * at(r0, c0) + fx * at(r0, c0 + 1)) + fy * ((1 - fx) * at(r0 + 1, c0) + fx * at(r0 + 1, c0 + 1));
}

double GeoidGrid::undulation_m(Angle lat, Angle lon) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (external_) {
    if (!std::isfinite(lat.deg()) || !std::isfinite(lon.deg())) return nan;
    const double n = (*external_)(lat.deg(), lon.deg());
    return std::isfinite(n) ? n : nan;
  }
  return sample(values_m_, lat.deg(), lon.deg());
}

std::optional<Deflection> GeoidGrid::deflection(Angle lat, Angle lon) const {
  if (xi_arcsec_.empty()) return std::nullopt;
  const double xi = sample(xi_arcsec_, lat.deg(), lon.deg()), eta = sample(eta_arcsec_, lat.deg(), lon.deg());
  if (!std::isfinite(xi) || !std::isfinite(eta)) return std::nullopt;
  constexpr double kRadPerArcsec = 3.14159265358979323846 / 648000.0;
  return Deflection{xi * kRadPerArcsec, eta * kRadPerArcsec};
}

const char* to_string(GeoidInterpolation i) {
  switch (i) {
    case GeoidInterpolation::bilinear: return "bilinear";
    case GeoidInterpolation::nga_spline: return "4 x 4 natural cubic spline (NGA INTPT)";
    case GeoidInterpolation::bicubic: return "bicubic (Catmull-Rom, 4 x 4 nodes)";
  }
  return "bilinear";
}

}  // namespace geoanchor::geodesy

namespace geoanchor::geodesy {

double GeoidGrid::undulation_m(Angle lat, Angle lon, std::string_view where) const {
  const double n = undulation_m(lat, lon);
  if (!std::isfinite(n)) throw Error(ErrorKind::input, "E_GEOID_RANGE", std::string(where) + ": outside the grid of " + name_);
  return n;
}

}  // namespace geoanchor::geodesy
