// Issue 16 points 2 and 3: the map metadata contract (io/map_metadata.hpp)
// in tile sidecars and transform files, the survey-metadata file, the GNSS
// solution type of control marks (CSV, JSON, two files) and of LAS points
// (extra bytes "gnss_solution"). Expected counts and shares are worked out
// by hand from the fixtures written here; each is stated beside its check.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/gnss_solution.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/io/map_metadata.hpp"
#include "geoanchor/io/tile/point_chain.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "las_builder.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
using geodesy::GnssSolution;
using nlohmann::json;

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code() + ": " + e.what();
  }
  return "accepted";
}

#define EXPECT_HAS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << (text)

// ---------------------------------------------------------------- contract

TEST(MapMetadata, Issue16_EveryFieldIsWrittenWithItsValueOrUnknown) {
  MapMetadata m;
  m.frame = "ITRF2014";
  m.coordinate_epoch = 2024.5;
  m.enu_origin = MetadataOrigin{47.464722, 8.549167, 480.0};
  m.rtk_fixed_percent = 98.7;
  m.rtk_fixed_from = "survey metadata s.json";
  const json j = json::parse(map_metadata_json_text(m));
  const char* keys[] = {"schema", "frame", "coordinate_epoch", "enu_origin", "enu_origin_source", "horizontal_crs",
                        "vertical_datum", "geoid_model", "gnss_method", "gnss_base", "rtk_fixed_percent",
                        "rtk_fixed_from", "gnss_solution_counts", "coordinate_storage"};
  EXPECT_EQ(j.size(), std::size(keys));
  for (const char* k : keys) EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["schema"], "geoanchor.map-metadata/1");
  EXPECT_EQ(j["frame"], "ITRF2014");
  EXPECT_EQ(j["coordinate_epoch"], 2024.5);
  EXPECT_EQ(j["enu_origin"]["height_type"], "ellipsoidal");
  for (const char* k : {"enu_origin_source", "horizontal_crs", "vertical_datum", "geoid_model", "gnss_method", "gnss_base",
                        "gnss_solution_counts", "coordinate_storage"}) {
    EXPECT_EQ(j[k], "unknown") << k;
  }
  // And read back as written.
  const MapMetadata back = parse_map_metadata(j.dump(), "t.json: metadata");
  EXPECT_EQ(back.frame, m.frame);
  EXPECT_EQ(back.coordinate_epoch, m.coordinate_epoch);
  ASSERT_TRUE(back.enu_origin);
  EXPECT_EQ(back.enu_origin->lat_deg, 47.464722);
  EXPECT_EQ(back.rtk_fixed_percent, 98.7);
  EXPECT_FALSE(back.geoid_model);
  EXPECT_FALSE(back.gnss_solution_counts);
}

