// The WKT2 and PROJJSON exports: PROJ parses them back and, applying them,
// lands where geoanchor's own application of the transform does.

#include <gtest/gtest.h>

#include <memory>

#include "geoanchor/io/transform/transform_file.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor::io {
namespace {

constexpr double kVsProjTol_m = 1e-6;  // issue acceptance for PROJ agreement

// PROJ applying `definition` (WKT2 or PROJJSON) through the reference
// helper: an error PROJ reports for the point fails the test.
Eigen::Vector3d proj_apply(const std::string& definition, const Eigen::Vector3d& x, double t) {
  return testing::ProjPipeline(definition).forward(x, t);
}

const char* kFiles[] = {
    R"J({"model": "translation3", "parameters": {"tx_m": 1.5, "ty_m": -2.25, "tz_m": 0.75}})J",
    R"J({"model": "helmert7", "convention": "position_vector", "source_frame": "WGS72", "target_frame": "WGS84(G1762)@2005.0",
        "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 4.5, "rx_arcsec": 0.3, "ry_arcsec": -0.2, "rz_arcsec": 0.554, "ds_ppm": 0.219}})J",
    R"J({"model": "helmert7", "convention": "coordinate_frame",
        "parameters": {"tx_m": 0.06155, "ty_m": -0.01087, "tz_m": -0.04019, "rx_arcsec": -0.0394924,
                       "ry_arcsec": -0.0327221, "rz_arcsec": -0.0328979, "ds_ppm": -0.009994}})J",
    R"J({"model": "helmert14", "convention": "coordinate_frame", "reference_epoch": 1994.0,
        "parameters": {"tx_mm": -84.68, "ty_mm": -19.42, "tz_mm": 32.01, "rx_mas": -0.4254, "ry_mas": 2.2578,
                       "rz_mas": 2.4015, "ds_ppb": 9.71, "dtx_mm_per_year": 1.42, "dty_mm_per_year": 1.34,
                       "dtz_mm_per_year": 0.90, "drx_mas_per_year": 1.5461, "dry_mas_per_year": 1.1820,
                       "drz_mas_per_year": 1.1551, "dds_ppb_per_year": 0.109}})J",
    R"J({"model": "molodensky-badekas", "convention": "coordinate_frame",
        "parameters": {"tx_m": -270.933, "ty_m": 115.599, "tz_m": -360.226, "rx_arcsec": -5.266, "ry_arcsec": -1.238,
                       "rz_arcsec": 2.381, "ds_ppm": -5.109, "px_m": 2464351.59, "py_m": -5783466.61, "pz_m": 974809.81}})J",
};

TEST(TransformWkt, ProjParsesTheWkt2AndProjjsonBackAndAppliesThemAsWeDo) {
  for (const char* text : kFiles) {
    const TransformFile t = parse_transform_json(text, "T.json");
    const auto wkt = to_wkt2(t);
    const auto projjson = to_projjson(t);
    ASSERT_TRUE(wkt && projjson) << text;
    EXPECT_NE(wkt->find("ID[\"EPSG\"," + epsg_method(t).substr(5) + "]"), std::string::npos) << *wkt;
    for (const auto& g : testing::worldwide_points(50, -100.0, 3000.0, 3)) {
      const double cl = std::cos(g.lat.rad());
      const Eigen::Vector3d x(6378137.0 * cl * std::cos(g.lon.rad()), 6378137.0 * cl * std::sin(g.lon.rad()),
                              6356752.0 * std::sin(g.lat.rad()));
      for (double epoch : {2000.0, 2013.9, 2024.5}) {
        const Eigen::Vector3d ours = t.target_from_source(geodesy::DecimalYear{epoch}, "").apply(x);
        EXPECT_THAT(proj_apply(*wkt, x, epoch), testing::IsNearVector(ours, kVsProjTol_m)) << text << " at " << epoch;
        EXPECT_THAT(proj_apply(*projjson, x, epoch), testing::IsNearVector(ours, kVsProjTol_m)) << text;
      }
    }
  }
}

TEST(TransformWkt, NoEpsgMethodDescribesTheExactRotationModelOrEnuOrigin) {
  TransformFile t = parse_transform_json(kFiles[1], "T.json");
  t.rotation_model = geodesy::RotationModel::exact;
  EXPECT_FALSE(to_wkt2(t).has_value());
  EXPECT_FALSE(to_projjson(t).has_value());
}

}  // namespace
}  // namespace geoanchor::io
