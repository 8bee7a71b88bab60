// `geoanchor audit` and `geoanchor locate` on a small map made here the way
// a user makes one (issue 16 points 4 and 5): two adjacent ENU tiles of an
// apron with their sidecars, a transform fitted to surveyed marks, `apply`
// with the survey's metadata file, and checkpoints. The clean map passes;
// each planted defect fails the check it belongs to, named, with the
// planted size in its evidence (the sizes come from the defects planted
// here, not from what audit printed).

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_support.hpp"
#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::RunResult;
using testing::slurp;
using json = nlohmann::json;

constexpr double kLat = 47.464722, kLon = 8.549167, kH = 480.0;  // the LSZH ARP, ellipsoidal
const std::array<double, 3> kShift_m = {0.10, -0.05, 0.03};             // the map's error: what the fit finds (ECEF)
constexpr int kExitFailed = 4;

std::string num(double v) { return format_shortest(v); }

geodesy::LocalOrigin arp() {
  return {geodesy::GeodeticPosition{geodesy::Angle::degrees(kLat), geodesy::Angle::degrees(kLon), geodesy::EllipsoidalHeight{kH}},
          geodesy::Ellipsoid::grs80()};
}

class Audit : public CliTest {
 protected:
  // The survey's metadata, every field given (or without `leave_out`).
  fs::path survey(const std::string& leave_out = "") const {
    json s = {{"schema", "geoanchor.survey/1"},
              {"frame", "ITRF2014@2024.5"},
              {"enu_origin", {{"lat_deg", kLat}, {"lon_deg", kLon}, {"h_m", kH}, {"height_type", "ellipsoidal"}}},
              {"enu_origin_source", "ICAO AIP published; survey confirmed"},
              {"vertical_datum", "ellipsoid GRS80"},
              {"geoid_model", "CHGeo2004"},
              {"gnss_method", "network RTK (VRS)"},
              {"gnss_base", "swipos VRS"},
              {"rtk_fixed_percent", 98.7}};
    if (!leave_out.empty()) s.erase(leave_out);
    return write("survey" + leave_out + ".json", s.dump(2));
  }