TEST(MapMetadata, Issue16_AMissingNullEmptyOrUnknownKeyIsRefusedByPath) {
  MapMetadata m;
  m.frame = "ETRF2000";
  const json good = json::parse(map_metadata_json_text(m));
  auto with = [&](const std::function<void(json&)>& edit) {
    json j = good;
    edit(j);
    return error_of([&] { (void)parse_map_metadata(j.dump(), "t.json: metadata"); });
  };
  EXPECT_HAS(with([](json& j) { j.erase("geoid_model"); }), "E_METADATA: t.json: metadata.geoid_model: missing");
  EXPECT_HAS(with([](json& j) { j["gnss_base"] = nullptr; }), "metadata.gnss_base: value null");
  EXPECT_HAS(with([](json& j) { j["gnss_method"] = ""; }), "metadata.gnss_method: empty");
  EXPECT_HAS(with([](json& j) { j["geoid"] = "EGM96"; }), "metadata.geoid: unknown key");
  EXPECT_HAS(with([](json& j) { j["schema"] = "geoanchor.map-metadata/2"; }), "metadata.schema: expected");
  EXPECT_HAS(with([](json& j) { j["rtk_fixed_percent"] = 101; }), "metadata.rtk_fixed_percent: value 101 not in [0, 100]");
  EXPECT_HAS(with([](json& j) { j["rtk_fixed_percent"] = 90; }), "metadata.rtk_fixed_from: \"unknown\", but");
  EXPECT_HAS(with([](json& j) { j["frame"] = "ITRF2014@2024.5"; }), "metadata.frame: \"ITRF2014@2024.5\" names an epoch");
  EXPECT_HAS(with([](json& j) { j["coordinate_epoch"] = json{{"from", 2024.6}, {"to", 2024.5}}; }), "is before from");
  // Counts and share say one thing: 3 fixed of 4 is 75 %, not 80 %.
  EXPECT_HAS(with([](json& j) {
               j["gnss_solution_counts"] = {{"fixed", 3},      {"ppk", 0},        {"float", 1},        {"dgps", 0},
                                            {"sbas", 0},       {"standalone", 0}, {"dead_reckoned", 0}};
               j["rtk_fixed_percent"] = 80;
               j["rtk_fixed_from"] = "x";
             }),
             "gnss_solution_counts give 75 % fixed or ppk");
}

TEST(MapMetadata, Issue16_AStatedShareAgreesToItsOwnRounding) {
  EXPECT_TRUE(share_agrees(98, 98.4));     // whole percent: ±0.5
  EXPECT_FALSE(share_agrees(98, 98.6));
  EXPECT_TRUE(share_agrees(98.7, 98.74));  // one decimal: ±0.05
  EXPECT_FALSE(share_agrees(98.7, 98.76));
  EXPECT_TRUE(share_agrees(86.11, 100.0 * 31 / 36));  // 86.111…
  EXPECT_FALSE(share_agrees(86.2, 100.0 * 31 / 36));
  EXPECT_FALSE(share_agrees(std::nan(""), 50.0));  // NaN agrees with nothing
}

TEST(MapMetadata, Issue16_StorageSaysWhatIsStoredAndHow) {
  EXPECT_EQ(coordinate_storage_text("enu", "int32_scaled"), "float64 ECEF origin + int32 scaled ENU offsets");
  EXPECT_EQ(coordinate_storage_text("ecef", "float32"), "float32 ECEF");
  EXPECT_EQ(coordinate_storage_text("utm", "float64"), "float64 projected (easting, northing, height)");
}

TEST(MapMetadata, Issue16_TwoSourcesThatDisagreeAreAnErrorNamingBoth) {
  MapMetadataBuilder b("out/t.las.geoanchor.json");
  b.frame("ETRF2000", "the output's coordinates");
  b.coordinate_epoch(2024.5, "the output's coordinates");
  SurveyMetadata s;
  s.source = "s.json";
  s.frame = geodesy::Frame::parse("ITRF2014@2024.5", "test");
  const std::string e = error_of([&] { b.survey(s); });
  EXPECT_HAS(e, "E_METADATA_CONFLICT: out/t.las.geoanchor.json: metadata.frame: survey metadata s.json says \"ITRF2014\" "
                "but the output's coordinates says \"ETRF2000\"");
  // The computed share is kept; a stated one must agree to its rounding.
  MapMetadataBuilder c("t");
  geodesy::SolutionCounts counts;
  counts.count[0] = 31;  // fixed
  counts.count[2] = 5;   // float: 31 of 36 = 86.11 %
  c.gnss_solution_counts(counts, "computed");
  c.rtk_fixed_percent(86.1, "sidecar", false);
  ASSERT_TRUE(c.metadata().rtk_fixed_percent);
  EXPECT_DOUBLE_EQ(*c.metadata().rtk_fixed_percent, 100.0 * 31.0 / 36.0);
  EXPECT_EQ(*c.metadata().rtk_fixed_from, "computed");
  EXPECT_HAS(error_of([&] { c.rtk_fixed_percent(98.7, "survey metadata s.json", false); }),
             "metadata.rtk_fixed_percent: survey metadata s.json says 98.7 % (beyond the stated value's rounding) but "
             "computed says");
}

