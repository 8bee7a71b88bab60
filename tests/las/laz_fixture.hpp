#pragma once
// What the LAZ tests share (laz_test.cpp, laz_malformed_test.cpp): the
// Laszip-written files and their uncompressed twins, the LazTest fixture.
// Test-only: one definition for every test file that includes it (inline).

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <sstream>
#include <thread>
#include <tuple>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/las/laz.hpp"
#include "laz_support.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace laz_fixture {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;
using nlohmann::json;

const fs::path kData = GEOANCHOR_LAZ_DATA_DIR;
using testing::base_size;
using testing::Content;
using testing::content_name;
using testing::laz_perf;
using testing::LazPerfRead;
using testing::make_records;
using testing::SameRecords;

inline Bytes slurp(const fs::path& p) { return testing::slurp_bytes(p); }
inline void write_file(const fs::path& p, const Bytes& b) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(b.data()),
                                                             static_cast<std::streamsize>(b.size()));
}
template <class T>
inline T get(const Bytes& b, std::size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
template <class T>
inline void put(Bytes& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

// Every record through read_records, in batches of an odd size that cuts
// across chunks.
inline Bytes records_of(LasReader& r) {
  Bytes all, batch;
  r.rewind();
  while (r.read_records(batch, 777) != 0) all.insert(all.end(), batch.begin(), batch.end());
  return all;
}

class LazTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_.emplace("geoanchor_laz");
    dir_ = folder_->path();
  }
  fs::path path(const std::string& name) const { return dir_ / name; }
  std::optional<testing::TempFolder> folder_;
  fs::path dir_;
};

// ---------------------------------------------------------------------------
// Files written by the LASzip library: their records are their twins'.

struct Twin {
  const char* laz;
  const char* las;
};
constexpr Twin kTwins[] = {
    {"point10.las.laz", "point10.las"},           {"point-time.las.laz", "point-time.las"},
    {"point-color.las.laz", "point-color.las"},   {"point-color-time.las.laz", "point-color-time.las"},
    {"point-time-1.4.las.laz", "point-time.las"}, {"1815.laz", "1815.las"},
    {"extrabytes.laz", "extrabytes.las"},         {"no-points-1.3.laz", "no-points-1.3.las"},
};
inline const char* kWkt =
    "PROJCRS[\"ETRS89 / UTM zone 32N\",BASEGEOGCRS[\"ETRS89\",DATUM[\"European Terrestrial Reference System "
    "1989\",ELLIPSOID[\"GRS 1980\",6378137,298.257222101]]],CONVERSION[\"UTM zone 32N\",METHOD[\"Transverse "
    "Mercator\"],PARAMETER[\"Latitude of natural origin\",0],PARAMETER[\"Longitude of natural origin\",9],"
    "PARAMETER[\"Scale factor at natural origin\",0.9996],PARAMETER[\"False easting\",500000],PARAMETER[\"False "
    "northing\",0]],CS[Cartesian,2],AXIS[\"easting\",east],AXIS[\"northing\",north],LENGTHUNIT[\"metre\",1],"
    "ID[\"EPSG\",25832]]";
struct Written {
  LasHeader header;
  std::array<double, 3> min{}, max{};
};

// Writes `records` as a LAZ (or LAS) file with a WKT VLR; returns the header
// given and the bounds passed to finish().
inline Written write_tile(const fs::path& p, std::uint8_t format, std::size_t extra, const Bytes& records, bool laz,
                   std::uint32_t chunk_points, std::size_t batch = 4321) {
  Written w;
  LasHeader& h = w.header;
  h.point_format = format;
  h.record_length = static_cast<std::uint16_t>(base_size(format) + extra);
  h.global_encoding = LasHeader::kWktBit | 1u;
  h.scale = {0.001, 0.001, 0.001};
  h.offset = {0.0, 0.0, 0.0};
  const std::size_t n = records.size() / h.record_length;
  std::array<std::uint64_t, 15> by_return{};
  w.min = {INFINITY, INFINITY, INFINITY};
  w.max = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* rec = records.data() + i * h.record_length;
    for (std::size_t k = 0; k < 3; ++k) {
      std::int32_t q;
      std::memcpy(&q, rec + 4 * k, 4);
      const double v = q * h.scale[k] + h.offset[k];
      w.min[k] = std::min(w.min[k], v);
      w.max[k] = std::max(w.max[k], v);
    }
    const unsigned r = format < 6 ? (rec[14] & 7u) : (rec[14] & 15u);
    if (r >= 1 && r <= 15) ++by_return[r - 1];
  }
  if (n == 0) w.min = w.max = {0, 0, 0};
  LasVlr wkt;
  wkt.user_id = "LASF_Projection";
  wkt.record_id = kLasWktRecordId;
  wkt.description = "WKT";
  wkt.data.assign(kWkt, kWkt + std::strlen(kWkt) + 1);
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  LasWriter writer(f, h, {wkt}, {}, p.string(), {laz, chunk_points});
  for (std::size_t i = 0; i < n; i += batch) {
    writer.write_records(records.data() + i * h.record_length, std::min(batch, n - i));
  }
  writer.finish(by_return, w.min, w.max);
  return w;
}




}  // namespace laz_fixture
}  // namespace geoanchor::io