  // An ENU tile (CSV) over e in [e0, e1], n in [0, 200] m, with its sidecar.
  fs::path tile(const std::string& name, double e0, double e1) const {
    std::ostringstream csv;
    csv << "e_m,n_m,u_m\n";
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 20; ++j) {
        const double e = e0 + (e1 - e0) * i / 20.0, n = 200.0 * j / 20.0;
        csv << num(e) << "," << num(n) << "," << num(1.0 + 0.001 * e) << "\n";
      }
    }
    const fs::path p = write("raw/" + name, csv.str());
    const json side = {{"schema", "geoanchor.tile/1"},
                       {"frame", "ITRF2014@2024.5"},
                       {"coordinates", {{"kind", "enu"}, {"ellipsoid", "GRS80"}, {"storage", "float64"}}},
                       {"enu_origin",
                        {{"lat_deg", kLat}, {"lon_deg", kLon}, {"h_m", kH}, {"height_type", "ellipsoidal"},
                         {"source", "ICAO AIP published; survey confirmed"}}},
                       {"horizontal_crs", "local ENU at the aerodrome reference point"},
                       {"vertical", {{"datum", "ellipsoid GRS80"}, {"height_type", "ellipsoidal"}, {"geoid_model", "CHGeo2004"}}},
                       {"survey", {{"method", "network RTK (VRS)"}, {"rtk_fixed_percent", 98.7}}}};
    write("raw/" + name + ".geoanchor.json", side.dump(2));
    return p;
  }

  // Marks around the ARP: source ECEF as the map has them, target = source
  // + the map's shift (+ `extra_m` on the first mark's east) + ±3 mm.
  fs::path control(const std::string& name, double extra_east_m = 0.0, double shift_x_extra_m = 0.0) const {
    const geodesy::LocalTangentPlane plane(arp());
    std::ostringstream out;
    out << "# source_frame = ITRF2014@2024.5\n# target_frame = ITRF2014@2024.5\n";
    out << "id,x_src_m,y_src_m,z_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m,sigma_dst_m\n";
    const double pts[8][2] = {{-300, -200}, {0, -250}, {350, -150}, {420, 120}, {100, 300}, {-250, 250}, {-400, 0}, {50, 40}};
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d s = plane.ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d(pts[i][0], pts[i][1], 2.0), arp()}).m;
      const double noise = 0.003 * ((i % 3) - 1.0);
      Eigen::Vector3d t = s + Eigen::Vector3d(kShift_m[0] + shift_x_extra_m + noise, kShift_m[1] - noise, kShift_m[2] + 0.5 * noise);
      if (i == 0) t += plane.enu_from_ecef_rotation().row(0).transpose() * extra_east_m;
      out << "M" << i << "," << num(s.x()) << "," << num(s.y()) << "," << num(s.z()) << "," << num(t.x()) << "," << num(t.y())
          << "," << num(t.z()) << ",0.003,0.003\n";
    }
    return write(name, out.str());
  }

  // The transform fitted to `control` (translation3), with the survey's metadata.
  fs::path fit(const fs::path& control, const std::string& name) const {
    const RunResult r = run("fit " + control.string() + " --model translation3 --survey-metadata " + survey().string() + " -o " +
                            path(name).string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return path(name);
  }

  fs::path apply(const std::string& inputs, const fs::path& transform, const std::string& out_dir,
                 const std::string& extra = "") const {
    const RunResult r = run("apply " + inputs + " --transform " + transform.string() + " --survey-metadata " + survey().string() +
                            " --out-dir " + path(out_dir).string() + " " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return path(out_dir);
  }

  // The clean map: two adjacent tiles 0.5 m apart, one transform.
  void clean_map() {
    west_ = tile("west.csv", 0.0, 200.0);
    east_ = tile("east.csv", 200.5, 400.0);
    transform_ = fit(control("control.csv"), "t.json");
    apply(west_.string() + " " + east_.string(), transform_, "map");
  }

  // Edits an output sidecar's JSON.
  void edit_sidecar(const fs::path& sidecar, const std::function<void(json&)>& change) const {
    json j = json::parse(slurp(sidecar));
    change(j);
    std::ofstream(sidecar, std::ios::trunc) << j.dump(2);
  }

  RunResult audit(const std::string& args) const { return run("audit " + args); }

  // The check's JSON object in an audit's --json output.
  static json check(const RunResult& r, const std::string& name) {
    const json j = json::parse(r.out);
    for (const auto& c : j.at("checks")) {
      if (c.at("name") == name) return c;
    }
    ADD_FAILURE() << "no check " << name;
    return json::object();
  }
  static std::vector<std::string> failing(const RunResult& r) {
    std::vector<std::string> out;
    const json j = json::parse(r.out);  // kept: a range over a temporary's member would dangle
    for (const auto& c : j.at("checks")) {
      if (c.at("status") == "fail") out.push_back(c.at("name"));
    }
    return out;
  }

  fs::path west_, east_, transform_;
};

TEST_F(Audit, Issue16_TheCleanMapPassesEveryCheck) {
  clean_map();
  const RunResult text = audit(path("map").string() + " " + transform_.string() + " --checkpoints " + path("control.csv").string());
  EXPECT_EQ(text.exit_code, 0) << text.out << text.err;
  EXPECT_NE(text.out.find("audit: PASSED (10 of 10 checks pass)"), std::string::npos) << text.out;
  const RunResult r =
      audit(path("map").string() + " " + transform_.string() + " --checkpoints " + path("control.csv").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(json::parse(r.out).at("passed"), true);
  EXPECT_EQ(failing(r), std::vector<std::string>{});
  // The two tiles meet; moved by one transform they have no seam.
  EXPECT_NE(check(r, "seams").at("summary").get<std::string>().find("1 shared boundaries or overlaps among 2 tiles and vector maps"), std::string::npos)
      << check(r, "seams");
}

TEST_F(Audit, Issue16_ATileInAnotherRealizationFailsOneFrameNamingIt) {
  clean_map();
  edit_sidecar(path("map/east.csv.geoanchor.json"), [](json& j) {
    j["frame"] = "ITRF2020@2024.5";
    j["metadata"]["frame"] = "ITRF2020";
  });
  const RunResult r = audit(path("map").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"one_frame"}) << r.out;
  const std::string evidence = check(r, "one_frame").at("evidence").dump();
  EXPECT_NE(evidence.find("ITRF2020 in " + path("map/east.csv").string()), std::string::npos) << evidence;
}

TEST_F(Audit, Issue16_ATileWithAnotherEnuOriginFailsOneFrame) {
  clean_map();
  edit_sidecar(path("map/west.csv.geoanchor.json"), [](json& j) {
    j["enu_origin"]["lat_deg"] = kLat + 1e-5;  // 1.1 m north
    j["metadata"]["enu_origin"]["lat_deg"] = kLat + 1e-5;
  });
  const RunResult r = audit(path("map").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  const auto f = failing(r);
  EXPECT_NE(std::find(f.begin(), f.end(), "one_frame"), f.end()) << r.out;
  EXPECT_NE(check(r, "one_frame").at("evidence").dump().find("ENU origin differs"), std::string::npos);
}

TEST_F(Audit, Issue16_ATileMovedByATransform3cmOffLeavesASeam) {
  west_ = tile("west.csv", 0.0, 200.0);
  east_ = tile("east.csv", 200.5, 400.0);
  transform_ = fit(control("control.csv"), "t.json");
  const fs::path off = fit(control("control_off.csv", 0.0, 0.03), "t_off.json");  // 3 cm more in ECEF x
  apply(west_.string(), transform_, "map");
  apply(east_.string(), off, "map");
  const RunResult r = audit(path("map").string() + " " + transform_.string() + " " + off.string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"seams"}) << r.out;
  const json seams = check(r, "seams");
  // The planted 3 cm, give or take the two fits' different noise (±2 mm).
  const std::string evidence = seams.at("evidence").dump();
  const auto at = evidence.find(" cm apart");
  ASSERT_NE(at, std::string::npos) << evidence;
  const double seam_cm = std::stod(evidence.substr(evidence.rfind(' ', at - 1) + 1));
  constexpr double kFitNoise_cm = 0.2;
  EXPECT_NEAR(seam_cm, 3.0, kFitNoise_cm) << evidence;
}

TEST_F(Audit, Issue16_AVectorLayerMovedByATransform3cmOffTearsFromTheTileUnderIt) {
  clean_map();
  // A GeoJSON layer over the west tile (lon, lat, h on GRS80 from ENU at the ARP).
  const geodesy::LocalTangentPlane plane(arp());
  std::string coords;
  for (const auto& [e, n] : std::vector<std::pair<double, double>>{{20, 20}, {180, 30}, {150, 180}}) {
    const geodesy::GeodeticPosition g = geodesy::geodetic_from_ecef(
        geodesy::Ellipsoid::grs80(), plane.ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d(e, n, 1.0), arp()}));
    coords += std::string(coords.empty() ? "" : ",") + "[" + num(g.lon.deg()) + "," + num(g.lat.deg()) + "," + num(g.h.m) + "]";
  }
  write("raw/lines.geojson", R"({"type": "FeatureCollection", "features": [{"type": "Feature", "id": "l1", "properties": {},
    "geometry": {"type": "LineString", "coordinates": [)" + coords + "]}}]}");
  const fs::path off = fit(control("control_off.csv", 0.0, 0.03), "t_off.json");
  apply(path("raw/lines.geojson").string(), off, "map", "--from-frame ITRF2014@2024.5");
  const RunResult r = audit(path("map").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"seams"}) << r.out;
  const std::string evidence = check(r, "seams").at("evidence").dump();
  EXPECT_NE(evidence.find("lines.geojson | " + path("map/west.csv").string() + ": 3.0 cm apart"), std::string::npos) << evidence;
}

