// The frame catalog against PROJ: the IERS parameter sets between ITRF
// realizations (PROJ's own ITRF2014 and ITRF2008 init files, from the same
// IERS tables, and the EPSG operations in PROJ's database for ITRF2020),
// the ITRF2014 plate motion model (PROJ's ITRF2014 file, from Altamimi et
// al. 2017), and the path search.

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor::geodesy {
namespace {

using testing::ProjPipeline;

// Both sides evaluate the same small-angle Helmert in float64 on
// coordinates of 6.4e6 m: they agree to rounding (~1e-9 m); the issue asks
// for 1e-6 m.
constexpr double kProjAgreement_m = 1e-6;
constexpr double kRoundTrip_m = 1e-8;  // a chain of exact inverses, float64

const double kEpochs[] = {1995.0, 2010.0, 2015.0, 2024.5};

std::vector<EcefPosition> stations(std::size_t n) {
  std::mt19937_64 rng(2020);
  std::uniform_real_distribution<double> u(-1.0, 1.0), h(-100.0, 5000.0);
  std::vector<EcefPosition> out;
  while (out.size() < n) {
    const Eigen::Vector3d d(u(rng), u(rng), u(rng));
    if (d.norm() < 0.1 || d.norm() > 1.0) continue;
    out.emplace_back(Eigen::Vector3d(d.normalized() * (6371000.0 + h(rng))));
  }
  return out;
}

// PROJ reads "EPSG:n" as a CRS; an operation from its database by URN.
std::string operation_urn(const std::string& epsg_code) {
  return "urn:ogc:def:coordinateOperation:EPSG::" + epsg_code.substr(5);
}

void expect_path_matches_proj(const std::string& from, const std::string& to, const std::string& proj) {
  const FramePath path = find_frame_path(from, to, "test");
  ASSERT_EQ(path.steps.size(), 1u) << from << " -> " << to;
  const ProjPipeline reference(proj);
  for (double t : kEpochs) {
    for (const auto& x : stations(50)) {
      const Eigen::Vector3d expected = reference.forward(x.m, t);
      EXPECT_LT((path.apply(x, DecimalYear{t}).m - expected).norm(), kProjAgreement_m) << from << " -> " << to << " at " << t;
    }
  }
}

TEST(FrameCatalog, Itrf2014ToEarlierRealizationsAgreeWithProjsItrf2014InitFile) {
  // PROJ's ITRF2014 file transcribes the ITRF97 row with two typos
  // ("+d=0.0038", "+dx0.0001"), so PROJ applies no scale and no x rate
  // there; ITRF96 and ITRF94 have the same published values and are checked
  // (docs/frames.md).
  for (const char* f : {"ITRF2008", "ITRF2005", "ITRF2000", "ITRF96", "ITRF94", "ITRF93", "ITRF92", "ITRF91", "ITRF90",
                        "ITRF89", "ITRF88"}) {
    expect_path_matches_proj("ITRF2014", f, std::string("+proj=helmert +init=ITRF2014:") + f);
  }
}

TEST(FrameCatalog, Itrf2008ToEarlierRealizationsAgreeWithProjsItrf2008InitFile) {
  // PROJ's ITRF2008 file has Tz = -3.86 mm for ITRF93 where the IERS table
  // has -38.6 mm, and leaves out ITRF88's Rx = 0.10 mas (3 mm at the
  // surface) (docs/frames.md); those rows are checked against EPSG below.
  for (const char* f : {"ITRF2005", "ITRF2000", "ITRF97", "ITRF96", "ITRF94", "ITRF92", "ITRF91", "ITRF90", "ITRF89"}) {
    expect_path_matches_proj("ITRF2008", f, std::string("+proj=helmert +init=ITRF2008:") + f);
  }
}

TEST(FrameCatalog, EveryParameterSetAgreesWithItsEpsgOperationInProjsDatabase) {
  // Each set names the EPSG operation that publishes it (the IERS tables
  // reversed, EUREF's in the same direction); PROJ's database is an
  // independent transcription.
  std::size_t compared = 0;
  for (const auto& edge : catalog_transformations()) {
    if (edge.epsg.empty()) continue;  // ETRF2020: newer than PROJ 9.1.1's EPSG v10.076 (checked below)
    // EPSG:8048 is defined in the geographic 2D domain, which PROJ applies to
    // latitude and longitude, not to ECEF (checked below).
    if (edge.epsg == "EPSG:8048") continue;
    const FramePath path = edge.epsg_reversed ? FramePath{edge.to, edge.from, {FramePathStep{&edge, true}}}
                                              : FramePath{edge.from, edge.to, {FramePathStep{&edge, false}}};
    // EPSG:8970 (ITRF2014 to NAD83(2011)) is held to HTDP's digits, as
    // EPSG's record now gives them; PROJ 9.1.1's database rounds them (tz
    // -0.5416 m, dtz -1.4 mm/yr): that transcription is checked to its
    // rounding, 0.75 mm at 1995, and the digits against HTDP 3.6.0 in
    // transform_cli_test.cpp.
    const bool rounded_in_proj = edge.epsg == "EPSG:8970";
    constexpr double kEpsg8970Rounding_m = 1e-3;
    const ProjPipeline reference(operation_urn(edge.epsg));
    const ProjPipeline full_digits(
        "+proj=helmert +x=1.0053 +y=-1.90921 +z=-0.54157 +rx=0.02678138 +ry=-0.00042027 +rz=0.01093206 +s=0.00036891 "
        "+dx=0.00079 +dy=-0.0006 +dz=-0.00144 +drx=6.667e-05 +dry=-0.00075744 +drz=-5.133e-05 +ds=-7.201e-05 +t_epoch=2010 "
        "+convention=coordinate_frame");
    for (double t : kEpochs) {
      for (const auto& x : stations(10)) {
        const Eigen::Vector3d got = path.apply(x, DecimalYear{t}).m;
        EXPECT_LT((got - reference.forward(x.m, t)).norm(), rounded_in_proj ? kEpsg8970Rounding_m : kProjAgreement_m)
            << edge.epsg << ": " << path.from << " -> " << path.to << " at " << t;
        if (rounded_in_proj) {
          EXPECT_LT((got - full_digits.forward(x.m, t)).norm(), kProjAgreement_m) << "EPSG:8970 to HTDP's digits at " << t;
        }
      }
    }
    ++compared;
  }
  EXPECT_EQ(compared, 36u + 14u + 17u);  // 13 + 12 + 11 IERS rows, 14 EUREF, 17 of the 18 NGS/NRCan/ICSM/NGA rows
}

TEST(FrameCatalog, Gda94ToGda2020IsTheTechnicalManualsSevenParameterSet) {
  // ICSM, GDA2020 Technical Manual: tx 61.55, ty -10.87, tz -40.19 mm,
  // rx -39.4924, ry -32.7221, rz -32.8979 mas, ds -9.994 ppb, coordinate
  // frame convention — written out for PROJ, which applies it in ECEF.
  const ProjPipeline manual("+proj=helmert +x=0.06155 +y=-0.01087 +z=-0.04019 +rx=-0.0394924 +ry=-0.0327221 "
                            "+rz=-0.0328979 +s=-0.009994 +convention=coordinate_frame");
  const FramePath path = find_frame_path("GDA94", "GDA2020", "test");
  ASSERT_EQ(path.steps.size(), 1u);
  EXPECT_FALSE(path.time_dependent());
  for (const auto& x : stations(50)) {
    EXPECT_LT((path.apply(x, DecimalYear{2020.0}).m - manual.forward(x.m)).norm(), kProjAgreement_m);
    // Static: the epoch does not matter.
    EXPECT_EQ(path.apply(x, DecimalYear{1994.0}).m, path.apply(x, DecimalYear{2020.0}).m);
  }
}

TEST(FrameCatalog, Etrf2020IsEpsg10574ComposedWithItrf2014ToItrf2020) {
  // EPSG:10574 "ITRF2014 to ETRF2020 (1)" (EPSG dataset v10.0xx, 2023;
  // not in PROJ 9.1.1's database), epoch 2015.0: T = (1.4, 0.9, -1.4) mm,
  // R = (2.236, 13.494, -19.578) mas, D = 0.42 ppb; rates (0, 0.1, -0.2)
  // mm/yr, (0.086, 0.519, -0.753) mas/yr, 0 ppb/yr.
  const ProjPipeline epsg10574(
      "+proj=helmert +x=0.0014 +y=0.0009 +z=-0.0014 +rx=0.002236 +ry=0.013494 +rz=-0.019578 +s=0.00042 "
      "+dx=0 +dy=0.0001 +dz=-0.0002 +drx=0.000086 +dry=0.000519 +drz=-0.000753 +ds=0 +t_epoch=2015.0 "
      "+convention=position_vector");
  const FramePath path = find_frame_path("ITRF2014", "ETRF2020", "test");
  ASSERT_EQ(path.steps.size(), 2u);
  for (double t : kEpochs) {
    for (const auto& x : stations(20)) {
      // The composition of two small-angle Helmerts and EPSG's single set
      // differ by second-order terms: |R|·|ΔT| + D·R·x ≈ 1e-10 · 6.4e6 m.
      EXPECT_LT((path.apply(x, DecimalYear{t}).m - epsg10574.forward(x.m, t)).norm(), kProjAgreement_m) << t;
    }
  }
}

TEST(FrameCatalog, EarlierRealizationsToItrf2020AgreeWithTheEpsgOperationsInProjsDatabase) {
  // EPSG publishes the IERS ITRF2020 table in the opposite direction
  // (EPSG:9991 ITRF2014 to ITRF2020, ..., EPSG:10105 ITRF88 to ITRF2020).
  const struct {
    const char* frame;
    const char* epsg;
  } kCases[] = {{"ITRF2014", "EPSG:9991"}, {"ITRF2008", "EPSG:9992"}, {"ITRF2005", "EPSG:9993"}, {"ITRF2000", "EPSG:9994"},
                {"ITRF97", "EPSG:9995"},   {"ITRF96", "EPSG:9996"},   {"ITRF94", "EPSG:9997"},   {"ITRF93", "EPSG:9998"},
                {"ITRF92", "EPSG:9999"},   {"ITRF91", "EPSG:10100"},  {"ITRF90", "EPSG:10103"},  {"ITRF89", "EPSG:10104"},
                {"ITRF88", "EPSG:10105"}};
  for (const auto& c : kCases) {
    const FramePath path = find_frame_path(c.frame, "ITRF2020", "test");
    ASSERT_EQ(path.steps.size(), 1u);
    EXPECT_TRUE(path.steps[0].reverse);
    EXPECT_EQ(path.steps[0].edge->epsg, c.epsg);
    expect_path_matches_proj(c.frame, "ITRF2020", operation_urn(c.epsg));
  }
  // And the other way, through PROJ's inverse.
  const ProjPipeline epsg9991(operation_urn("EPSG:9991"));
  const FramePath down = find_frame_path("ITRF2020", "ITRF2014", "test");
  for (double t : kEpochs) {
    for (const auto& x : stations(20)) {
      EXPECT_LT((down.apply(x, DecimalYear{t}).m - epsg9991.inverse(x.m, t)).norm(), kProjAgreement_m);
    }
  }
}

TEST(FrameCatalog, TheItrf2014PlateMotionModelAgreesWithProjsItrf2014File) {
  // PROJ applies a pole as a rotation rate: x(t) = x + (t − t0) ω × x.
  for (const char* plate : {"ANTA", "ARAB", "AUST", "EURA", "INDI", "NAZC", "NOAM", "NUBI", "PCFC", "SOAM", "SOMA"}) {
    const auto model = find_plate_motion_model("ITRF2014", plate);
    ASSERT_TRUE(model.has_value()) << plate;
    const ProjPipeline pmm(std::string("+proj=helmert +init=ITRF2014:") + plate + " +t_epoch=2010.0");
    for (const auto& x : stations(20)) {
      const Eigen::Vector3d v_proj = pmm.forward(x.m, 2011.0) - pmm.forward(x.m, 2010.0);
      EXPECT_LT((model->velocity_m_per_year(x) - v_proj).norm(), 1e-9) << plate;  // m/yr, float64 rounding
    }
  }
  EXPECT_FALSE(find_plate_motion_model("ITRF2014", "MARS").has_value());
}

TEST(FrameCatalog, TheItrf2020PlateMotionModelAgreesWithEurefAndKeepsItsBiasHorizontal) {
  // EUREF's ITRF2020 → ETRF2020 rotation rates (0.086, 0.519, −0.753) mas/yr
  // (EPSG:10574) turn stable Eurasia back: the EURA pole of the ITRF2020-PMM
  // is their negative to the published rounding.
  constexpr double kPublishedRounding_mas_per_year = 0.0015;
  const auto eura = find_plate_motion_model("ITRF2020", "EURA");
  ASSERT_TRUE(eura.has_value());
  EXPECT_WORST_WITHIN(testing::max_abs_component(eura->omega_mas_per_year + Eigen::Vector3d(0.086, 0.519, -0.753)), kPublishedRounding_mas_per_year);
  // The origin rate bias adds to the horizontal velocity only.
  for (const auto& m : plate_motion_models()) {
    if (m.frame != "ITRF2020") continue;
    for (const auto& x : stations(10)) {
      const Eigen::Vector3d v = m.velocity_m_per_year(x);
      const Eigen::Vector3d w = m.omega_mas_per_year * Angle::milliarcseconds(1.0).rad();
      const Eigen::Vector3d rotation = w.cross(x.m);
      const Eigen::Vector3d bias = v - rotation;
      EXPECT_LE(bias.norm(), m.origin_rate_bias_m_per_year.norm() + 1e-15);
      EXPECT_GT(bias.norm(), 0.0);
      // Horizontal: orthogonal to the ellipsoidal normal, which is within 0.2° of the radial direction.
      EXPECT_LT(std::abs(bias.dot(x.m.normalized())), m.origin_rate_bias_m_per_year.norm() * std::sin(0.2 * M_PI / 180.0)) << m.plate;
    }
  }
  EXPECT_EQ(std::count_if(plate_motion_models().begin(), plate_motion_models().end(),
                          [](const PlateMotionModel& m) { return m.frame == "ITRF2020"; }),
            13);
}

TEST(FrameCatalog, Wgs84G2296IsAlignedWithItrf2020AsNgaAnnounced) {
  // NGA press release NGA-U-2023-02846 (2024-01-02): WGS 84 (G2296) is
  // aligned with ITRF2020. The tie is the identity; to G2139 the path runs
  // through the IERS's ITRF2020 → ITRF2014 set.
  const auto tie = find_frame_path("WGS84(G2296)", "ITRF2020", "test");
  ASSERT_EQ(tie.steps.size(), 1u);
  EXPECT_NE(tie.steps[0].edge->source.find("NGA-U-2023-02846"), std::string::npos);
  const EcefPosition x(Eigen::Vector3d(4027894.006, 307045.600, 4919474.910));
  EXPECT_EQ(tie.apply(x, DecimalYear{2024.0}).m, x.m);
  const auto to_g2139 = find_frame_path("WGS84(G2296)", "WGS84(G2139)", "test");
  const auto itrf = find_frame_path("ITRF2020", "ITRF2014", "test");
  EXPECT_LT((to_g2139.apply(x, DecimalYear{2024.0}).m - itrf.apply(x, DecimalYear{2024.0}).m).norm(), 1e-9);
}

TEST(FramePathSearch, FindsDirectEdgesHubsAndRefusesUnknownFrames) {
  EXPECT_TRUE(find_frame_path("ITRF2014", "ITRF2014", "test").steps.empty());
  // Realizations listed only under older tables reach each other through a hub.
  const FramePath two = find_frame_path("ITRF88", "ITRF2005", "test");
  ASSERT_EQ(two.steps.size(), 2u);
  EXPECT_EQ(two.steps[0].from(), "ITRF88");
  EXPECT_EQ(two.steps[1].to(), "ITRF2005");
  EXPECT_NEAR(two.accuracy_m(), std::sqrt(2.0) * 0.01, 1e-12);
  EXPECT_NE(two.describe().find("reverse of"), std::string::npos);
  try {
    find_frame_path("ITRF2030", "ITRF2014", "--from");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_NE(std::string(e.what()).find("--from: frame ITRF2030 is not in geoanchor's catalog; it knows ETRF2000, ETRF2005"), std::string::npos)
        << e.what();
  }
}

TEST(FramePathSearch, ThereAndBackClosesAndTheTablesAgreeWithinTheirStatedAccuracy) {
  const FramePath there = find_frame_path("ITRF2020", "ITRF88", "test"), back = find_frame_path("ITRF88", "ITRF2020", "test");
  // ITRF2014 → ITRF2008 directly and through ITRF2020 are two IERS
  // estimates of the same transformation; they differ by less than the
  // stated ±1 cm (in practice a few millimetres).
  const FramePath direct = find_frame_path("ITRF2014", "ITRF2008", "test");
  const FramePath via{"ITRF2014", "ITRF2008",
                      {find_frame_path("ITRF2014", "ITRF2020", "test").steps[0], find_frame_path("ITRF2020", "ITRF2008", "test").steps[0]}};
  for (const auto& x : stations(50)) {
    for (double t : kEpochs) {
      EXPECT_LT((back.apply(there.apply(x, DecimalYear{t}), DecimalYear{t}).m - x.m).norm(), kRoundTrip_m);
      EXPECT_LT((direct.apply(x, DecimalYear{t}).m - via.apply(x, DecimalYear{t}).m).norm(), 0.01);
    }
  }
}

}  // namespace
}  // namespace geoanchor::geodesy