// ---------------------------------------------------------------- survey file

TEST(SurveyMetadata, Issue16_TheFileIsReadStrictly) {
  const std::string good = R"({"schema": "geoanchor.survey/1", "frame": "ITRF2014@2024.5",
    "enu_origin": {"lat_deg": 47.464722, "lon_deg": 8.549167, "h_m": 480.0, "height_type": "ellipsoidal"},
    "enu_origin_source": "ICAO AIP published; survey confirmed", "gnss_method": "network RTK", "gnss_base": "unknown",
    "rtk_fixed_percent": 97.5})";
  const SurveyMetadata s = parse_survey_metadata(good, "s.json");
  EXPECT_EQ(s.frame->to_string(), "ITRF2014@2024.5");
  EXPECT_EQ(*s.enu_origin_source, "ICAO AIP published; survey confirmed");
  EXPECT_FALSE(s.gnss_base);  // "unknown" is as absent
  EXPECT_EQ(*s.rtk_fixed_percent, 97.5);
  auto error = [](const std::string& text) { return error_of([&] { (void)parse_survey_metadata(text, "s.json"); }); };
  EXPECT_HAS(error(R"({"schema": "geoanchor.survey/1", "gnss_methd": "RTK"})"),
             "E_SURVEY_METADATA: s.json.gnss_methd: unknown key");
  EXPECT_HAS(error(R"({"gnss_method": "RTK"})"), "s.json.schema: expected \"geoanchor.survey/1\", the key is missing");
  EXPECT_HAS(error(R"({"schema": "geoanchor.survey/1", "rtk_fixed_percent": "high"})"), "rtk_fixed_percent: expected a number");
  EXPECT_HAS(error(R"({"schema": "geoanchor.survey/1", "gnss_base": "A", "gnss_base": "B"})"), "E_JSON_DUPLICATE_KEY");
  EXPECT_HAS(error(R"({"schema": "geoanchor.survey/1", "enu_origin": {"lat_deg": 47, "lon_deg": 8, "h_m": 480}})"),
             "s.json.enu_origin.height_type: missing");
}

// ---------------------------------------------------------------- tile sidecar

const char* kSidecarV1 = R"J({
  "schema": "geoanchor.tile/1",
  "frame": "ITRF2014@2024.5",
  "coordinates": {"kind": "enu", "ellipsoid": "GRS80", "storage": "int32_scaled"},
  "enu_origin": {"lat_deg": 47.464722, "lon_deg": 8.549167, "h_m": 480.0, "height_type": "ellipsoidal",
                 "source": "AIP"},
  "vertical": {"height_type": "ellipsoidal", "datum": "ellipsoid GRS80"},
  "survey": {"rtk_fixed_percent": 98.5}
})J";

TEST(TileMetadataContract, Issue16_ASidecarWithItsContractReadsBackAndTheOldSchemaIsStillRead) {
  TileMetadata m = parse_tile_metadata(kSidecarV1, "v1.json");
  EXPECT_FALSE(m.metadata);  // /1 has none
  MapMetadataBuilder b("t");
  tile_contract_fields(b, m, "the sidecar");
  m.metadata = b.metadata();
  const std::string text = to_json_text(m);
  EXPECT_HAS(text, "\"schema\": \"geoanchor.tile/2\"");
  const TileMetadata back = parse_tile_metadata(text, "v2.json");
  ASSERT_TRUE(back.metadata);
  EXPECT_EQ(*back.metadata->frame, "ITRF2014");
  EXPECT_EQ(*back.metadata->coordinate_epoch, 2024.5);
  EXPECT_EQ(*back.metadata->enu_origin_source, "AIP");
  EXPECT_EQ(*back.metadata->coordinate_storage, "float64 ECEF origin + int32 scaled ENU offsets");
  EXPECT_EQ(*back.metadata->rtk_fixed_percent, 98.5);
  EXPECT_FALSE(back.metadata->gnss_method);
  // A /1 sidecar has no metadata key: given, it is an unknown key.
  std::string v1 = kSidecarV1;
  v1.insert(v1.rfind('}'), R"(, "metadata": {})");
  EXPECT_HAS(error_of([&] { (void)parse_tile_metadata(v1, "v1.json"); }), "v1.json: metadata: unknown key");
}

