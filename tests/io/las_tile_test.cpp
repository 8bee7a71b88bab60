// LAS files: the reader against files assembled from the specification's
// tables (tests/support/las_builder.hpp), tiles through a chain against
// PROJ, pass-through of every attribute byte, and each malformed-file case.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <optional>
#include <random>

#include "geoanchor/base/error.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "las_builder.hpp"
#include "proj_reference.hpp"
#include "temp_folder.hpp"
#include "test_support.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
using geodesy::Angle;
using testing::build_las;
using testing::LasBuild;
using testing::ProjPipeline;
using testing::write_bytes;

constexpr double kVsProjTol_m = 1e-6;           // issue acceptance, beyond half the quantization step
constexpr double kMetresPerDegree = 111319.49;  // only to express kVsProjTol_m in degrees
constexpr double kRoundTripTol_m = 1e-9;        // identity chain: decoded values re-quantized on the same grid
constexpr double kDecodeTol_m = 1e-12;          // integer × scale + offset, as the reader decodes it

const char* kHelmert = R"J({"model": "helmert7", "convention": "position_vector",
  "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
  "parameters": {"tx_m": 0.0547, "ty_m": 0.0522, "tz_m": -0.0741, "rx_arcsec": 0.00228, "ry_arcsec": 0.01404,
                 "rz_arcsec": -0.02168, "ds_ppm": 0.00212}})J";
const char* kProjHelmert =
    "+proj=helmert +x=0.0547 +y=0.0522 +z=-0.0741 +rx=0.00228 +ry=0.01404 +rz=-0.02168 +s=0.00212 "
    "+convention=position_vector";

geodesy::LocalOrigin origin(double lat, double lon, double h) {
  return {{Angle::degrees(lat), Angle::degrees(lon), geodesy::EllipsoidalHeight{h}}, geodesy::Ellipsoid::grs80()};
}
const geodesy::LocalOrigin kArpA = origin(47.464722, 8.549167, 480.0);
const geodesy::LocalOrigin kArpB = origin(47.2597, 11.3439, 581.0);  // a second airport, 210 km away

std::string topocentric(const geodesy::LocalOrigin& o) {
  char def[200];
  std::snprintf(def, sizeof def, "+proj=topocentric +ellps=GRS80 +lat_0=%.17g +lon_0=%.17g +h_0=%.17g",
                o.point.lat.deg(), o.point.lon.deg(), o.point.h.m);
  return def;
}

ArrayFrame enu_frame(const geodesy::LocalOrigin& o) {
  return ArrayFrame{CoordinateKind::enu, geodesy::Ellipsoid::grs80(), o, std::nullopt};
}

class LasTileTest : public ::testing::Test {
 protected:
  // issue 12, tests that can fail, item 6: a folder of the test's own
  // (mkdtemp; a fixed name per test was shared by two runs of the suite),
  // removed unless the test failed.
  void SetUp() override {
    folder_.emplace("geoanchor_las");
    dir_ = folder_->path();
  }
  fs::path write(const std::string& name, const LasBuild& b) const {
    write_bytes(dir_ / name, build_las(b));
    return dir_ / name;
  }
  // Runs a tile through `chain` into `name`; returns the result.
  TileApplyResult apply(const fs::path& in, const std::string& name, const PointChain& chain, const TileApplyOptions& o) {
    std::ofstream out(dir_ / name, std::ios::binary);
    const auto r = apply_las_tile(in, out, name, chain, o);
    out.close();
    return r;
  }
  // Every record of a LAS file, and its decoded coordinates.
  static std::vector<std::array<double, 3>> decode(const fs::path& p, std::vector<std::uint8_t>* records = nullptr) {
    LasReader r(p);
    std::vector<std::uint8_t> buf;
    std::vector<std::array<double, 3>> xyz;
    const auto& h = r.header();
    while (const std::size_t n = r.read_records(buf, 4096)) {
      for (std::size_t i = 0; i < n; ++i) {
        std::int32_t q[3];
        std::memcpy(q, &buf[i * h.record_length], 12);
        xyz.push_back({q[0] * h.scale[0] + h.offset[0], q[1] * h.scale[1] + h.offset[1], q[2] * h.scale[2] + h.offset[2]});
      }
      if (records) records->insert(records->end(), buf.begin(), buf.end());
    }
    return xyz;
  }
  std::optional<testing::TempFolder> folder_;
  fs::path dir_;
};

