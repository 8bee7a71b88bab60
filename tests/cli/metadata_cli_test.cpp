// Issue 16 points 2 and 3 through the command line: the map metadata
// contract in what fit, adjust --estimate-helmert and apply write, the
// survey-metadata file, and GNSS solution types (control sets, network
// measurements, LAS extra bytes). Expected counts and shares are worked
// out by hand from the fixtures (stated beside each check).

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>

#include "cli_support.hpp"
#include "las_builder.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::CliTest;
using testing::RunResult;
using testing::slurp;

const std::string kFixtures = GEOANCHOR_FIXTURES_DIR;

class MetadataCli : public CliTest {
 protected:
  // geoanchor with `args`, run in the test's folder (relative names are the folder's).
  RunResult here(const std::string& args) const { return shell("cd '" + dir_.string() + "' && " + exe() + " " + args); }
  json read_json(const std::string& name) const { return json::parse(slurp(path(name))); }
  // A format-6 ENU tile of `codes.size()` points around the LSZH
  // aerodrome reference point with one extra byte, "gnss_solution" =
  // codes[i], and its sidecar (ITRF2014@2024.5, `survey` as its survey key).
  void gnss_tile(const std::string& name, const std::vector<std::uint8_t>& codes, const std::string& survey) const {
    testing::LasBuild b;
    b.point_format = 6;
    b.extra_bytes = 1;
    std::vector<std::uint8_t> d(192, 0);
    d[2] = 1;  // uint8
    std::memcpy(d.data() + 4, "gnss_solution", 13);
    b.vlrs.push_back({"LASF_Spec", 4, "extra bytes", d});
    for (std::size_t i = 0; i < codes.size(); ++i) {
      b.xyz.push_back({static_cast<std::int32_t>(10000 * i), -5000 * static_cast<std::int32_t>(i), 1000});
    }
    std::vector<std::uint8_t> bytes = testing::build_las(b);
    const std::size_t first = 375 + 54 + 192, length = 31;  // header, VLR header and descriptor; 30 + 1 bytes a point
    for (std::size_t i = 0; i < codes.size(); ++i) bytes[first + i * length + 30] = codes[i];
    fs::create_directories(path(name).parent_path());
    testing::write_bytes(path(name), bytes);
    write(name + ".geoanchor.json", R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014@2024.5",
      "coordinates": {"kind": "enu", "ellipsoid": "GRS80", "storage": "int32_scaled"},
      "enu_origin": {"lat_deg": 47.464722, "lon_deg": 8.549167, "h_m": 480.0, "height_type": "ellipsoidal"},
      "vertical": {"height_type": "ellipsoidal", "datum": "ellipsoid GRS80"})" +
                                        (survey.empty() ? "" : ", \"survey\": " + survey) + "}");
  }
};