TEST(TileMetadataContract, Issue16_AContractThatContradictsTheSidecarOrLeavesOutWhatItStatesIsRefused) {
  TileMetadata m = parse_tile_metadata(kSidecarV1, "v1.json");
  MapMetadataBuilder b("t");
  tile_contract_fields(b, m, "the sidecar");
  m.metadata = b.metadata();
  const json good = json::parse(to_json_text(m));
  auto error = [&](const std::function<void(json&)>& edit) {
    json j = good;
    edit(j);
    return error_of([&] { (void)parse_tile_metadata(j.dump(), "v2.json"); });
  };
  EXPECT_HAS(error([](json& j) { j["metadata"]["frame"] = "ITRF2008"; }),
             "E_METADATA_CONFLICT: v2.json: metadata.frame: its metadata says \"ITRF2008\" but the sidecar's own keys says "
             "\"ITRF2014\"");
  EXPECT_HAS(error([](json& j) { j["metadata"]["coordinate_epoch"] = 2024.0; }), "metadata.coordinate_epoch");
  EXPECT_HAS(error([](json& j) { j["metadata"]["enu_origin"]["h_m"] = 480.01; }), "metadata.enu_origin");
  EXPECT_HAS(error([](json& j) { j["metadata"]["coordinate_storage"] = "float32 ECEF"; }), "metadata.coordinate_storage");
  EXPECT_HAS(error([](json& j) { j["metadata"]["rtk_fixed_percent"] = 97.0; }), "metadata.rtk_fixed_percent");
  EXPECT_HAS(error([](json& j) { j["metadata"]["frame"] = "unknown"; }),
             "v2.json: metadata.frame: \"unknown\" but the sidecar states it");
  EXPECT_HAS(error([](json& j) { j.erase("metadata"); }), "v2.json: metadata: missing");
}

// ---------------------------------------------------------------- control sets

class SolutionColumn : public ::testing::Test {
 protected:
  void SetUp() override { folder_.emplace("geoanchor_solution"); }
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = folder_->path() / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::optional<testing::TempFolder> folder_;
};

const char* kHeader = "id,x_src_m,y_src_m,z_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m,sigma_dst_m";