LasBuild random_enu_tile(std::size_t n, std::uint8_t format, double half_width_m, unsigned seed) {
  LasBuild b;
  b.point_format = format;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> h(-half_width_m, half_width_m), v(-30.0, 80.0);
  for (std::size_t i = 0; i < n; ++i) {
    b.xyz.push_back({static_cast<std::int32_t>(std::lround(h(rng) / b.scale[0])),
                     static_cast<std::int32_t>(std::lround(h(rng) / b.scale[1])),
                     static_cast<std::int32_t>(std::lround(v(rng) / b.scale[2]))});
  }
  return b;
}

TEST_F(LasTileTest, ReaderReadsEveryVersionAndPointFormat) {
  for (const std::uint8_t minor : std::vector<std::uint8_t>{2, 3, 4}) {
    for (const std::uint8_t format : std::vector<std::uint8_t>{0, 1, 2, 3, 6, 7, 8}) {
      if (format >= 6 && minor < 4) continue;
      LasBuild b = random_enu_tile(7, format, 100.0, format);
      b.minor = minor;
      b.extra_bytes = 5;
      b.vlrs.push_back({"LASF_Spec", 4, "extra bytes", std::vector<std::uint8_t>(192, 0)});
      const auto p = write("t.las", b);
      LasReader r(p);
      SCOPED_TRACE("LAS 1." + std::to_string(minor) + " format " + std::to_string(format));
      EXPECT_EQ(r.header().point_count, 7u);
      EXPECT_EQ(r.header().point_format, format);
      EXPECT_EQ(r.header().record_length, testing::las_format_size(format) + 5);
      ASSERT_EQ(r.vlrs().size(), 1u);
      EXPECT_EQ(r.vlrs()[0].user_id, "LASF_Spec");
      EXPECT_EQ(r.vlrs()[0].record_id, 4);
      std::vector<std::uint8_t> records;
      const auto xyz = decode(p, &records);
      const auto bytes = build_las(b);
      const std::size_t start = bytes.size() - records.size();
      EXPECT_TRUE(std::equal(records.begin(), records.end(), bytes.begin() + static_cast<std::ptrdiff_t>(start)));
      EXPECT_NEAR(xyz[3][0], b.xyz[3][0] * 0.001, kDecodeTol_m);
    }
  }
}