TEST_F(Audit, Issue16_CheckpointsWithoutTheirFramesAreRefused) {
  clean_map();
  std::string text = slurp(path("control.csv"));
  text = text.substr(text.find("id,"));  // without the frame comments
  write("bare.csv", text);
  const RunResult r = audit(path("map").string() + " --checkpoints " + path("bare.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.out;
  EXPECT_NE(r.err.find("E_CHECKPOINT_FRAME"), std::string::npos) << r.err;
}

TEST_F(Audit, Issue16_ACheckpoint6cmOffFailsNamingItsResidualAndUncertainty) {
  clean_map();
  control("checkpoints.csv", 0.06);  // M0's target 6 cm east of where the map puts it
  const RunResult r = audit(path("map").string() + " --checkpoints " + path("checkpoints.csv").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"checkpoints"}) << r.out;
  const json cp = check(r, "checkpoints");
  std::string m0;
  for (const auto& e : cp.at("evidence")) {
    if (e.get<std::string>().rfind("M0:", 0) == 0) m0 = e.get<std::string>();
  }
  ASSERT_FALSE(m0.empty()) << cp;
  EXPECT_NE(m0.find("FAIL"), std::string::npos) << m0;
  EXPECT_NE(m0.find("propagated σ east"), std::string::npos) << m0;
  // The residual is map − surveyed: 6 cm west, within the fit's noise.
  const auto h = m0.find("horizontal ");
  const double residual_cm = std::stod(m0.substr(h + 11));
  EXPECT_NEAR(residual_cm, 6.0, 0.5) << m0;
}

TEST_F(Audit, Issue16_AMissingGeoidNameFailsTheMetadataCheck) {
  west_ = tile("west.csv", 0.0, 200.0);
  json side = json::parse(slurp(path("raw/west.csv.geoanchor.json")));
  side["vertical"]["geoid_model"] = nullptr;
  std::ofstream(path("raw/west.csv.geoanchor.json"), std::ios::trunc) << side.dump(2);
  transform_ = fit(control("control.csv"), "t.json");
  const RunResult a = run("apply " + west_.string() + " --transform " + transform_.string() + " --survey-metadata " +
                          survey("geoid_model").string() + " --out-dir " + path("map").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const RunResult r = audit(path("map").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"metadata"}) << r.out;
  EXPECT_NE(check(r, "metadata").at("evidence").dump().find("geoid_model"), std::string::npos) << check(r, "metadata");
}

TEST_F(Audit, Issue16_Float32EcefFails) {
  clean_map();
  edit_sidecar(path("map/east.csv.geoanchor.json"), [](json& j) {
    j["coordinates"] = {{"kind", "ecef"}, {"storage", "float32"}};
    j.erase("enu_origin");
    j["metadata"]["coordinate_storage"] = "float32 ECEF";
  });
  const RunResult r = audit(path("map").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  const auto f = failing(r);
  EXPECT_NE(std::find(f.begin(), f.end(), "no_float32_ecef"), f.end()) << r.out;
  EXPECT_NE(check(r, "no_float32_ecef").at("evidence").dump().find("east.csv"), std::string::npos);
}

TEST_F(Audit, Issue16_AWebMercatorLayerFails) {
  // apply refuses to move ITRF2014 into EPSG:3857 (a datum ensemble); a
  // layer made elsewhere in Web Mercator says so in its sidecar.
  clean_map();
  edit_sidecar(path("map/east.csv.geoanchor.json"), [](json& j) {
    j["horizontal_crs"] = "EPSG:3857 (WGS 84 / Pseudo-Mercator)";
    j["metadata"]["horizontal_crs"] = "EPSG:3857 (WGS 84 / Pseudo-Mercator)";
  });
  const RunResult r = audit(path("map").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"no_web_mercator"}) << r.out;
  const std::string evidence = check(r, "no_web_mercator").at("evidence").dump();
  EXPECT_NE(evidence.find(path("map/east.csv").string()), std::string::npos) << evidence;
  EXPECT_EQ(evidence.find(path("map/west.csv").string()), std::string::npos) << evidence;
}

TEST_F(Audit, Issue16_AMapTooLargeForItsTangentPlaneFails) {
  clean_map();
  const fs::path far = tile("far.csv", 5000.0, 5100.0);  // 5.1 km east: d²/2R ≈ 2.0 m
  apply(far.string(), transform_, "map");
  const RunResult r = audit(path("map").string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"tangent_plane"}) << r.out;
  const std::string summary = check(r, "tangent_plane").at("summary");
  // d = |(5100, 200)| = 5103.9 m; d²/2R with R ≈ 6.38e6 m is 204 cm.
  EXPECT_NE(summary.find("5.10"), std::string::npos) << summary;
}