TEST_F(SolutionColumn, Issue16_EachMarkCarriesItsSolutionAndABadCellIsRefusedByLine) {
  const std::string rows = std::string(kHeader) + ",solution\n" +
                           "A,4270000,640000,4680000,4270000.1,640000.1,4680000.1,0.003,0.004,fixed\n"
                           "B,4271000,640000,4679000,4271000.1,640000.1,4679000.1,0.003,0.004,ppk\n"
                           "C,4270000,641000,4679500,4270000.1,641000.1,4679500.1,0.003,0.004,dead_reckoned\n";
  const auto set = read_control_set(write("c.csv", rows), {});
  EXPECT_TRUE(set.has_solutions);
  ASSERT_EQ(set.points.size(), 3u);
  EXPECT_EQ(set.points[0].solution, GnssSolution::fixed);
  EXPECT_EQ(set.points[1].solution, GnssSolution::ppk);
  EXPECT_EQ(set.points[2].solution, GnssSolution::dead_reckoned);
  std::string bad = rows;
  bad.replace(bad.find(",ppk"), 4, ",Float");
  EXPECT_HAS(error_of([&] { (void)read_control_set(write("bad.csv", bad), {}); }),
             "E_VALUE: " + (folder_->path() / "bad.csv").string() +
                 ":3: solution=Float: not a GNSS solution type; expected one of fixed, ppk, float, dgps, sbas, "
                 "standalone, dead_reckoned (lower case)");
  std::string empty = rows;
  empty.replace(empty.find(",ppk"), 4, ",");
  EXPECT_HAS(error_of([&] { (void)read_control_set(write("empty.csv", empty), {}); }), ":3: solution=: empty; expected one of");
  // A misspelt column would leave every mark's solution unread.
  std::string typo = rows;
  typo.replace(typo.find(",solution"), 9, ",soluton");
  EXPECT_HAS(error_of([&] { (void)read_control_set(write("typo.csv", typo), {}); }),
             "header column 10 'soluton': not read: a mark's GNSS solution type is read from the column 'solution'");
  const auto none = read_control_set(
      write("none.csv", std::string(kHeader) + "\nA,4270000,640000,4680000,4270000.1,640000.1,4680000.1,1,1\n"), {});
  EXPECT_FALSE(none.has_solutions);
  EXPECT_FALSE(none.points[0].solution);
}

TEST_F(SolutionColumn, Issue16_JsonPointsStateTheirSolutionAllOrNone) {
  const std::string one = R"({"points": [
    {"id": "A", "source": {"x_m": 4270000, "y_m": 640000, "z_m": 4680000}, "target": {"x_m": 4270000, "y_m": 640000, "z_m": 4680000},
     "solution": "sbas"},
    {"id": "B", "source": {"x_m": 4271000, "y_m": 640000, "z_m": 4679000}, "target": {"x_m": 4271000, "y_m": 640000, "z_m": 4679000}}]})";
  EXPECT_HAS(error_of([&] { (void)read_control_set(write("c.json", one), {}); }),
             "c.json: points[1].solution: missing, but points[0] states one");
  std::string two = one;
  two.insert(two.rfind("}]}"), R"(, "solution": "rtk")");
  EXPECT_HAS(error_of([&] { (void)read_control_set(write("d.json", two), {}); }),
             "d.json: points[1].solution: value \"rtk\" is not a GNSS solution type");
  std::string ok = one;
  ok.insert(ok.rfind("}]}"), R"(, "solution": "float")");
  const auto set = read_control_set(write("e.json", ok), {});
  EXPECT_TRUE(set.has_solutions);
  EXPECT_EQ(set.points[0].solution, GnssSolution::sbas);
  EXPECT_EQ(set.points[1].solution, GnssSolution::floating);
}

// ---------------------------------------------------------------- LAS extra bytes

// One extra-bytes descriptor (R15 Table 24, 192 bytes): data type and name.
std::vector<std::uint8_t> descriptor(std::uint8_t type, const std::string& name, std::uint8_t options = 0) {
  std::vector<std::uint8_t> d(192, 0);
  d[2] = type;
  d[3] = options;
  std::memcpy(d.data() + 4, name.data(), name.size());
  return d;
}