TEST_F(LasTileTest, IdentityChainKeepsEveryAttributeByteAndTheVlrsAndRewritesTheHeader) {
  LasBuild b = random_enu_tile(1000, 7, 500.0, 1);
  b.extra_bytes = 4;
  b.vlrs.push_back({"LASF_Projection", 34735, "GeoKeyDirectoryTag", std::vector<std::uint8_t>(16, 1)});
  b.vlrs.push_back({"LASF_Spec", 4, "extra bytes", std::vector<std::uint8_t>(192, 2)});
  b.evlrs.push_back({"LASF_Projection", 2112, "old WKT", {'X', 0}});
  b.evlrs.push_back({"geoanchor_test", 7, "kept", std::vector<std::uint8_t>(70000, 9)});
  const auto in = write("in.las", b);
  const PointChain chain(enu_frame(kArpA), std::nullopt, false, std::nullopt, enu_frame(kArpA));
  TileApplyOptions o{enu_frame(kArpA), enu_frame(kArpA), std::nullopt, "WKT-PLACEHOLDER", 64, {}};
  const auto r = apply(in, "out.las", chain, o);
  EXPECT_EQ(r.points, 1000u);

  std::vector<std::uint8_t> a, c;
  const auto xin = decode(in, &a), xout = decode(dir_ / "out.las", &c);
  ASSERT_EQ(a.size(), c.size());
  const std::size_t len = testing::las_format_size(7) + 4;
  for (std::size_t i = 0; i < 1000; ++i) {
    for (std::size_t k = 0; k < 3; ++k) ASSERT_NEAR(xin[i][k], xout[i][k], kRoundTripTol_m) << "point " << i;
    ASSERT_TRUE(std::equal(a.begin() + static_cast<std::ptrdiff_t>(i * len + 12), a.begin() + static_cast<std::ptrdiff_t>((i + 1) * len),
                           c.begin() + static_cast<std::ptrdiff_t>(i * len + 12)))
        << "attribute bytes of point " << i;
  }
  LasReader out(dir_ / "out.las");
  const LasHeader& h = out.header();
  EXPECT_EQ(h.version_minor, 4);
  EXPECT_TRUE(h.wkt_bit());
  EXPECT_EQ(h.point_count, 1000u);
  EXPECT_EQ(h.points_by_return[0], 1000u);
  for (std::size_t k = 0; k < 3; ++k) {
    double lo = 1e300, hi = -1e300;
    for (const auto& p : xout) lo = std::min(lo, p[k]), hi = std::max(hi, p[k]);
    EXPECT_DOUBLE_EQ(h.min[k], lo);
    EXPECT_DOUBLE_EQ(h.max[k], hi);
  }
  // The new WKT replaces both old CRS records; everything else is kept.
  std::vector<std::string> kinds;
  for (const auto& v : out.vlrs()) kinds.push_back(v.user_id + "/" + std::to_string(v.record_id) + (v.extended ? "/E" : ""));
  EXPECT_EQ(kinds, (std::vector<std::string>{"LASF_Projection/2112", "LASF_Spec/4", "geoanchor_test/7/E"}));
  EXPECT_EQ(out.wkt(), "WKT-PLACEHOLDER");
  EXPECT_EQ(out.vlrs()[2].data.size(), 70000u);
}

struct ChainCase {
  const char* name;
  ArrayFrame to;
  std::string proj_tail;  // PROJ steps from ECEF (after the Helmert) to the output
  bool geodetic = false;
};

