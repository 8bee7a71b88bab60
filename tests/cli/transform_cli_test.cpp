// `geoanchor transform` against PROJ: the same epoch through an EPSG
// operation from PROJ's database, an epoch change by the ITRF2014 plate
// motion model as PROJ's ITRF2014 file applies it, and per-point velocities;
// then its refusals.

#include <gtest/gtest.h>

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/Geocentric.hpp>
#include <nlohmann/json.hpp>

#include <sstream>

#include "cli_support.hpp"
#include "geoanchor/base/number_text.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::ProjPipeline;
using testing::slurp;

constexpr double kProjAgreement_m = 1e-6;        // the issue's bound; float64 rounding is ~1e-9 m
constexpr double kVelocityAgreement_m_per_year = 1e-9;

const char* kEpsg9991 = "urn:ogc:def:coordinateOperation:EPSG::9991";  // ITRF2014 to ITRF2020

// Marks of the EUREF network (ECEF, m, rounded) and velocities of the size
// of Eurasia's motion.
const Eigen::Vector3d kMarks[] = {{4331297.0, 567555.6, 4633133.7}, {4027893.7, 307045.8, 4919474.9}, {3946489.4, 1316564.8, 4836751.5}};
const Eigen::Vector3d kVelocity(-0.0135, 0.0180, 0.0100);

std::vector<Eigen::Vector3d> read_xyz(const std::string& csv, std::vector<Eigen::Vector3d>* velocities = nullptr) {
  std::istringstream in(csv);
  std::string line;
  while (std::getline(in, line) && line.rfind('#', 0) == 0) {
  }  // comments above the header
  std::vector<Eigen::Vector3d> out;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream row(line);
    std::string cell;
    std::getline(row, cell, ',');  // id
    while (std::getline(row, cell, ',')) v.push_back(std::stod(cell));
    out.emplace_back(v[0], v[1], v[2]);
    if (velocities && v.size() >= 6) velocities->emplace_back(v[3], v[4], v[5]);
  }
  return out;
}

class TransformCli : public CliTest {
 protected:
  std::string marks_csv(bool with_velocity) const {
    std::string s = with_velocity ? "id,x_m,y_m,z_m,vx_m_per_year,vy_m_per_year,vz_m_per_year\n" : "id,x_m,y_m,z_m\n";
    int i = 0;
    for (const auto& m : kMarks) {
      s += "M" + std::to_string(i++) + "," + format_shortest(m.x()) + "," + format_shortest(m.y()) + "," + format_shortest(m.z());
      if (with_velocity) s += "," + format_shortest(kVelocity.x()) + "," + format_shortest(kVelocity.y()) + "," + format_shortest(kVelocity.z());
      s += "\n";
    }
    return s;
  }
};

