// A geoid grid in NTv2 form, as AUSGeoid is distributed (geoid.hpp).
//
// NTv2 (Natural Resources Canada's "NTv2 Developer's Guide", 1997): an
// overview header of NUM_OREC 16-byte records (an 8-character name, then an
// 8-byte value: int32 plus padding, float64 or 8 characters), then per
// sub-grid NUM_SREC such records and GS_COUNT nodes of four float32. A
// sub-grid's limits and spacing are arc-seconds with longitudes positive
// west; its nodes run from the south row up, each row from E_LONG westward.
// AUSGeoid keeps N (m), ξ (″) and η (″) in the first three fields of each
// node (Geoscience Australia's AUSGeoid files; DynAdjust's dnageoid writes
// and reads that layout) and names the height datum in SYSTEM_T.

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/geoid.hpp"

namespace geoanchor::geodesy {
namespace {

constexpr std::size_t kRecord = 16;  // one header record: 8-byte name, 8-byte value
constexpr std::size_t kNode = 16;    // one node: four float32

// The file's byte order: NUM_OREC's count (11 in NTv2.0 files) read either way.
struct Bytes {
  const std::vector<unsigned char>& b;
  bool swap = false;
  template <class T>
  T get(std::size_t at) const {
    unsigned char t[sizeof(T)];
    for (std::size_t i = 0; i < sizeof(T); ++i) t[i] = b[at + (swap ? sizeof(T) - 1 - i : i)];
    T v;
    std::memcpy(&v, t, sizeof(T));
    return v;
  }
  std::string name(std::size_t at) const { return std::string(reinterpret_cast<const char*>(&b[at]), 8); }
  std::string text(std::size_t at) const {
    std::string s(reinterpret_cast<const char*>(&b[at + 8]), 8);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
    return s;
  }
};

bool host_little() { return std::endian::native == std::endian::little; }

}  // namespace

bool GeoidGrid::looks_like_ntv2(std::string_view bytes) { return bytes.substr(0, 8) == "NUM_OREC"; }

GeoidGrid GeoidGrid::load_ntv2(const std::filesystem::path& path, GeoidInterpolation interpolation) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw Error(ErrorKind::io, "E_READ", file + ": cannot open geoid grid");
  const auto size = static_cast<std::size_t>(in.tellg());
  in.seekg(0);
  std::vector<unsigned char> raw(size);
  if (!in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(size))) {
    throw Error(ErrorKind::io, "E_READ", file + ": read failed");
  }
  const auto fail = [&](const std::string& why) -> Error {
    return Error(ErrorKind::input, "E_GEOID", file + ": not read as an NTv2 geoid grid: " + why);
  };
  if (size < 11 * kRecord || std::string_view(reinterpret_cast<const char*>(raw.data()), 8) != "NUM_OREC") {
    throw fail("no NTv2 overview header (NUM_OREC) at its start");
  }
  // The byte order: NUM_OREC's count read as little-endian is small in a
  // little-endian file.
  const std::uint32_t orec_le = static_cast<std::uint32_t>(raw[8]) | static_cast<std::uint32_t>(raw[9]) << 8 |
                                static_cast<std::uint32_t>(raw[10]) << 16 | static_cast<std::uint32_t>(raw[11]) << 24;
  const bool file_little = orec_le > 0 && orec_le < 100;
  Bytes b{raw, file_little != host_little()};
  const std::int32_t orec = b.get<std::int32_t>(8);
  if (orec < 11 || orec > 100) throw fail("NUM_OREC " + std::to_string(orec) + " in neither byte order; expected 11");
  std::int32_t srec = 0, files = 0;
  std::string gs_type, system_f, system_t;
  for (std::int32_t r = 0; r < orec; ++r) {
    const std::size_t at = static_cast<std::size_t>(r) * kRecord;
    if (at + kRecord > size) throw fail("the file ends inside its overview header");
    const std::string name = b.name(at);
    if (name == "NUM_SREC") srec = b.get<std::int32_t>(at + 8);
    if (name == "NUM_FILE") files = b.get<std::int32_t>(at + 8);
    if (name == "GS_TYPE ") gs_type = b.text(at);
    if (name == "SYSTEM_F") system_f = b.text(at);
    if (name == "SYSTEM_T") system_t = b.text(at);
  }
  if (files != 1) {
    throw fail("NUM_FILE " + std::to_string(files) + ": geoanchor reads a geoid grid of one sub-grid (AUSGeoid's form)");
  }
  if (gs_type != "SECONDS") throw fail("GS_TYPE '" + gs_type + "': expected SECONDS (AUSGeoid's deflections in arc-seconds)");
  // A geoid grid names its height datum as the system it leads to; a
  // horizontal shift grid (NTF -> RGF93, CH1903 -> CH1903+) names a datum.
  if (system_t.rfind("AHD", 0) != 0 && system_t.rfind("AUSHT", 0) != 0) {
    throw fail("SYSTEM_F '" + system_f + "' -> SYSTEM_T '" + system_t +
               "' is a horizontal shift grid; an NTv2 geoid grid (AUSGeoid) names its height datum in SYSTEM_T (AHD_1971)");
  }
  const std::size_t sub = static_cast<std::size_t>(orec) * kRecord;
  if (srec < 11 || srec > 100 || sub + static_cast<std::size_t>(srec) * kRecord > size) throw fail("its sub-grid header is cut short");
  double s_lat = NAN, n_lat = NAN, e_long = NAN, w_long = NAN, lat_inc = NAN, long_inc = NAN;
  std::int32_t count = -1;
  for (std::int32_t r = 0; r < srec; ++r) {
    const std::size_t at = sub + static_cast<std::size_t>(r) * kRecord;
    const std::string name = b.name(at);
    if (name == "S_LAT   ") s_lat = b.get<double>(at + 8);
    if (name == "N_LAT   ") n_lat = b.get<double>(at + 8);
    if (name == "E_LONG  ") e_long = b.get<double>(at + 8);
    if (name == "W_LONG  ") w_long = b.get<double>(at + 8);
    if (name == "LAT_INC ") lat_inc = b.get<double>(at + 8);
    if (name == "LONG_INC") long_inc = b.get<double>(at + 8);
    if (name == "GS_COUNT") count = b.get<std::int32_t>(at + 8);
  }
  if (!(lat_inc > 0 && long_inc > 0) || !(n_lat > s_lat) || !(w_long > e_long) || !(std::abs(s_lat) <= 324000.0) ||
      !(std::abs(n_lat) <= 324000.0)) {
    throw fail("sub-grid limits S_LAT " + format_shortest(s_lat) + ", N_LAT " + format_shortest(n_lat) + ", E_LONG " +
               format_shortest(e_long) + ", W_LONG " + format_shortest(w_long) + " and spacing " + format_shortest(lat_inc) +
               "\", " + format_shortest(long_inc) + "\" describe no grid");
  }
  const double rows_f = std::round((n_lat - s_lat) / lat_inc) + 1.0, cols_f = std::round((w_long - e_long) / long_inc) + 1.0;
  if (rows_f < 2 || cols_f < 2 || rows_f * cols_f > 1e9 || rows_f * cols_f != static_cast<double>(count)) {
    throw fail("GS_COUNT " + std::to_string(count) + " but the limits and spacing give " + format_shortest(rows_f) + " x " +
               format_shortest(cols_f) + " nodes");
  }
  const auto rows = static_cast<std::int32_t>(rows_f), cols = static_cast<std::int32_t>(cols_f);
  const std::size_t nodes_at = sub + static_cast<std::size_t>(srec) * kRecord;
  const std::size_t n = static_cast<std::size_t>(count);
  if (nodes_at + n * kNode > size) {
    throw fail(std::to_string(size) + " bytes; its " + std::to_string(n) + " nodes need " + std::to_string(nodes_at + n * kNode));
  }
  GeoidGrid g;
  g.name_ = path.filename().string() + " (NTv2 geoid grid, " + system_f + " -> " + system_t + ", " + to_string(interpolation) + ")";
  g.path_ = path;
  g.interpolation_ = interpolation;
  g.rows_ = rows;
  g.cols_ = cols;
  g.lat0_deg_ = s_lat / 3600.0;
  g.dlat_deg_ = lat_inc / 3600.0;
  g.lon0_deg_ = -w_long / 3600.0;  // the west edge, east positive
  g.dlon_deg_ = long_inc / 3600.0;
  g.values_m_.resize(n);
  g.xi_arcsec_.resize(n);
  g.eta_arcsec_.resize(n);
  for (std::int32_t r = 0; r < rows; ++r) {
    for (std::int32_t k = 0; k < cols; ++k) {
      // Record k of row r lies k spacings west of E_LONG: column cols − 1 − k west to east.
      const std::size_t rec = nodes_at + (static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(k)) * kNode;
      const std::size_t cell = static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(cols - 1 - k);
      const float nv = b.get<float>(rec), xi = b.get<float>(rec + 4), eta = b.get<float>(rec + 8);
      if (!std::isfinite(nv) || !std::isfinite(xi) || !std::isfinite(eta) || std::abs(nv) > 200.0f || std::abs(xi) > 300.0f ||
          std::abs(eta) > 300.0f) {
        throw fail("node " + std::to_string(r * cols + k + 1) + " holds N " + format_shortest(nv) + " m, xi " + format_shortest(xi) +
                   "\", eta " + format_shortest(eta) + "\": expected |N| <= 200 m and deflections within 300\"");
      }
      g.values_m_[cell] = nv;
      g.xi_arcsec_[cell] = xi;
      g.eta_arcsec_[cell] = eta;
    }
  }
  return g;
}

}  // namespace geoanchor::geodesy
