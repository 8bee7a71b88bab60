#include "geoanchor/geodesy/geoid.hpp"

#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>

#include "geoanchor/geodesy/error.hpp"

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

double GeoidGrid::undulation_m(Angle lat, Angle lon) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double y = (lat.deg() - lat0_deg_) / dlat_deg_;
  double x = (lon.deg() - lon0_deg_) / dlon_deg_;
  if (!std::isfinite(x) || !std::isfinite(y)) return nan;
  if (global_lon_) x = std::fmod(std::fmod(x, cols_) + cols_, cols_);
  if (y < 0 || y > rows_ - 1) return nan;
  const auto r0 = static_cast<std::int32_t>(std::floor(y));
  const auto c0 = static_cast<std::int32_t>(std::floor(x));
  const std::int32_t r1 = std::min(r0 + 1, rows_ - 1);
  std::int32_t c1 = c0 + 1;
  if (c1 >= cols_) {
    if (!global_lon_) {
      if (x > cols_ - 1) return nan;
      c1 = cols_ - 1;
    } else {
      c1 = 0;
    }
  }
  if (c0 < 0) return nan;
  const double fy = y - r0, fx = x - c0;
  const auto at = [&](std::int32_t r, std::int32_t c) {
    return static_cast<double>(values_m_[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(c)]);
  };
  return (1 - fy) * ((1 - fx) * at(r0, c0) + fx * at(r0, c1)) + fy * ((1 - fx) * at(r1, c0) + fx * at(r1, c1));
}

}  // namespace geoanchor::geodesy

namespace geoanchor::geodesy {

double GeoidGrid::undulation_m(Angle lat, Angle lon, std::string_view where) const {
  const double n = undulation_m(lat, lon);
  if (!std::isfinite(n)) throw Error(ErrorKind::input, "E_GEOID_RANGE", std::string(where) + ": outside the grid of " + name_);
  return n;
}

}  // namespace geoanchor::geodesy