TEST_F(TransformCli, SameEpochMatchesTheEpsgOperationInProjsDatabase) {
  const auto in = write("in.csv", marks_csv(false));
  const auto r = run("transform " + in.string() + " --from ITRF2014@2010.0 --to ITRF2020@2010.0 -o " + path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("step ITRF2014 -> ITRF2020 (reverse), ±0.001 m: IERS, Transfo-ITRF2020_TRFs.txt"), std::string::npos) << r.err;
  const ProjPipeline epsg(kEpsg9991);
  const auto got = read_xyz(slurp(path("out.csv")));
  ASSERT_EQ(got.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_LT((got[i] - epsg.forward(kMarks[i], 2010.0)).norm(), kProjAgreement_m);
  const auto side = nlohmann::json::parse(slurp(path("out.csv.geoanchor.json")));
  EXPECT_EQ(side["output"]["frame"], "ITRF2020");
  EXPECT_EQ(side["path"]["steps"][0]["from"], "ITRF2014");
  EXPECT_EQ(side["path"]["accuracy_m"], 0.001);
}

TEST_F(TransformCli, AnEpochChangeByThePlateMotionModelMatchesProj) {
  const auto in = write("in.csv", marks_csv(false));
  const auto r = run("transform " + in.string() + " --from ITRF2014@2010.0 --to ITRF2020@2024.5 --plate EURA --plate-model ITRF2014 -o " +
                     path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // PROJ: the EURA pole of its ITRF2014 file from 2010.0 to 2024.5, then EPSG:9991 at 2024.5.
  const ProjPipeline pmm("+proj=helmert +init=ITRF2014:EURA +t_epoch=2010.0"), epsg(kEpsg9991);
  const auto got = read_xyz(slurp(path("out.csv")));
  for (std::size_t i = 0; i < 3; ++i) {
    const Eigen::Vector3d expected = epsg.forward(pmm.forward(kMarks[i], 2024.5), 2024.5);
    EXPECT_LT((got[i] - expected).norm(), kProjAgreement_m) << i;
    EXPECT_GT((got[i] - kMarks[i]).norm(), 0.3);  // 14.5 years of Eurasia's ~2.5 cm/yr
  }
}

TEST_F(TransformCli, AMarkOnStableEurasiaStaysPutInEtrf2020AndMovesInItrf2020) {
  // ETRF2020 is ITRF2020 turned with stable Eurasia (EUREF TN1), so the
  // ITRF2020-PMM's EURA motion, taken over 14.5 years, nearly cancels there.
  // Left over: its origin rate bias (<= 0.9 mm/yr horizontally, by design
  // not in ETRF) and the 0.001 mas/yr between the two published poles.
  constexpr double kLeftOver_m = 0.015;
  const auto in = write("in.csv", marks_csv(false));
  const auto etrf = run("transform " + in.string() + " --from ITRF2020@2010.0 --to ETRF2020@2024.5 --plate EURA -o " + path("e.csv").string());
  ASSERT_EQ(etrf.exit_code, 0) << etrf.err;
  const auto etrf_start = run("transform " + in.string() + " --from ITRF2020@2010.0 --to ETRF2020@2010.0 -o " + path("e0.csv").string());
  ASSERT_EQ(etrf_start.exit_code, 0) << etrf_start.err;
  const auto itrf = run("transform " + in.string() + " --from ITRF2020@2010.0 --to ITRF2020@2024.5 --plate EURA -o " + path("i.csv").string());
  ASSERT_EQ(itrf.exit_code, 0) << itrf.err;
  const auto e = read_xyz(slurp(path("e.csv"))), e0 = read_xyz(slurp(path("e0.csv"))), i = read_xyz(slurp(path("i.csv")));
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_LT((e[k] - e0[k]).norm(), kLeftOver_m) << k;
    EXPECT_GT((i[k] - kMarks[k]).norm(), 0.3) << k;  // ~2.5 cm/yr for 14.5 years
  }
}

TEST_F(TransformCli, VelocitiesCarryThePointsAndAreTransformedWithThem) {
  const auto in = write("in.csv", marks_csv(true));
  const auto r = run("transform " + in.string() + " --from ITRF2014@2010.0 --to ITRF2020@2024.5 -o " + path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<Eigen::Vector3d> v_out;
  const auto got = read_xyz(slurp(path("out.csv")), &v_out);
  ASSERT_EQ(v_out.size(), 3u);
  const ProjPipeline epsg(kEpsg9991);
  for (std::size_t i = 0; i < 3; ++i) {
    // The mark where its velocity takes it by 2024.5, in ITRF2020 at 2024.5.
    EXPECT_LT((got[i] - epsg.forward(kMarks[i] + 14.5 * kVelocity, 2024.5)).norm(), kProjAgreement_m) << i;
    // Its velocity in ITRF2020: the time derivative of PROJ's output along the motion.
    const Eigen::Vector3d v_proj = (epsg.forward(kMarks[i] + kVelocity, 2011.0) - epsg.forward(kMarks[i] - kVelocity, 2009.0)) / 2.0;
    EXPECT_LT((v_out[i] - v_proj).norm(), kVelocityAgreement_m_per_year) << i;
  }
}

TEST_F(TransformCli, RefusesWhatItCannotDoAndLeavesNothing) {
  const auto in = write("in.csv", marks_csv(false));
  write("partial.csv", "id,x_m,y_m,z_m,vx_m_per_year\nA,4331297,567555.6,4633133.7,0.01\n");
  const struct {
    std::string args, message;
    int exit_code;
  } cases[] = {
      {"in.csv --from ITRF2014 --to ITRF2020", "--from ITRF2014: the transformation ITRF2014 → ITRF2020 is time-dependent", 2},
      {"in.csv --from ITRF2014@2010 --to ITRF2020@2020", "moving coordinates from 2010.0 to 2020.0 needs velocities", 2},
      {"in.csv --from ITRF2030@2010 --to ITRF2020", "frame ITRF2030 is not in geoanchor's catalog", 3},
      {"in.csv --from ITRF2014@2010 --to ITRF2020@2020 --plate MARS", "--plate MARS: expected a plate: AMUR", 2},
      {"in.csv --from ITRF2014@2010 --to ITRF2020@2020 --plate EURA --plate-model NNR", "--plate-model NNR: expected ITRF2020 or ITRF2014", 2},
      {"partial.csv --from ITRF2014@2010 --to ITRF2020", "velocities need all three columns", 3},
  };
  for (const auto& c : cases) {
    const auto r = shell("cd '" + dir_.string() + "' && " + exe() + " transform " + c.args + " -o out.csv");
    EXPECT_EQ(r.exit_code, c.exit_code) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
    EXPECT_EQ(leftovers({"in.csv", "partial.csv"}), std::vector<std::string>{}) << c.args;
  }
  (void)in;
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// Issue 13 point 4: a static (plate-fixed) frame needs no epoch to go to a
// dynamic frame at an epoch; the published time-dependent sets are evaluated
// at the target epoch, as EPSG and PROJ do. Compared with PROJ's
// proj_create_crs_to_crs on the same pair (geocentric CRSs, t = the target
// epoch) where PROJ 9.1.1's database has the operation, and with PROJ's
// helmert on the published parameters where it is newer (EPSG:10334).
TEST_F(TransformCli, Issue13_StaticFramesNeedNoEpochAndAgreeWithProj) {
  struct Case {
    const char* from;
    const char* to;
    double t;
    Eigen::Vector3d mark;
    std::string reference;  // PROJ: "crs:SRC:DST" or a pipeline
  };
  // NGS, HTDP user guide table 5: ITRF2020 to NAD83(2011), coordinate frame, epoch 2010.0 (EPSG:10334).
  const std::string epsg10334 =
      "+proj=helmert +x=1.00390 +y=-1.90961 +z=-0.54117 +rx=0.02678138 +ry=-0.00042027 +rz=0.01093206 "
      "+s=-0.00005109 +dx=0.00079 +dy=-0.00070 +dz=-0.00124 +drx=0.00006667 +dry=-0.00075744 +drz=-0.00005133 "
      "+ds=-0.00007201 +t_epoch=2010.0 +convention=coordinate_frame";
  const std::vector<Case> cases = {
      {"GDA94", "ITRF2014@2024.3", 2024.3, {-4052051.767, 4212836.215, -2545106.023}, "crs:EPSG:4938:EPSG:7789"},
      {"ETRF2000", "ITRF2020@2024.5", 2024.5, {4331297.0, 567555.6, 4633133.7}, "crs:EPSG:7930:EPSG:9988"},
      {"NAD83(2011)", "ITRF2020@2024.5", 2024.5, {-1283720.0, -4726030.0, 4074910.0}, epsg10334},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(std::string(c.from) + " -> " + c.to);
    const auto in = write("in.csv", "id,x_m,y_m,z_m\nA," + format_shortest(c.mark.x()) + "," + format_shortest(c.mark.y()) +
                                        "," + format_shortest(c.mark.z()) + "\n");
    const auto r = run("transform " + in.string() + " --from '" + c.from + "' --to '" + c.to + "' -o " +
                       path("out.csv").string() + " --overwrite");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto got = read_xyz(slurp(path("out.csv")));
    ASSERT_EQ(got.size(), 1u);
    Eigen::Vector3d expected;
    if (c.reference.rfind("crs:", 0) == 0) {
      const auto rest = c.reference.substr(4);
      const auto mid = rest.find(":EPSG");
      const auto pj = ProjPipeline::crs_to_crs(rest.substr(0, mid), rest.substr(mid + 1));
      expected = pj.forward(c.mark, c.t);
    } else {
      expected = ProjPipeline(c.reference).inverse(c.mark, c.t);  // the set is published ITRF2020 → NAD83(2011)
    }
    EXPECT_LT((got[0] - expected).norm(), kProjAgreement_m) << r.err;
  }
}

// The epoch change by a plate model carries the model's uncertainty (its
// published WRMS over the years), never ±0; the plate is never guessed.
TEST_F(TransformCli, Issue13_PlateMotionCarriesItsUncertaintyAndNoPlateIsGuessed) {
  const auto in = write("in.csv", marks_csv(false));
  const auto r = run("transform " + in.string() + " --from ITRF2014@2010.0 --to ITRF2020@2024.5 --plate EURA --plate-model ITRF2014 -o " +
                     path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto side = nlohmann::json::parse(slurp(path("out.csv.geoanchor.json")));
  // Altamimi et al. (2017) Table 1, EURA: WRMS 0.23 mm/yr east, 0.19 mm/yr north, over 14.5 years.
  const double expected = std::hypot(0.23, 0.19) * 1e-3 * 14.5;
  EXPECT_NEAR(side["epoch_propagation"]["accuracy_m"].get<double>(), expected, 1e-12);
  EXPECT_GT(side["path"]["stated_accuracy_m"].get<double>(), expected);
  const auto hint = run("transform " + in.string() + " --from ITRF2014@2010.0 --to ITRF2020@2024.5");
  EXPECT_EQ(hint.exit_code, 2);
  EXPECT_EQ(hint.err.find("e.g."), std::string::npos) << hint.err;
  EXPECT_NE(hint.err.find("the plate the points are on"), std::string::npos) << hint.err;
}

// Issue 13 point 5: each frame's geodetic coordinates are on its ellipsoid;
// --ellipsoid that contradicts a frame is refused.
TEST_F(TransformCli, Issue13_TheEllipsoidComesFromEachFrame) {
  const auto in = write("g.csv", "id,lat_deg,lon_deg,h_m\nA,47.0,8.0,500.0\n");
  const auto r = run("transform " + in.string() + " --from ITRF2014@2024.5 --to 'WGS84(G2139)@2024.5' -o " +
                     path("o.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto side = nlohmann::json::parse(slurp(path("o.csv.geoanchor.json")));
  EXPECT_EQ(side["input"]["ellipsoid"], "GRS80");
  EXPECT_EQ(side["output"]["ellipsoid"], "WGS84");
  const auto bad = run("transform " + in.string() + " --from ITRF2014@2024.5 --to ITRF2020@2024.5 --ellipsoid WGS84 -o " +
                       path("b.csv").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("contradicts frame ITRF2014"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(path("b.csv")));
}

// Issue 13 point 4: velocities carry the points in CRS mode too, and may be
// given in local east, north, up. Reference: the mark moved by its ECEF
// velocity to 2024.5, then EPSG:9991 at 2024.5 (PROJ), geodetic through
// PROJ's cart on GRS80; the local velocities rotated with GeographicLib's
// east/north/up matrix at the mark.
TEST_F(TransformCli, Issue13_VelocitiesInACrsAndInLocalAxes) {
  constexpr double kAngleAgreement_deg = 1e-9;  // the issue's bound for angles (0.1 mm of arc)
  const ProjPipeline epsg(kEpsg9991);
  const ProjPipeline geodetic("+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step +proj=cart +ellps=GRS80");
  const auto local_from_ecef = [](const Eigen::Vector3d& lonlath) {
    double x = 0, y = 0, z = 0;
    std::vector<double> m(9);  // local east, north, up -> geocentric, row-major
    GeographicLib::Geocentric(6378137.0, 1.0 / 298.257222101)  // GRS80 (EPSG:7019)
        .Forward(lonlath.y(), lonlath.x(), lonlath.z(), x, y, z, m);
    Eigen::Matrix3d r;
    r << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
    return Eigen::Matrix3d(r.transpose());
  };
  // Rows of a CSV that may state its CRS above the header.
  const auto rows = [](const std::string& csv) {
    std::istringstream in(csv);
    std::string line;
    std::vector<std::vector<double>> out;
    bool header = true;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      if (header) {
        header = false;
        continue;
      }
      std::vector<double> v;
      std::stringstream row(line);
      std::string cell;
      std::getline(row, cell, ',');  // id
      while (std::getline(row, cell, ',')) v.push_back(std::stod(cell));
      out.push_back(v);
    }
    return out;
  };
  std::string crs_csv = "id,lat_deg,lon_deg,h_m,vx_m_per_year,vy_m_per_year,vz_m_per_year\n";
  std::string local_csv = "id,x_m,y_m,z_m,ve_m_per_year,vn_m_per_year,vu_m_per_year\n";
  for (std::size_t i = 0; i < std::size(kMarks); ++i) {
    const Eigen::Vector3d g = geodetic.inverse(kMarks[i]);  // lon, lat, h
    crs_csv += "M" + std::to_string(i) + "," + format_shortest(g.y()) + "," + format_shortest(g.x()) + "," +
               format_shortest(g.z()) + "," + format_shortest(kVelocity.x()) + "," + format_shortest(kVelocity.y()) + "," +
               format_shortest(kVelocity.z()) + "\n";
    const Eigen::Vector3d v_local = local_from_ecef(g) * kVelocity;
    local_csv += "M" + std::to_string(i) + "," + format_shortest(kMarks[i].x()) + "," + format_shortest(kMarks[i].y()) + "," +
                 format_shortest(kMarks[i].z()) + "," + format_shortest(v_local.x()) + "," + format_shortest(v_local.y()) +
                 "," + format_shortest(v_local.z()) + "\n";
  }
  const auto crs_in = write("crs.csv", crs_csv), local_in = write("local.csv", local_csv);
  const auto a = run("transform " + crs_in.string() + " --from EPSG:7912@2010.0 --to EPSG:9989@2024.5 -o " + path("a.csv").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto b = run("transform " + local_in.string() + " --from ITRF2014@2010.0 --to ITRF2020@2024.5 -o " + path("b.csv").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const auto got_a = rows(slurp(path("a.csv"))), got_b = rows(slurp(path("b.csv")));
  ASSERT_EQ(got_a.size(), std::size(kMarks));
  ASSERT_EQ(got_b.size(), std::size(kMarks));
  for (std::size_t i = 0; i < std::size(kMarks); ++i) {
    SCOPED_TRACE(i);
    const Eigen::Vector3d x = epsg.forward(kMarks[i] + 14.5 * kVelocity, 2024.5);
    const Eigen::Vector3d v = (epsg.forward(kMarks[i] + kVelocity, 2011.0) - epsg.forward(kMarks[i] - kVelocity, 2009.0)) / 2.0;
    const Eigen::Vector3d g = geodetic.inverse(x);
    // The CRS input is the marks' geodetic coordinates as PROJ gave them
    // (its inverse cart is a Bowring step, µm off at these marks' 14 km
    // heights): PROJ's ECEF of those is where they start.
    const Eigen::Vector3d start = geodetic.forward(geodetic.inverse(kMarks[i]));
    const Eigen::Vector3d g_crs = geodetic.inverse(epsg.forward(start + 14.5 * kVelocity, 2024.5));
    EXPECT_NEAR(got_a[i][0], g_crs.y(), kAngleAgreement_deg);
    EXPECT_NEAR(got_a[i][1], g_crs.x(), kAngleAgreement_deg);
    EXPECT_NEAR(got_a[i][2], g_crs.z(), kProjAgreement_m);
    EXPECT_LT((Eigen::Vector3d(got_a[i][3], got_a[i][4], got_a[i][5]) - v).norm(), kVelocityAgreement_m_per_year);
    EXPECT_LT((Eigen::Vector3d(got_b[i][0], got_b[i][1], got_b[i][2]) - x).norm(), kProjAgreement_m);
    const Eigen::Vector3d v_local = local_from_ecef(g) * v;  // at the moved mark, in ITRF2020 (GRS80)
    EXPECT_LT((Eigen::Vector3d(got_b[i][3], got_b[i][4], got_b[i][5]) - v_local).norm(), kVelocityAgreement_m_per_year);
  }
  const auto side = nlohmann::json::parse(slurp(path("b.csv.geoanchor.json")));
  EXPECT_EQ(side["epoch_propagation"]["by"], "velocities (local east, north, up)");
  // A CRS's conversions at both ends are recorded as convert records them.
  const auto crs_side = nlohmann::json::parse(slurp(path("a.csv.geoanchor.json")));
  ASSERT_EQ(crs_side["crs_operations"].size(), 2u);
  EXPECT_EQ(crs_side["crs_operations"][0]["candidates"][0]["points"], std::size(kMarks));
  // Both sets at once, or a set missing a column, is refused.
  const auto both = write("both.csv", "id,x_m,y_m,z_m,vx_m_per_year,vy_m_per_year,vz_m_per_year,ve_m_per_year,vn_m_per_year,vu_m_per_year\n"
                                      "A,4331297,567555.6,4633133.7,0,0,0,0,0,0\n");
  const auto r = run("transform " + both.string() + " --from ITRF2014@2010.0 --to ITRF2020@2024.5 -o " + path("c.csv").string());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("give one set"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("c.csv")));
  // A velocity in another unit would pass through unmoved: refused by name.
  const auto mm = write("mm.csv", "id,x_m,y_m,z_m,ve_mm_per_year,vn_mm_per_year,vu_mm_per_year\nA,4331297,567555.6,4633133.7,1,2,3\n");
  const auto u = run("transform " + mm.string() + " --from ITRF2014@2020.0 --to ITRF2020@2020.0 -o " + path("d.csv").string());
  EXPECT_EQ(u.exit_code, 3);
  EXPECT_NE(u.err.find("'ve_mm_per_year' reads as a velocity"), std::string::npos) << u.err;
  EXPECT_FALSE(std::filesystem::exists(path("d.csv")));
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// Issue 40 point 1: a plate-fixed frame's coordinates move too (intraplate
// velocities), so an epoch asked for on its side is honoured: the point
// moves by its velocity in the source frame and the time-dependent set is
// evaluated at the target epoch, as NGS's HTDP does. References: PROJ's
// helmert with EPSG:8970 (ITRF2014 to NAD83(2011), NGS) at the propagated
// epoch, and NGS's HTDP 3.6.0 itself.
constexpr double kPropagatedAgreement_m = 0.5e-3;             // the issue's bound against cct
constexpr double kOutputVelocityAgreement_m_per_year = 1e-6;  // the path's rates times the years: 1e-9 m/yr
constexpr double kHtdpAgreement_m = 0.1e-3;                   // HTDP's values below to 0.01 mm; the issue asks 1 mm
constexpr double kHtdpVelocityAgreement_m_per_year = 0.01e-3;

// EPSG:8970 to the digits of EPSG's record today and of HTDP (htdp.f 3.6.0:
// ITRF94 -> NAD83(2011) less ITRF94 -> ITRF2014); PROJ 9.1.1's database
// rounds them (tz -0.5416 m, dtz -0.0014 m/yr: 0.45 mm in ten years).
const char* kEpsg8970 =
    "+proj=helmert +x=1.0053 +y=-1.90921 +z=-0.54157 +rx=0.02678138 +ry=-0.00042027 +rz=0.01093206 +s=0.00036891 "
    "+dx=0.00079 +dy=-0.0006 +dz=-0.00144 +drx=6.667e-05 +dry=-0.00075744 +drz=-5.133e-05 +ds=-7.201e-05 +t_epoch=2010 "
    "+convention=coordinate_frame";

// A mark near Los Angeles with a velocity of the Pacific plate's size in
// ITRF2014, and one near Washington, D.C. (ECEF, m and m/yr, rounded).
struct MovingMark {
  Eigen::Vector3d x, v;
};
const MovingMark kUsMarks[] = {{{-2494360.0, -4656410.0, 3553450.0}, {-0.0320, 0.0210, 0.0090}},
                               {{1115450.0, -4843290.0, 3983240.0}, {-0.0145, -0.0010, 0.0035}}};

std::string moving_csv(const MovingMark* marks, std::size_t n) {
  std::string s = "id,x_m,y_m,z_m,vx_m_per_year,vy_m_per_year,vz_m_per_year\n";
  for (std::size_t i = 0; i < n; ++i) {
    s += "M" + std::to_string(i);
    for (const auto& c : {marks[i].x, marks[i].v}) {
      for (int k = 0; k < 3; ++k) s += "," + format_shortest(c(k));
    }
    s += "\n";
  }
  return s;
}

TEST_F(TransformCli, Issue40_PlateFixedEpochsAreHonouredWithVelocities) {
  const ProjPipeline epsg(kEpsg8970);
  const auto in = write("in.csv", moving_csv(kUsMarks, 2));
  const auto r = run("transform " + in.string() + " --from ITRF2014@2020.0 --to 'NAD83(2011)@2010.0' -o " +
                     path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("not used"), std::string::npos) << r.err;
  std::vector<Eigen::Vector3d> v_got;
  const auto got = read_xyz(slurp(path("out.csv")), &v_got);
  ASSERT_EQ(got.size(), 2u);
  ASSERT_EQ(v_got.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& m = kUsMarks[i];
    const Eigen::Vector3d expected = epsg.forward(m.x - 10.0 * m.v, 2010.0);  // to 2010.0 in ITRF2014, then EPSG:8970
    EXPECT_LT((got[i] - expected).norm(), kPropagatedAgreement_m) << i;
    // The output velocity: the motion through the time-dependent set.
    const Eigen::Vector3d v_expected = (epsg.forward(m.x - 9.0 * m.v, 2011.0) - epsg.forward(m.x - 11.0 * m.v, 2009.0)) / 2.0;
    EXPECT_LT((v_got[i] - v_expected).norm(), kOutputVelocityAgreement_m_per_year) << i;
    // Not the old answer, the set evaluated at 2020.0 with the epoch ignored:
    // 10 years of intraplate motion, 2 cm in the east, 0.3 m in the west.
    EXPECT_GT((got[i] - epsg.forward(m.x, 2020.0)).norm(), 0.01) << i;
  }
  const auto side = nlohmann::json::parse(slurp(path("out.csv.geoanchor.json")));
  EXPECT_EQ(side["output"]["epoch"], 2010.0);
  EXPECT_EQ(side["input"]["epoch"], 2020.0);

  // The reverse: NAD83(2011)@2010.0 with NAD83 velocities to ITRF2014@2020.0.
  const MovingMark nad83[] = {{got[0], v_got[0]}, {got[1], v_got[1]}};
  const auto back_in = write("nad83.csv", moving_csv(nad83, 2));
  const auto b = run("transform " + back_in.string() + " --from 'NAD83(2011)@2010.0' --to ITRF2014@2020.0 -o " +
                     path("back.csv").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  std::vector<Eigen::Vector3d> v_back;
  const auto back = read_xyz(slurp(path("back.csv")), &v_back);
  ASSERT_EQ(back.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const Eigen::Vector3d expected = epsg.inverse(nad83[i].x + 10.0 * nad83[i].v, 2020.0);  // to 2020.0 in NAD83(2011)
    EXPECT_LT((back[i] - expected).norm(), kPropagatedAgreement_m) << i;
    EXPECT_LT((back[i] - kUsMarks[i].x).norm(), kPropagatedAgreement_m) << i;  // the round trip
    EXPECT_LT((v_back[i] - kUsMarks[i].v).norm(), kOutputVelocityAgreement_m_per_year) << i;
  }
}

TEST_F(TransformCli, Issue40_PlateFixedEpochChangeWithoutVelocitiesIsRefusedOrAssumedAloud) {
  const ProjPipeline epsg(kEpsg8970);
  const auto& m = kUsMarks[0];
  const auto in = write("in.csv", "id,x_m,y_m,z_m\nM0," + format_shortest(m.x.x()) + "," + format_shortest(m.x.y()) + "," +
                                      format_shortest(m.x.z()) + "\n");
  for (const std::string& pair : {std::string("--from ITRF2014@2020.0 --to 'NAD83(2011)@2010.0'"),
                                  std::string("--from 'NAD83(2011)@2010.0' --to ITRF2014@2020.0")}) {
    const auto r = run("transform " + in.string() + " " + pair + " -o " + path("out.csv").string());
    EXPECT_EQ(r.exit_code, 2) << pair << ": " << r.err;
    EXPECT_NE(r.err.find("E_EPOCH_PROPAGATION"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--assume-zero-velocity"), std::string::npos) << r.err;
    EXPECT_EQ(leftovers({"in.csv"}), std::vector<std::string>{}) << pair;
  }
  // Said in every output: the terminal, the CSV and the sidecar.
  const auto r = run("transform " + in.string() + " --from ITRF2014@2020.0 --to 'NAD83(2011)@2010.0' --assume-zero-velocity -o " +
                     path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: --assume-zero-velocity"), std::string::npos) << r.err;
  const std::string csv = slurp(path("out.csv"));
  EXPECT_EQ(csv.rfind("# geoanchor: --assume-zero-velocity", 0), 0u) << csv;
  const auto got = read_xyz(csv);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_LT((got[0] - epsg.forward(m.x, 2020.0)).norm(), kPropagatedAgreement_m);
  const auto side = nlohmann::json::parse(slurp(path("out.csv.geoanchor.json")));
  EXPECT_EQ(side["epoch_propagation"]["by"], "assumed_zero_velocity");
  EXPECT_EQ(side["epoch_propagation"]["plate_fixed_frame"], "NAD83(2011)");
  EXPECT_EQ(side["output"]["epoch"], 2010.0);
  // Where it says nothing, it is refused: two dynamic frames.
  const auto dyn = run("transform " + in.string() + " --from ITRF2014@2020.0 --to ITRF2020@2010.0 --assume-zero-velocity -o " +
                       path("dyn.csv").string());
  EXPECT_EQ(dyn.exit_code, 2) << dyn.err;
  EXPECT_NE(dyn.err.find("both dynamic frames"), std::string::npos) << dyn.err;
  EXPECT_FALSE(std::filesystem::exists(path("dyn.csv")));
  // The earlier rule stays: a static frame named without an epoch takes the other side's.
  const auto same = run("transform " + in.string() + " --from ITRF2014@2020.0 --to 'NAD83(2011)' -o " + path("same.csv").string());
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_LT((read_xyz(slurp(path("same.csv")))[0] - epsg.forward(m.x, 2020.0)).norm(), kPropagatedAgreement_m);
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// Issue 40 point 1 against NGS's HTDP 3.6.0 (github.com/noaa-ngs/HTDP,
// commit 59fdbe6b; option "transform positions and velocities", the
// velocities given, no earthquake model needed: the marks are outside the
// 2010 and 2019 events' radii). Its own example outputs (Ex5_trans.out,
// Ex7_vel_trans.out) were reproduced by the same build; its transformation
// of TTCD, TORP and SIO3 at 2010.0 matches NGS's published coordinate sheets
// to the mm. P1 near Modesto (CMOD), P2 at 37°N 122°W (HTDP's example 7
// point), P3 TTCD, Virginia. Positions in m, velocities in m/yr.
struct HtdpCase {
  Eigen::Vector3d x, v, x_expected, v_expected;
};
const HtdpCase kHtdpForward[] = {  // ITRF2014@2020.0 -> NAD83(2011)@2010.0
    {{-2604474.5860, -4334578.0210, 3874014.6420}, {-0.01848, 0.00715, -0.00242},
     {-2604473.61870, -4334579.36226, 3874014.69418}, {-0.002198, 0.007466, 0.006826}},
    {{-2702597.2968, -4325059.7721, 3817411.2147}, {-0.02511, 0.03224, 0.01840},
     {-2702596.26286, -4325061.36637, 3817411.05765}, {-0.009031, 0.032513, 0.028007}},
    {{1097052.9840, -4897222.4110, 3923142.6200}, {-0.01460, -0.00070, 0.00300},
     {1097053.88415, -4897223.86378, 3923142.68349}, {0.001736, 0.000594, -0.001168}},
};
const HtdpCase kHtdpReverse[] = {  // NAD83(2011)@2010.0 -> ITRF2014@2020.0
    {{-2604473.6187, -4334579.3623, 3874014.6942}, {-0.00220, 0.00747, 0.00683},
     {-2604474.58600, -4334578.02100, 3874014.64207}, {-0.018482, 0.007154, -0.002416}},
    {{-2702596.2629, -4325061.3664, 3817411.0577}, {-0.00903, 0.03251, 0.02801},
     {-2702597.29681, -4325059.77215, 3817411.21479}, {-0.025109, 0.032237, 0.018403}},
    {{1097053.8842, -4897223.8638, 3923142.6835}, {0.00174, 0.00059, -0.00117},
     {1097052.98411, -4897222.41106, 3923142.61998}, {-0.014596, -0.000704, 0.002998}},
};

TEST_F(TransformCli, Issue40_PlateFixedEpochsAgreeWithHtdp) {
  struct Direction {
    const HtdpCase* cases;
    const char* from;
    const char* to;
  };
  // By frame names, and by the geocentric CRSs (EPSG:7789 ITRF2014, EPSG:6317
  // NAD83(2011)), whose static side's epoch was refused as unused.
  for (const auto& d : {Direction{kHtdpForward, "ITRF2014@2020.0", "'NAD83(2011)@2010.0'"},
                        Direction{kHtdpReverse, "'NAD83(2011)@2010.0'", "ITRF2014@2020.0"},
                        Direction{kHtdpForward, "EPSG:7789@2020.0", "EPSG:6317@2010.0"},
                        Direction{kHtdpReverse, "EPSG:6317@2010.0", "EPSG:7789@2020.0"}}) {
    SCOPED_TRACE(std::string(d.from) + " -> " + d.to);
    std::vector<MovingMark> marks;
    for (std::size_t i = 0; i < 3; ++i) marks.push_back({d.cases[i].x, d.cases[i].v});
    const auto in = write("in.csv", moving_csv(marks.data(), marks.size()));
    const auto r = run("transform " + in.string() + " --from " + d.from + " --to " + d.to + " -o " + path("out.csv").string() +
                       " --overwrite");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::vector<Eigen::Vector3d> v;
    const auto x = read_xyz(slurp(path("out.csv")), &v);
    ASSERT_EQ(x.size(), 3u);
    ASSERT_EQ(v.size(), 3u);
    testing::WorstCase position, velocity;
    for (std::size_t i = 0; i < 3; ++i) {
      position.add((x[i] - d.cases[i].x_expected).norm(), i);
      velocity.add((v[i] - d.cases[i].v_expected).norm(), i);
    }
    EXPECT_WORST_WITHIN(position, kHtdpAgreement_m) << "(m)";
    EXPECT_WORST_WITHIN(velocity, kHtdpVelocityAgreement_m_per_year) << "(m/yr)";
  }
}

}  // namespace
}  // namespace geoanchor