TEST_F(LasTileTest, EveryOutputKindAgreesWithProjToHalfTheQuantizationStep) {
  const std::size_t n = 100000;
  const auto in = write("in.las", random_enu_tile(n, 6, 2000.0, 2));
  const TransformFile t = parse_transform_json(kHelmert, "T.json");
  ArrayFrame ecef{CoordinateKind::ecef, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  ArrayFrame geodetic{CoordinateKind::geodetic, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  ArrayFrame utm{CoordinateKind::projected, geodesy::Ellipsoid::grs80(), std::nullopt,
                 geodesy::utm_projection(geodesy::Ellipsoid::grs80(), geodesy::UtmZone{32, geodesy::Hemisphere::north})};
  geodesy::TransverseMercatorParams tmp{Angle::degrees(47.0), Angle::degrees(8.5), 1.0, 600000.0, 200000.0};
  ArrayFrame tm{CoordinateKind::projected, geodesy::Ellipsoid::grs80(), std::nullopt,
                geodesy::ProjectionDef{geodesy::Ellipsoid::grs80(), tmp, std::nullopt}};
  const std::vector<ChainCase> cases = {
      {"ENU(A) -> Helmert -> ENU(B)", enu_frame(kArpB), "+step " + topocentric(kArpB)},
      {"ENU(A) -> Helmert -> ECEF", ecef, ""},
      {"ENU(A) -> Helmert -> geodetic", geodetic, "+step +inv +proj=cart +ellps=GRS80", true},
      {"ENU(A) -> Helmert -> UTM 32N", utm, "+step +inv +proj=cart +ellps=GRS80 +step +proj=utm +zone=32 +ellps=GRS80"},
      {"ENU(A) -> Helmert -> TM", tm,
       "+step +inv +proj=cart +ellps=GRS80 +step +proj=tmerc +lat_0=47 +lon_0=8.5 +k_0=1 +x_0=600000 +y_0=200000 "
       "+ellps=GRS80"},
  };
  const auto xin = decode(in);
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const PointChain chain(enu_frame(kArpA), t, false, std::nullopt, c.to);
    const TileApplyOptions o{enu_frame(kArpA), c.to, std::nullopt, "WKT", 1 << 14, {}};
    const auto r = apply(in, "out.las", chain, o);
    const auto xout = decode(dir_ / "out.las");
    ASSERT_EQ(xout.size(), n);
    const ProjPipeline proj("+proj=pipeline +step +inv " + topocentric(kArpA).substr(0) + " +step " + kProjHelmert + " " +
                            c.proj_tail);
    std::array<testing::WorstCase, 3> worst;
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector3d e = proj.forward(Eigen::Vector3d(xin[i][0], xin[i][1], xin[i][2]));
      if (c.geodetic) e = Eigen::Vector3d(testing::proj_degrees(e.x()), testing::proj_degrees(e.y()), e.z());  // lon, lat
      for (std::size_t k = 0; k < 3; ++k) {
        const bool degrees = c.geodetic && k < 2;
        const double tol = 0.5 * r.scale[k] + (degrees ? kVsProjTol_m / kMetresPerDegree : kVsProjTol_m);
        worst[k].add(std::abs(xout[i][k] - e(static_cast<Eigen::Index>(k))) / tol, i);
      }
    }
    for (std::size_t k = 0; k < 3; ++k) EXPECT_WORST_WITHIN(worst[k], 1.0) << "axis " << k << " (1 = half a step + 1 µm)";
    ::testing::Test::RecordProperty(
        std::string("worst_fraction_of_half_step_plus_1um ") + c.name,
        testing::scientific(testing::nan_max(worst[0].value(), testing::nan_max(worst[1].value(), worst[2].value()))));
  }
}