TEST_F(MetadataCli, Issue16_FitLeavesFloatAndWorseOutAndCountsEachSolutionType) {
  const RunResult r = here("fit " + kFixtures + "/airport_control_gnss.csv --remove-outliers --model molodensky-badekas --convention "
                          "position_vector -o T.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The fixture: P01-P28 fixed (P17 the planted blunder, removed by data
  // snooping), P29-P31 ppk, P32-P33 float, P34 dgps, P35 sbas, P36 standalone.
  EXPECT_NE(r.out.find("GNSS solutions (float and worse left out; --solution-weighting weighs them): fixed 28 (used 27), "
                       "ppk 3 (used 3), float 2 (used 0, left out 2), dgps 1 (used 0, left out 1), sbas 1 (used 0, left "
                       "out 1), standalone 1 (used 0, left out 1)"),
            std::string::npos)
      << r.out;
  const json t = read_json("T.json");
  const json& c = t["gnss_solutions"]["classes"];
  EXPECT_EQ(t["gnss_solutions"]["policy"], "exclude");
  EXPECT_EQ(c["fixed"], json({{"marks", 28}, {"used", 27}, {"excluded", 0}, {"sigma_factor", 1.0}}));
  EXPECT_EQ(c["ppk"]["used"], 3);
  EXPECT_EQ(c["float"], json({{"marks", 2}, {"used", 0}, {"excluded", 2}, {"sigma_factor", 1.0}}));
  EXPECT_EQ(c["standalone"]["excluded"], 1);
  EXPECT_EQ(c["dead_reckoned"]["marks"], 0);
  // The contract: 31 of 36 marks fixed or ppk = 86.111 %.
  const json& m = t["metadata"];
  EXPECT_EQ(m["schema"], "geoanchor.map-metadata/1");
  EXPECT_EQ(m["frame"], "ETRF2000");
  EXPECT_EQ(m["coordinate_epoch"], 2024.5);
  EXPECT_NEAR(m["rtk_fixed_percent"].get<double>(), 100.0 * 31 / 36, 1e-12);
  EXPECT_EQ(m["gnss_solution_counts"]["float"], 2);
  EXPECT_EQ(m["horizontal_crs"], "geographic (latitude, longitude) on GRS80 in ETRF2000@2024.5");
  EXPECT_EQ(m["vertical_datum"], "ellipsoid GRS80");
  EXPECT_EQ(m["gnss_method"], "unknown");
  EXPECT_EQ(m["enu_origin"], "unknown");
  // Each mark's record says its type and why it was left out.
  bool saw = false;
  for (const auto& p : t["points"]) {
    if (p["id"] == "P34") {
      saw = true;
      EXPECT_EQ(p["solution"], "dgps");
      EXPECT_EQ(p["used"], false);
      EXPECT_NE(p["note"].get<std::string>().find("GNSS solution dgps"), std::string::npos);
    }
  }
  EXPECT_TRUE(saw);
  // Weighted, the float marks enter with σ × 10.
  const RunResult w = here("fit " + kFixtures + "/airport_control_gnss.csv --remove-outliers --model molodensky-badekas --convention "
                          "position_vector --solution-weighting -o W.json");
  ASSERT_EQ(w.exit_code, 0) << w.err;
  const json wc = read_json("W.json")["gnss_solutions"]["classes"];
  EXPECT_EQ(wc["float"], json({{"marks", 2}, {"used", 2}, {"excluded", 0}, {"sigma_factor", 10.0}}));
  EXPECT_EQ(wc["standalone"]["sigma_factor"], 250.0);
}

TEST_F(MetadataCli, Issue16_WithoutASolutionColumnTheFitIsTheSameAndHasNoCounts) {
  ASSERT_EQ(here("fit " + kFixtures + "/airport_control.csv --remove-outliers --model molodensky-badekas --convention position_vector -o A.json")
                .exit_code, 0);
  const json a = read_json("A.json");
  EXPECT_FALSE(a.contains("gnss_solutions"));
  EXPECT_EQ(a["metadata"]["rtk_fixed_percent"], "unknown");
  EXPECT_EQ(a["metadata"]["gnss_solution_counts"], "unknown");
  // fit.md's worked example: the same parameters as before issue 16.
  EXPECT_NEAR(a["parameters"]["tx_m"].get<double>(), 0.4514, 5e-5);
  EXPECT_EQ(a["points"].size(), 36u);
}

TEST_F(MetadataCli, Issue16_FitTakesTheSurveyMetadataAndRefusesAContradiction) {
  const RunResult r = here("fit " + kFixtures + "/airport_control.csv --remove-outliers --model helmert7 --convention position_vector "
                          "--survey-metadata " + kFixtures + "/lszh_survey.json -o T.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = read_json("T.json")["metadata"];
  EXPECT_EQ(m["gnss_method"], "network RTK (VRS), 1 s epochs, 3 min occupations");
  EXPECT_EQ(m["geoid_model"], "CHGeo2004");
  EXPECT_EQ(m["rtk_fixed_percent"], 98.7);
  EXPECT_EQ(m["rtk_fixed_from"], "survey metadata " + kFixtures + "/lszh_survey.json");
  // The survey file's frame (ITRF2014) is the source's: its origin is not the target's.
  EXPECT_EQ(m["enu_origin"], "unknown");
  // 98.7 % stated, 31 of 36 = 86.1 % computed from the marks: refused, nothing written.
  const RunResult bad = here("fit " + kFixtures + "/airport_control_gnss.csv --remove-outliers --model helmert7 --convention position_vector "
                            "--survey-metadata " + kFixtures + "/lszh_survey.json -o U.json");
  EXPECT_EQ(bad.exit_code, 3) << bad.err;
  EXPECT_NE(bad.err.find("error[E_METADATA_CONFLICT]"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("metadata.rtk_fixed_percent: survey metadata"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("U.json")));
  // A survey file with an unknown key fails before the fit.
  write("typo.json", R"({"schema": "geoanchor.survey/1", "gnss_bsae": "ZIMM"})");
  const RunResult typo = here("fit " + kFixtures + "/airport_control.csv --remove-outliers --model helmert7 --convention position_vector "
                             "--survey-metadata typo.json -o V.json");
  EXPECT_EQ(typo.exit_code, 3);
  EXPECT_NE(typo.err.find("typo.json.gnss_bsae: unknown key"), std::string::npos) << typo.err;
  EXPECT_FALSE(fs::exists(path("V.json")));
}

TEST_F(MetadataCli, Issue16_ApplyWritesTheContractAndReadsItBack) {
  ASSERT_EQ(here("fit " + kFixtures + "/airport_control.csv --remove-outliers --model helmert7 --convention position_vector -o T.json").exit_code, 0);
  const RunResult r = here("apply " + kFixtures + "/airport_tile.las --transform T.json --out-dir out --survey-metadata " +
                          kFixtures + "/lszh_survey.json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json side = read_json("out/airport_tile.las.geoanchor.json");
  EXPECT_EQ(side["schema"], "geoanchor.tile/2");
  const json& m = side["metadata"];
  EXPECT_EQ(m["frame"], "ETRF2000");
  EXPECT_EQ(m["coordinate_epoch"], 2024.5);
  EXPECT_EQ(m["enu_origin"]["lat_deg"], 47.464722);
  // The bundled sidecar's origin source, carried with its origin.
  EXPECT_EQ(m["enu_origin_source"], "LSZH aerodrome reference point as in scripts/example.sh; height synthetic");
  EXPECT_EQ(m["coordinate_storage"], "float64 ECEF origin + int32 scaled ENU offsets");
  EXPECT_EQ(m["vertical_datum"], "ellipsoid GRS80");
  EXPECT_EQ(m["geoid_model"], "CHGeo2004");
  EXPECT_EQ(m["gnss_base"], "swipos VRS from AGNES stations ETH2 and ZIMM");
  // The bundled sidecar's 98.7 % (survey.rtk_fixed_percent) and the survey
  // file's agree; the first stated is recorded.
  EXPECT_EQ(m["rtk_fixed_percent"], 98.7);
  EXPECT_EQ(side["survey"]["rtk_fixed_percent"], 98.7);
  // The output, as the next run's input, is read back with its contract.
  const RunResult again = here("apply out/airport_tile.las --out-dir out2");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(read_json("out2/airport_tile.las.geoanchor.json")["metadata"]["gnss_base"],
            "swipos VRS from AGNES stations ETH2 and ZIMM");
}

TEST_F(MetadataCli, Issue16_ApplyComputesTheRtkFixedShareFromTheExtraBytes) {
  // 8 points: codes 1 1 1 2 3 1 4 1 — fixed 5, ppk 1, float 1, dgps 1:
  // fixed or ppk 6 of 8 = 75 %.
  gnss_tile("t.las", {1, 1, 1, 2, 3, 1, 4, 1}, "");
  const RunResult r = here("apply t.las --out-dir out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = read_json("out/t.las.geoanchor.json")["metadata"];
  EXPECT_EQ(m["rtk_fixed_percent"], 75.0);
  EXPECT_EQ(m["gnss_solution_counts"],
            json({{"fixed", 5}, {"ppk", 1}, {"float", 1}, {"dgps", 1}, {"sbas", 0}, {"standalone", 0}, {"dead_reckoned", 0}}));
  EXPECT_NE(m["rtk_fixed_from"].get<std::string>().find("extra bytes 'gnss_solution' of 8 points"), std::string::npos);
  // As LAZ the byte passes through compressed, and is counted again when read back.
  ASSERT_EQ(here("apply t.las --format laz --out-dir laz").exit_code, 0);
  ASSERT_EQ(here("apply laz/t.laz --format las --out-dir back").exit_code, 0);
  EXPECT_EQ(read_json("back/t.las.geoanchor.json")["metadata"]["gnss_solution_counts"], m["gnss_solution_counts"]);
  // A sidecar that states 75 (whole percent: ±0.5) agrees; 80 does not.
  gnss_tile("in2/t.las", {1, 1, 1, 2, 3, 1, 4, 1}, R"({"rtk_fixed_percent": 75})");
  EXPECT_EQ(here("apply in2/t.las --out-dir out2").exit_code, 0);
  gnss_tile("in3/t.las", {1, 1, 1, 2, 3, 1, 4, 1}, R"({"rtk_fixed_percent": 80})");
  const RunResult bad = here("apply in3/t.las --out-dir out3");
  EXPECT_EQ(bad.exit_code, 3) << bad.err;
  EXPECT_NE(bad.err.find("E_METADATA_CONFLICT"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("metadata.rtk_fixed_percent"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("out3/t.las")));
  EXPECT_FALSE(fs::exists(path("out3/t.las.geoanchor.json")));
  // A code outside the table fails the tile by point, leaving nothing.
  gnss_tile("in4/t.las", {1, 9}, "");
  const RunResult code = here("apply in4/t.las --out-dir out4");
  EXPECT_EQ(code.exit_code, 3);
  EXPECT_NE(code.err.find("point 2 (byte"), std::string::npos) << code.err;
  EXPECT_FALSE(fs::exists(path("out4/t.las")));
}

TEST_F(MetadataCli, Issue16_ASurveyFileForAnotherFrameOrOriginIsRefusedBeforeAnyOutput) {
  write("other.json", R"({"schema": "geoanchor.survey/1", "frame": "ITRF2008@2024.5"})");
  const RunResult r = here("apply " + kFixtures + "/airport_tile.las --out-dir out --survey-metadata other.json");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("metadata.frame: survey metadata other.json says \"ITRF2008\" but the input (sidecar"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("out/airport_tile.las")));
  write("origin.json", R"({"schema": "geoanchor.survey/1",
    "enu_origin": {"lat_deg": 47.2597, "lon_deg": 11.3439, "h_m": 581, "height_type": "ellipsoidal"}})");
  const RunResult o = here("apply " + kFixtures + "/airport_tile.las --out-dir out --survey-metadata origin.json");
  EXPECT_EQ(o.exit_code, 3) << o.err;
  EXPECT_NE(o.err.find("metadata.enu_origin"), std::string::npos) << o.err;
}

TEST_F(MetadataCli, Issue16_AdjustLeavesFloatGnssMeasurementsOutAndCountsThem) {
  json net = json::parse(slurp(kFixtures + "/airport_network/lszh_network.json"));
  // The reference cluster fixed; of the 16 baselines the first two float,
  // the others fixed: 15 fixed, 2 float.
  int baselines = 0;
  for (auto& m : net["measurements"]) {
    if (m["kind"] == "gnss_point_cluster") m["solution"] = "fixed";
    if (m["kind"] == "gnss_baseline") m["solution"] = baselines++ < 2 ? "float" : "fixed";
  }
  ASSERT_EQ(baselines, 16);
  write("net.json", net.dump(1));
  const RunResult r = here("adjust net.json -o stations.csv --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json rep = json::parse(r.out);
  const json& c = rep["gnss_solutions"]["classes"];
  EXPECT_EQ(rep["gnss_solutions"]["policy"], "exclude");
  EXPECT_EQ(c["fixed"]["measurements"], 15);
  EXPECT_EQ(c["float"], json({{"measurements", 2}, {"used", 0}, {"excluded", 2}, {"sigma_factor", 1.0}}));
  const RunResult w = here("adjust net.json -o stations2.csv --json --solution-weighting");
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_EQ(json::parse(w.out)["gnss_solutions"]["classes"]["float"]["excluded"], 0);
  EXPECT_EQ(json::parse(w.out)["gnss_solutions"]["classes"]["float"]["sigma_factor"], 10.0);
  // A value outside the list is refused by its path.
  net["measurements"][1]["solution"] = "RTK";
  write("bad.json", net.dump(1));
  const RunResult bad = here("adjust bad.json -o s3.csv");
  EXPECT_EQ(bad.exit_code, 3);
  EXPECT_NE(bad.err.find("measurements[1].solution: value \"RTK\" is not a GNSS solution type"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("s3.csv")));
}

}  // namespace
}  // namespace geoanchor