TEST_F(Audit, Issue16_FilesThatAreNoPartOfAMapAreNamed) {
  clean_map();
  write("map/notes.md", "what is this\n");
  const RunResult r = audit(path("map").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("notes.md"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--exclude"), std::string::npos) << r.err;
  EXPECT_EQ(audit(path("map").string() + " --exclude '*.md'").exit_code, 0);
  // A tile without its sidecar is audited, and fails the metadata check by name.
  write("map/extra.csv", "e_m,n_m,u_m\n1,2,3\n");
  const RunResult no_sidecar = audit(path("map").string() + " --exclude '*.md' --json");
  EXPECT_EQ(no_sidecar.exit_code, kExitFailed);
  EXPECT_NE(check(no_sidecar, "metadata").at("evidence").dump().find("extra.csv: no sidecar"), std::string::npos)
      << check(no_sidecar, "metadata");
}

TEST_F(Audit, Issue16_LocateGivesTheGeodeticPositionAndTheTransformsSigmas) {
  clean_map();
  write("points.csv", "id,e_m,n_m,u_m\nstand_12,120.0,80.0,2.5\n");
  const RunResult r = run("locate " + path("map").string() + " " + path("points.csv").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  const json& p = j.at("points").at(0);
  // ENU at the ARP -> ECEF -> geodetic, independently: PROJ's topocentric
  // conversion is checked against geodesy elsewhere; here the geodetic
  // position must come back to the ENU given through an independent
  // tangent-plane rotation of the ECEF difference.
  const geodesy::EcefPosition x(p.at("ecef_m")[0].get<double>(), p.at("ecef_m")[1].get<double>(), p.at("ecef_m")[2].get<double>());
  const Eigen::Vector3d o = geodesy::ecef_from_geodetic(geodesy::Ellipsoid::grs80(), arp().point).m;
  const double lat = kLat * std::numbers::pi / 180.0, lon = kLon * std::numbers::pi / 180.0;
  const Eigen::Vector3d d = x.m - o;
  const double e = -std::sin(lon) * d.x() + std::cos(lon) * d.y();
  const double n = -std::sin(lat) * std::cos(lon) * d.x() - std::sin(lat) * std::sin(lon) * d.y() + std::cos(lat) * d.z();
  const double u = std::cos(lat) * std::cos(lon) * d.x() + std::cos(lat) * std::sin(lon) * d.y() + std::sin(lat) * d.z();
  constexpr double kRoundTrip_m = 1e-6;
  EXPECT_NEAR(e, 120.0, kRoundTrip_m);
  EXPECT_NEAR(n, 80.0, kRoundTrip_m);
  EXPECT_NEAR(u, 2.5, kRoundTrip_m);
  // The fitted translation's sigmas reach the point: a few mm, finite.
  ASSERT_TRUE(p.at("sigma_m").is_object()) << p;
  for (const char* k : {"east", "north", "up"}) {
    const double s = p.at("sigma_m").at(k).get<double>();
    EXPECT_GT(s, 0.0) << k;
    EXPECT_LT(s, 0.01) << k;
  }
  // A column locate does not read is an error naming it.
  write("bad.csv", "id,e_m,n_m,u_m,h_m\nA,1,2,3,4\n");
  const RunResult bad = run("locate " + path("map").string() + " " + path("bad.csv").string());
  EXPECT_EQ(bad.exit_code, 3);
  EXPECT_NE(bad.err.find("'h_m'"), std::string::npos) << bad.err;
}

// Issue 40 point 3: locate extrapolates the map's transform no farther
// than apply does: a point 20 km outside the control network (about 420 m
// across) is refused by name with nothing written, accepted with a note
// under a larger --max-extrapolation.
TEST_F(Audit, Issue40_LocateRefusesPointsFarOutsideTheControlNetwork) {
  clean_map();
  write("points.csv", "id,e_m,n_m,u_m\nstand_12,120.0,80.0,2.5\nfar_away,20000.0,0.0,2.5\n");
  const fs::path out = path("located.csv");
  const RunResult r = run("locate " + path("map").string() + " " + path("points.csv").string() + " -o " + out.string());
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("E_EXTRAPOLATION"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("far_away"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("points.csv:3"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  const RunResult wide = run("locate " + path("map").string() + " " + path("points.csv").string() +
                             " --max-extrapolation 30000 -o " + out.string());
  ASSERT_EQ(wide.exit_code, 0) << wide.err;
  const std::string csv = slurp(out);
  EXPECT_NE(csv.find("# note: points lie outside the control network"), std::string::npos) << csv;
  EXPECT_NE(csv.find("far_away 19"), std::string::npos) << csv;  // about 19.6 km outside the hull
}

// Issue 40 point 11: one sign for residuals, measured minus map. A
// checkpoint surveyed 3 cm east of where the map puts it reads +3 cm east in
// audit, and the same mark in a fit reads a positive east residual too.
TEST_F(Audit, Issue40_CheckpointResidualsHaveFitsSign) {
  clean_map();
  const fs::path shifted = control("shifted.csv", 0.03);  // M0's target 3 cm east
  const RunResult r = audit(path("map").string() + " " + transform_.string() + " --checkpoints " + shifted.string() + " --json");
  const std::string evidence = check(r, "checkpoints").at("evidence").dump();
  const auto at = evidence.find("M0: ");
  ASSERT_NE(at, std::string::npos) << evidence;
  const std::string m0 = evidence.substr(at, evidence.find('"', at) - at);
  const auto east = m0.find("(east ");
  ASSERT_NE(east, std::string::npos) << m0;
  EXPECT_NE(m0[east + 6], '-') << m0;  // +2.x to +3.x cm, not −
  const double audit_east_cm = std::stod(m0.substr(east + 6));
  EXPECT_GT(audit_east_cm, 2.0) << m0;
  // fit of the shifted set: M0's east residual (target − transformed source) is positive too.
  const RunResult f = run("fit " + shifted.string() + " --model translation3 --survey-metadata " + survey().string() +
                          " --accept-failed-global-test -o " + path("shifted.json").string());
  ASSERT_EQ(f.exit_code, 0) << f.err;
  const json t = json::parse(slurp(path("shifted.json")));
  bool seen = false;
  for (const auto& p : t.at("points")) {
    if (p.at("id") != "M0") continue;
    seen = true;
    EXPECT_GT(p.at("residual_enu_m")[0].get<double>(), 0.0) << p;
  }
  EXPECT_TRUE(seen);
}

// Issue 40 point 6: audit checks the data, not only the metadata. A tile
// changed by one byte after apply fails, naming it; the untouched map
// passes.
TEST_F(Audit, Issue40_ATileChangedAfterApplyFailsNamingIt) {
  clean_map();
  const RunResult clean = audit(path("map").string() + " " + transform_.string() + " --json");
  ASSERT_EQ(clean.exit_code, 0) << clean.out << clean.err;
  EXPECT_EQ(check(clean, "data").at("status"), "pass") << check(clean, "data");
  // One byte of one tile, after apply: a digit of its last coordinate.
  std::string text = slurp(path("map/east.csv"));
  const auto at = text.find_last_of("0123456789");
  text[at] = text[at] == '9' ? '8' : static_cast<char>(text[at] + 1);
  write("map/east.csv", text);
  const RunResult r = audit(path("map").string() + " " + transform_.string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.out << r.err;
  EXPECT_EQ(failing(r), std::vector<std::string>{"data"}) << r.out;
  const std::string evidence = check(r, "data").at("evidence").dump();
  EXPECT_NE(evidence.find(path("map/east.csv").string() + ": FAIL the file's SHA-256"), std::string::npos) << evidence;
  EXPECT_EQ(evidence.find(path("map/west.csv").string() + ": FAIL"), std::string::npos) << evidence;
  // Resuming the same apply does not call the changed tile up to date (its
  // bytes are not the ones its sidecar records): refused, naming it, and
  // written again with --overwrite; the map then passes.
  const RunResult resumed = run("apply " + west_.string() + " " + east_.string() + " --transform " + transform_.string() +
                                " --survey-metadata " + survey().string() + " --out-dir " + path("map").string());
  EXPECT_NE(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find(path("map/east.csv").string() + ": output already exists and is not the one this request wrote"),
            std::string::npos)
      << resumed.err;
  EXPECT_EQ(slurp(path("map/east.csv")), text);
  apply(west_.string() + " " + east_.string(), transform_, "map", "--overwrite");
  EXPECT_NE(slurp(path("map/east.csv")), text);
  const RunResult again = audit(path("map").string() + " " + transform_.string() + " --json");
  EXPECT_EQ(again.exit_code, 0) << again.out << again.err;
}

// The seams come from the points each tile holds now: a tile moved 4 cm
// after apply fails the seams check too (its extent is not the one its
// sidecar records), naming it, as well as the data check.
TEST_F(Audit, Issue40_SeamsAreReadFromThePointsATileHolds) {
  clean_map();
  std::istringstream rows(slurp(path("map/east.csv")));
  std::string line, moved;
  std::getline(rows, line);
  moved = line + "\n";
  while (std::getline(rows, line)) {
    const auto comma = line.find(',');
    moved += format_shortest(std::stod(line.substr(0, comma)) + 0.04) + line.substr(comma) + "\n";
  }
  write("map/east.csv", moved);
  const RunResult r = audit(path("map").string() + " " + transform_.string() + " --json");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.out << r.err;
  EXPECT_EQ(failing(r), (std::vector<std::string>{"data", "seams"})) << r.out;
  const std::string evidence = check(r, "seams").at("evidence").dump();
  EXPECT_NE(evidence.find(path("map/east.csv").string() + ": FAIL its points span"), std::string::npos) << evidence;
  EXPECT_EQ(evidence.find(path("map/west.csv").string() + ": FAIL"), std::string::npos) << evidence;
}

// A map moved to another frame by a Helmert (a GeoJSON in longitude and
// latitude) has no ENU origin to state: it is auditable, and passes.
TEST_F(Audit, Issue40_AMapMovedBetweenFramesByAHelmertIsAuditable) {
  // The fitted Helmert (fit writes its metadata), without the survey's ENU origin.
  const RunResult fitted = run("fit " + control("control.csv").string() + " --model translation3 --survey-metadata " +
                               survey("enu_origin").string() + " -o " + path("helmert.json").string());
  ASSERT_EQ(fitted.exit_code, 0) << fitted.err;
  const fs::path t = path("helmert.json");
  const fs::path apron = fs::path(GEOANCHOR_SOURCE_DIR) / "tests" / "data" / "vector" / "apron.geojson";
  const RunResult moved = run("apply " + apron.string() + " --from-frame ITRF2014@2024.5 --transform " + t.string() +
                              " --survey-metadata " + survey().string() + " --out-dir " + path("moved").string());
  ASSERT_EQ(moved.exit_code, 0) << moved.err;
  const RunResult r = audit(path("moved").string() + " " + t.string() + " --json");
  EXPECT_EQ(failing(r), std::vector<std::string>{}) << r.out << r.err;
  EXPECT_EQ(check(r, "metadata").at("status"), "pass") << check(r, "metadata");
  EXPECT_EQ(r.out.find("unknown: enu_origin"), std::string::npos) << r.out;
}

// A folder of transforms alone is no map; locate refuses a tile whose
// sidecar is missing or broken, as audit fails it.
TEST_F(Audit, Issue40_NoTilesIsRefusedAndLocateNamesATileWithoutItsSidecar) {
  clean_map();
  fs::create_directories(path("only"));
  fs::copy_file(transform_, path("only/t.json"));
  const RunResult empty = audit(path("only").string());
  EXPECT_EQ(empty.exit_code, 3) << empty.out << empty.err;
  EXPECT_NE(empty.err.find("E_MAP_EMPTY"), std::string::npos) << empty.err;
  fs::remove(path("map/east.csv.geoanchor.json"));
  write("points.csv", "id,e_m,n_m,u_m\nstand_12,120.0,80.0,2.5\n");
  const RunResult located = run("locate " + path("map").string() + " " + path("points.csv").string() + " -o " + path("l.csv").string());
  EXPECT_EQ(located.exit_code, 3) << located.err;
  EXPECT_NE(located.err.find("E_MAP_REFERENCE"), std::string::npos) << located.err;
  EXPECT_NE(located.err.find(path("map/east.csv").string()), std::string::npos) << located.err;
  EXPECT_FALSE(fs::exists(path("l.csv")));
}

}  // namespace
}  // namespace geoanchor