class GnssExtraBytes : public SolutionColumn {
 protected:
  // A format-6 tile of `codes.size()` points with two extra bytes: a
  // uint8 "intensity_2" first, then "gnss_solution" = codes[i].
  fs::path tile(const std::string& name, const std::vector<std::uint8_t>& codes, std::uint8_t type = 1) const {
    testing::LasBuild b;
    b.point_format = 6;
    b.extra_bytes = type == 1 ? 2 : 3;
    std::vector<std::uint8_t> vlr = descriptor(1, "intensity_2");
    const auto second = descriptor(type, "gnss_solution");
    vlr.insert(vlr.end(), second.begin(), second.end());
    b.vlrs.push_back({"LASF_Spec", 4, "extra bytes", vlr});
    for (std::size_t i = 0; i < codes.size(); ++i) {
      b.xyz.push_back({static_cast<std::int32_t>(1000 * i), 2000, 300});
    }
    std::vector<std::uint8_t> bytes = testing::build_las(b);
    // Point data after the 375-byte header and the VLR (54-byte header):
    // 30-byte format-6 records plus the extra bytes; gnss_solution is the
    // second extra byte.
    const std::size_t first = 375 + 54 + vlr.size(), length = 30 + b.extra_bytes;
    for (std::size_t i = 0; i < codes.size(); ++i) bytes[first + i * length + 31] = codes[i];
    const fs::path p = folder_->path() / name;
    testing::write_bytes(p, bytes);
    return p;
  }
  TileApplyResult run(const fs::path& in) const {
    ArrayFrame ecef;
    const PointChain chain(ecef, std::nullopt, false, std::nullopt, ecef);
    TileApplyOptions o;
    o.from = ecef;
    o.to = ecef;
    std::ofstream out(folder_->path() / "out.las", std::ios::binary);
    return apply_las_tile(in, out, "out.las", chain, o);
  }
};

TEST_F(GnssExtraBytes, Issue16_ThePointsOfEachSolutionTypeAreCounted) {
  // 10 points: 6 fixed (1), 1 ppk (2), 2 float (3), 1 standalone (6):
  // RTK-fixed (fixed or ppk) 7 of 10 = 70 %.
  const auto r = run(tile("t.las", {1, 1, 3, 1, 2, 1, 6, 3, 1, 1}));
  ASSERT_TRUE(r.gnss_solution_counts);
  const std::array<std::uint64_t, 7> expected{6, 1, 2, 0, 0, 1, 0};
  EXPECT_EQ(*r.gnss_solution_counts, expected);
  geodesy::SolutionCounts c;
  c.count = *r.gnss_solution_counts;
  EXPECT_DOUBLE_EQ(*c.rtk_fixed_percent(), 70.0);
  // Without the attribute, nothing is counted.
  testing::LasBuild plain;
  plain.xyz = {{0, 0, 0}};
  testing::write_bytes(folder_->path() / "plain.las", testing::build_las(plain));
  EXPECT_FALSE(run(folder_->path() / "plain.las").gnss_solution_counts);
}

TEST_F(GnssExtraBytes, Issue16_ACodeOutsideTheTableOrAnotherTypeIsRefusedByPoint) {
  const std::string e = error_of([&] { (void)run(tile("bad.las", {1, 1, 0, 1})); });
  EXPECT_HAS(e, "E_GNSS_SOLUTION: ");
  EXPECT_HAS(e, "bad.las: point 3 (byte ");
  EXPECT_HAS(e, "extra byte gnss_solution = 0 is no GNSS solution code; expected 1 fixed");
  EXPECT_HAS(error_of([&] { (void)run(tile("eight.las", {8})); }), "gnss_solution = 8 is no GNSS solution code");
  EXPECT_HAS(error_of([&] { (void)run(tile("short.las", {1}, 3)); }),
             "E_LAS_EXTRA_BYTES: " + (folder_->path() / "short.las").string() +
                 ": extra-bytes attribute 'gnss_solution' has data type 3; a GNSS solution code is an unscaled uint8");
}

TEST(LasExtraBytes, Issue16_AttributesAreLaidOutInRecordOrder) {
  LasVlr v;
  v.user_id = "LASF_Spec";
  v.record_id = 4;
  for (const auto& d : {descriptor(10, "range"), descriptor(0, "raw", 3), descriptor(1, "gnss_solution")}) {
    v.data.insert(v.data.end(), d.begin(), d.end());
  }
  // Format 6 is 30 bytes; a double (8), 3 undocumented bytes, a uint8: 42.
  const auto a = las_extra_bytes({v}, 6, 42, "t.las");
  ASSERT_EQ(a.size(), 3u);
  EXPECT_EQ(a[0].offset, 30u);
  EXPECT_EQ(a[1].offset, 38u);
  EXPECT_EQ(a[2].offset, 41u);
  EXPECT_EQ(a[2].name, "gnss_solution");
  EXPECT_HAS(error_of([&] { (void)las_extra_bytes({v}, 6, 41, "t.las"); }),
             "its attributes need 42-byte records, the file's are 41 bytes");
  v.data.resize(100);
  EXPECT_HAS(error_of([&] { (void)las_extra_bytes({v}, 6, 42, "t.las"); }), "100 bytes, not a multiple of the 192-byte");
}

