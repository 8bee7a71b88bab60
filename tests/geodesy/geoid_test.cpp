// EGM96 undulations from PROJ's egm96_15.gtx, read and interpolated by
// geoanchor, against PROJ's own vgridshift on the same grid; and the grid
// reader's refusals.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "proj_reference.hpp"
#include "temp_folder.hpp"
#include "test_support.hpp"

namespace geoanchor::geodesy {
namespace {

using testing::proj_radians;
using testing::ProjPipeline;

// The bound is 1 mm; both sides interpolate the same float32 grid
// bilinearly in double, so they agree to rounding.
constexpr double kProjAgreement_m = 1e-3;
constexpr double kRounding_m = 1e-6;

TEST(Egm96, AgreesWithProjsVgridshiftOnTheSameGrid) {
  const GeoidGrid& egm96 = GeoidGrid::egm96();
  EXPECT_EQ(egm96.model_name(), "EGM96 (15' grid, egm96_15.gtx)");
  // vgridshift: z_out = z_in + multiplier × N.
  const ProjPipeline vgridshift("+proj=vgridshift +grids=egm96_15.gtx +multiplier=1");
  std::mt19937_64 rng(96);
  std::uniform_real_distribution<double> lat(-89.9, 89.9), lon(-180.0, 180.0);
  testing::WorstCase worst;
  for (int i = 0; i < 5000; ++i) {
    const double la = lat(rng), lo = lon(rng);
    const double n_proj = vgridshift.forward(Eigen::Vector3d(proj_radians(lo), proj_radians(la), 0.0)).z();
    const double n = egm96.undulation_m(Angle::degrees(la), Angle::degrees(lo));
    ASSERT_TRUE(std::isfinite(n)) << la << " " << lo;
    worst.add(std::abs(n - n_proj));
    EXPECT_LT(std::abs(n - n_proj), kProjAgreement_m) << la << " " << lo;
  }
  EXPECT_WORST_WITHIN(worst, kRounding_m);
  // Across the antimeridian and on grid nodes.
  for (double lo : {-180.0, -179.9, 179.9, 180.0, 0.0}) {
    for (double la : {-89.0, 0.0, 47.25, 89.0}) {
      const double n_proj = vgridshift.forward(Eigen::Vector3d(proj_radians(lo), proj_radians(la), 0.0)).z();
      EXPECT_NEAR(egm96.undulation_m(Angle::degrees(la), Angle::degrees(lo)), n_proj, kRounding_m) << la << " " << lo;
    }
  }
}

// NGA's check values for its 15′ grid interpolation (the readme of
// WW15MGH.GRD, "OUTINTPT.DAT": latitude, longitude east, N in metres to the
// millimetre), computed by NGA's INTPT.F.
struct NgaCheckPoint {
  double lat_deg, lon_deg, n_m;
};
constexpr NgaCheckPoint kNgaCheckPoints[] = {
    {38.6281550, 269.7791550, -31.628}, {-14.6212170, 305.0211140, -2.969}, {46.8743190, 102.4487290, -43.575},
    {-23.6174460, 133.8747120, 15.871}, {38.6254730, 359.9995000, 50.066},  {-0.4667440, 0.0023000, 17.329}};
// The bound against published values; NGA prints millimetres.
constexpr double kPublishedAgreement_m = 0.01;
constexpr double kPublishedRounding_m = 0.001;  // measured: 0.6 mm at worst

TEST(Egm96, NgaInterpolationReproducesNgasPublishedCheckValues) {
  const GeoidGrid& nga = GeoidGrid::egm96_nga();
  EXPECT_EQ(nga.interpolation(), GeoidInterpolation::nga_spline);
  EXPECT_NE(nga.model_name(), GeoidGrid::egm96().model_name());
  for (const auto& p : kNgaCheckPoints) {
    const double n = nga.undulation_m(Angle::degrees(p.lat_deg), Angle::degrees(p.lon_deg));
    EXPECT_NEAR(n, p.n_m, kPublishedAgreement_m) << p.lat_deg << " " << p.lon_deg;
    EXPECT_NEAR(n, p.n_m, kPublishedRounding_m) << p.lat_deg << " " << p.lon_deg;
  }
}

TEST(Egm96, BilinearAsProjDiffersFromNgasValuesByCentimetres) {
  // What docs/frames.md states: PROJ's bilinear interpolation of the same
  // grid is within 6 cm of NGA's values at its check points, not within 1 cm.
  constexpr double kBilinearVsNgaBound_m = 0.06;
  const GeoidGrid& bilinear = GeoidGrid::egm96();
  testing::WorstCase worst;
  for (const auto& p : kNgaCheckPoints) {
    worst.add(std::abs(bilinear.undulation_m(Angle::degrees(p.lat_deg), Angle::degrees(p.lon_deg)) - p.n_m));
  }
  EXPECT_WORST_WITHIN(worst, kBilinearVsNgaBound_m);
  EXPECT_GT(worst.value(), kPublishedAgreement_m);  // false for NaN
}

TEST(Egm96, NgaSplinePassesThroughTheGridNodesAndWrapsInLongitude) {
  const GeoidGrid& nga = GeoidGrid::egm96_nga();
  const GeoidGrid& bilinear = GeoidGrid::egm96();
  for (double la : {-60.0, 0.0, 47.25, 80.5}) {
    for (double lo : {-180.0, -0.25, 0.0, 8.5, 179.75}) {
      // At a node both interpolations return the node's value.
      EXPECT_NEAR(nga.undulation_m(Angle::degrees(la), Angle::degrees(lo)),
                  bilinear.undulation_m(Angle::degrees(la), Angle::degrees(lo)), kRounding_m)
          << la << " " << lo;
    }
    EXPECT_NEAR(nga.undulation_m(Angle::degrees(la), Angle::degrees(-179.9)),
                nga.undulation_m(Angle::degrees(la), Angle::degrees(180.1)), kRounding_m);
  }
}

TEST(Egm96, ARangeOfKnownMagnitudes) {
  // The geoid's known extremes: about −106 m south of India, about +85 m
  // over New Guinea; about 48 m at Zurich (EGM96).
  const GeoidGrid& g = GeoidGrid::egm96();
  EXPECT_LT(g.undulation_m(Angle::degrees(5.0), Angle::degrees(78.0)), -100.0);
  EXPECT_GT(g.undulation_m(Angle::degrees(-5.0), Angle::degrees(147.0)), 70.0);
  EXPECT_NEAR(g.undulation_m(Angle::degrees(47.46), Angle::degrees(8.55)), 48.0, 2.0);
  EXPECT_TRUE(std::isnan(g.undulation_m(Angle::degrees(std::nan("")), Angle::degrees(0.0))));
}

// issue 12, tests that can fail, item 6: a folder of the test's own.
TEST(GeoidGrid, RefusesFilesThatAreNotGtxGridsNamingThem) {
  const testing::TempFolder folder;
  const auto& dir = folder.path();
  const auto short_file = dir / "geoanchor_short.gtx";
  std::ofstream(short_file, std::ios::binary) << "not a grid";
  try {
    (void)GeoidGrid::load_gtx(short_file, "x");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_NE(std::string(e.what()).find("geoanchor_short.gtx: 10 bytes, shorter than a .gtx header (40)"), std::string::npos) << e.what();
  }
  // A real header with the data cut short.
  {
    std::ifstream in("/usr/share/proj/egm96_15.gtx", std::ios::binary);
    std::string head(1000, '\0');
    in.read(head.data(), 1000);
    std::ofstream(dir / "geoanchor_cut.gtx", std::ios::binary) << head;
  }
  try {
    (void)GeoidGrid::load_gtx(dir / "geoanchor_cut.gtx", "x");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("1000 bytes; a 721 × 1440 .gtx grid has 4153000"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)GeoidGrid::load_gtx(dir / "geoanchor_none.gtx", "x"), Error);
}


// An NTv2 geoid grid in AUSGeoid's form: DynAdjust's sample clip of
// AUSGeoid09 (sampleData/urban-network-geoid.gsb, fixtures/networks) at
// three stations of its urban network, against the N, xi, eta DynAdjust
// publishes for them in sampleData/urban-network.geo (dnageoid, bicubic by
// default). The stations' latitude and longitude are PROJ's (cs2cs
// EPSG:28355 -> EPSG:4283 of their UTM coordinates in urban-network.stn).
// The .geo values are written to 1 mm and 0.001"; they differ from the clip
// by up to 1.5 mm and 0.012" (the clip's float32 nodes, and a grid edge two
// nodes away): the tolerances say so.
TEST(GeoidNtv2, AusGeoidClipMatchesDynAdjustsStationValues) {
  constexpr double kNTol_m = 0.002;          // published to 1 mm; the clip's nodes
  constexpr double kDeflectionTol_arcsec = 0.02;
  constexpr double kArcsec = 3.14159265358979323846 / 648000.0;
  const GeoidGrid g = GeoidGrid::load_ntv2(std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/urban-network-geoid.gsb",
                                           GeoidInterpolation::bicubic);
  ASSERT_TRUE(g.has_deflections());
  struct Case {
    double lat, lon, n, xi, eta;
  };
  const Case cases[] = {{-37.8038056346, 144.9580517107, 4.780, -7.168, -4.144},   // station 1
                        {-37.7996094759, 144.9602945073, 4.801, -7.066, -4.034},   // station 1002
                        {-37.8006751325, 144.9593559074, 4.795, -7.094, -4.069}};  // station 1008
  for (const Case& c : cases) {
    const double n = g.undulation_m(Angle::degrees(c.lat), Angle::degrees(c.lon));
    const auto d = g.deflection(Angle::degrees(c.lat), Angle::degrees(c.lon));
    ASSERT_TRUE(d.has_value());
    EXPECT_LE(std::abs(n - c.n), kNTol_m) << c.lat;  // NaN fails: the comparison is false
    EXPECT_LE(std::abs(d->xi_rad / kArcsec - c.xi), kDeflectionTol_arcsec) << c.lat;
    EXPECT_LE(std::abs(d->eta_rad / kArcsec - c.eta), kDeflectionTol_arcsec) << c.lat;
  }
  // Outside the clip: no value.
  EXPECT_TRUE(std::isnan(g.undulation_m(Angle::degrees(-37.9), Angle::degrees(144.95))));
  EXPECT_FALSE(g.deflection(Angle::degrees(-37.9), Angle::degrees(144.95)).has_value());
}

TEST(GeoidNtv2, HorizontalShiftGridsAreNoGeoid) {
  // PROJ's Swiss CH1903 -> CH1903+ grid (proj-data): SYSTEM_T names a datum.
  try {
    (void)GeoidGrid::load_ntv2("/usr/share/proj/CHENYX06.gsb", GeoidInterpolation::bicubic);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("horizontal shift grid"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace geoanchor::geodesy