TEST_F(LasTileTest, EveryInputKindAgreesWithProjToHalfTheQuantizationStep) {
  // The same 10^5 points as ECEF, geodetic, UTM and TM tiles (made by PROJ
  // from ENU at A), each through the Helmert into ENU at B.
  const std::size_t n = 100000;
  const auto enu_points = decode(write("enu.las", random_enu_tile(n, 6, 2000.0, 3)));
  const TransformFile t = parse_transform_json(kHelmert, "T.json");
  const std::string cart = "+step +proj=cart +ellps=GRS80";
  struct InCase {
    const char* name;
    ArrayFrame from;
    std::string to_kind;    // PROJ steps from ECEF to this kind
    std::string from_kind;  // PROJ steps from this kind to ECEF
    bool geodetic = false;
    std::array<double, 3> scale{0.001, 0.001, 0.001};
  };
  geodesy::TransverseMercatorParams tmp{Angle::degrees(47.0), Angle::degrees(8.5), 1.0, 600000.0, 200000.0};
  const std::string tm = "+proj=tmerc +lat_0=47 +lon_0=8.5 +k_0=1 +x_0=600000 +y_0=200000 +ellps=GRS80";
  const std::vector<InCase> cases = {
      {"ECEF", {CoordinateKind::ecef, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt}, "", ""},
      {"geodetic", {CoordinateKind::geodetic, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt},
       "+step +inv +proj=cart +ellps=GRS80", cart, true, {1e-9, 1e-9, 0.001}},
      {"UTM 32N",
       {CoordinateKind::projected, geodesy::Ellipsoid::grs80(), std::nullopt,
        geodesy::utm_projection(geodesy::Ellipsoid::grs80(), geodesy::UtmZone{32, geodesy::Hemisphere::north})},
       "+step +inv +proj=cart +ellps=GRS80 +step +proj=utm +zone=32 +ellps=GRS80",
       "+step +inv +proj=utm +zone=32 +ellps=GRS80 " + cart},
      {"TM",
       {CoordinateKind::projected, geodesy::Ellipsoid::grs80(), std::nullopt,
        geodesy::ProjectionDef{geodesy::Ellipsoid::grs80(), tmp, std::nullopt}},
       "+step +inv +proj=cart +ellps=GRS80 +step +proj=" + tm.substr(6), "+step +inv +proj=" + tm.substr(6) + " " + cart},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    // The tile, quantized at its own resolution around its middle.
    const ProjPipeline make("+proj=pipeline +step +inv " + topocentric(kArpA) + " " + c.to_kind);
    std::vector<std::array<double, 3>> v(n);
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector3d q = make.forward(Eigen::Vector3d(enu_points[i][0], enu_points[i][1], enu_points[i][2]));
      if (c.geodetic) q = Eigen::Vector3d(testing::proj_degrees(q.x()), testing::proj_degrees(q.y()), q.z());  // lon, lat
      v[i] = {q.x(), q.y(), q.z()};
    }
    LasBuild b;
    b.scale = c.scale;
    for (std::size_t k = 0; k < 3; ++k) b.offset[k] = std::round(v[n / 2][k]);
    for (const auto& p : v) {
      b.xyz.push_back({static_cast<std::int32_t>(std::lround((p[0] - b.offset[0]) / b.scale[0])),
                       static_cast<std::int32_t>(std::lround((p[1] - b.offset[1]) / b.scale[1])),
                       static_cast<std::int32_t>(std::lround((p[2] - b.offset[2]) / b.scale[2]))});
    }
    const auto in = write("in.las", b);
    const PointChain chain(c.from, t, false, std::nullopt, enu_frame(kArpB));
    const auto r = apply(in, "out.las", chain, TileApplyOptions{c.from, enu_frame(kArpB), std::nullopt, "WKT", 1 << 14, {}});
    const auto xin = decode(in), xout = decode(dir_ / "out.las");
    ASSERT_EQ(xout.size(), n);
    const ProjPipeline proj("+proj=pipeline " + c.from_kind + " +step " + kProjHelmert + " +step " + topocentric(kArpB));
    testing::WorstCase worst;
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Vector3d x(xin[i][0], xin[i][1], xin[i][2]);
      if (c.geodetic) x = Eigen::Vector3d(testing::proj_radians(x.x()), testing::proj_radians(x.y()), x.z());
      const Eigen::Vector3d e = proj.forward(x);
      for (std::size_t k = 0; k < 3; ++k) {
        worst.add(std::abs(xout[i][k] - e(static_cast<Eigen::Index>(k))) / (0.5 * r.scale[k] + kVsProjTol_m), i);
      }
    }
    EXPECT_WORST_WITHIN(worst, 1.0) << "(1 = half a step + 1 µm)";
  }
}