// ---------------------------------------------------------------- transform file

const char* kTransform = R"J({
  "model": "translation3", "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
  "parameters": {"tx_m": 0.1, "ty_m": 0.2, "tz_m": 0.3},
  "sigmas": {"tx_m": 0.01, "ty_m": 0.01, "tz_m": 0.01}, "correlation": "none",
  "gnss_solutions": {"policy": "exclude", "classes": {
    "fixed": {"marks": 28, "used": 27, "excluded": 0, "sigma_factor": 1},
    "ppk": {"marks": 3, "used": 3, "excluded": 0, "sigma_factor": 1},
    "float": {"marks": 2, "used": 0, "excluded": 2, "sigma_factor": 1},
    "dgps": {"marks": 1, "used": 0, "excluded": 1, "sigma_factor": 1},
    "sbas": {"marks": 1, "used": 0, "excluded": 1, "sigma_factor": 1},
    "standalone": {"marks": 1, "used": 0, "excluded": 1, "sigma_factor": 1},
    "dead_reckoned": {"marks": 0, "used": 0, "excluded": 0, "sigma_factor": 1}}}
})J";

TEST(TransformFileSolutions, Issue16_TheCountsAreReadBackAndCheckedAgainstThePolicy) {
  const TransformFile t = parse_transform_json(kTransform, "t.json");
  ASSERT_TRUE(t.fit && t.fit->gnss_solutions);
  EXPECT_EQ(t.fit->gnss_solutions->classes[0].used, 27u);
  EXPECT_EQ(t.fit->gnss_solutions->classes[2].excluded, 2u);
  const TransformFile again = parse_transform_json(to_json_text(t), "again.json");
  EXPECT_EQ(again.fit->gnss_solutions->classes[5].marks, 1u);
  auto error = [](std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return error_of([&] { (void)parse_transform_json(text, "t.json"); });
  };
  EXPECT_HAS(error(kTransform, R"("float": {"marks": 2, "used": 0)", R"("float": {"marks": 3, "used": 1)"),
             "t.json: gnss_solutions.classes.float: used is not 0, but policy exclude leaves out float marks");
  EXPECT_HAS(error(kTransform, R"("policy": "exclude")", R"("policy": "weight")"),
             "gnss_solutions.classes.float: excluded is not 0, but policy weight uses float marks");
  EXPECT_HAS(error(kTransform, R"("dead_reckoned": {)", R"("dead_reckonned": {)"), "gnss_solutions.classes.dead_reckonned: unknown key");
  EXPECT_HAS(error(kTransform, R"("marks": 28, "used": 27)", R"("marks": 20, "used": 27)"), "used 27 + excluded 0 > marks 20");
}

TEST(TransformFileSolutions, Issue16_TheContractDescribesTheTargetSide) {
  std::string text = kTransform;
  MapMetadata m;
  m.frame = "ITRF2014";  // the source's, not the target's
  text.insert(text.rfind('}'), ", \"metadata\": " + map_metadata_json_text(m));
  EXPECT_HAS(error_of([&] { (void)parse_transform_json(text, "t.json"); }),
             "E_METADATA_CONFLICT: t.json: metadata.frame: metadata.frame says \"ITRF2014\" but target_frame says \"ETRF2000\"");
}

}  // namespace
}  // namespace geoanchor::io