TEST_F(LasTileTest, WrongHeaderBoundsAreRecoveredAndATrueOverflowIsAnErrorNotAClamp) {
  // Points 3000 km apart along east: at 1 mm the output spans more than
  // int32 unless the offset sits in the middle, which the (wrong) header
  // bounds do not give.
  LasBuild b;
  b.offset = {1500000.0, 0.0, 0.0};
  b.xyz = {{-1500000000, 0, 0}, {1500000000, 0, 0}, {0, 0, 0}};
  b.stated_bounds = std::array<double, 6>{0, 0, 0, 1, 1, 1};
  const auto in = write("in.las", b);
  ArrayFrame ecef{CoordinateKind::ecef, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  const PointChain chain(enu_frame(kArpA), std::nullopt, false, std::nullopt, ecef);
  const auto r = apply(in, "out.las", chain, TileApplyOptions{enu_frame(kArpA), ecef, std::nullopt, "WKT", 64, {}});
  const auto xout = decode(dir_ / "out.las");
  const ProjPipeline to_ecef("+proj=pipeline +step +inv " + topocentric(kArpA));
  // The offset came from the true bounds, not from the header's.
  const Eigen::Vector3d arp = to_ecef.forward(Eigen::Vector3d::Zero());
  EXPECT_GT(std::abs(r.offset[1] - arp.y()), 1.0e6) << "the header's bounds were used";
  for (std::size_t i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = to_ecef.forward(Eigen::Vector3d(b.xyz[i][0] * 0.001 + 1500000.0, 0, 0));
    for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(xout[i][k], e(static_cast<Eigen::Index>(k)), 0.5 * r.scale[k] + kVsProjTol_m);
  }
  // 5000 km at 1 mm cannot be stored.
  LasBuild wide;
  wide.scale = {0.01, 0.01, 0.01};
  wide.offset = {2500000.0, 0.0, 0.0};
  wide.xyz = {{-250000000, 0, 0}, {250000000, 0, 0}};
  const auto in2 = write("wide.las", wide);
  try {
    apply(in2, "wide_out.las", chain, TileApplyOptions{enu_frame(kArpA), ecef, 0.001, "WKT", 64, {}});
    ADD_FAILURE() << "expected an int32 overflow error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_INT32_OVERFLOW");
    EXPECT_NE(std::string(e.what()).find("does not fit a 32-bit integer"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("never clamped"), std::string::npos) << e.what();
  }
}

struct BadLas {
  const char* name;
  std::function<std::vector<std::uint8_t>()> bytes;
  const char* message;
};

TEST_F(LasTileTest, MalformedFilesNameTheFileAndTheByteOffset) {
  auto good = [] { return random_enu_tile(10, 6, 100.0, 3); };
  const std::vector<BadLas> cases = {
      {"truncated header", [&] { auto v = build_las(good()); v.resize(200); return v; }, "truncated LAS header"},
      {"truncated points", [&] { auto v = build_las(good()); v.resize(v.size() - 7); return v; }, "truncated point data"},
      {"count disagrees with size", [&] { auto v = build_las(good()); v.resize(v.size() + 30, 0); return v; },
       "disagrees with the file size"},
      {"unknown point format", [&] { auto b = good(); b.point_format = 12; return build_las(b); }, "point data record format 12 is unknown"},
      {"waveform format", [&] { auto b = good(); b.point_format = 9; return build_las(b); }, "(waveform) is not supported"},
      {"compressed", [&] { auto b = good(); b.point_format = 6 | 0x80; return build_las(b); }, "compressed (LAZ)"},
      {"VLR past the header", [&] { auto b = good(); b.vlrs.push_back({"a", 1, "", {1, 2}}); b.stated_vlr_count = 2; return build_las(b); },
       "runs past the start of the point data"},
      {"record too short", [&] { auto b = good(); b.stated_record_length = 20; return build_las(b); }, "shorter than format 6"},
      {"LAS 1.1", [&] { auto v = build_las(good()); v[25] = 1; return v; }, "LAS version 1.1 is not supported"},
      {"EVLR past the end", [&] { auto b = good(); b.evlrs.push_back({"a", 1, "", std::vector<std::uint8_t>(100, 0)}); auto v = build_las(b); v.resize(v.size() - 50); return v; },
       "runs past the end of the file"},
      {"not LAS", [&] { std::vector<std::uint8_t> v(400, 'x'); return v; }, "not a LAS file"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path p = dir_ / "bad.las";
    write_bytes(p, c.bytes());
    try {
      LasReader r(p);
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_EQ(e.kind(), ErrorKind::input);
      EXPECT_NE(m.find(p.string() + ": byte "), std::string::npos) << m;
      EXPECT_NE(m.find(c.message), std::string::npos) << m;
    }
  }
}

}  // namespace
}  // namespace geoanchor::io
