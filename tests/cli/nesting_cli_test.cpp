// Issue 40 point 7: JSON and XML nested deeper than 256 levels (GeoJSON
// properties 10⁵ deep, GeometryCollections 2·10⁵ deep, a transform file's
// description 10⁵ deep, an OpenDRIVE file's elements) are refused with a clear
// error: no crash (it was SIGSEGV, exit 139), no temporary file left.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;

class Nesting : public CliTest {
 protected:
  // Every file in the test's folder, hidden ones included, but `keep`.
  std::vector<std::string> others(const std::vector<std::string>& keep) const {
    std::vector<std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(dir_)) {
      if (!e.is_regular_file()) continue;
      const std::string name = e.path().filename().string();
      if (std::find(keep.begin(), keep.end(), name) == keep.end() && !name.starts_with("geoanchor-apply-summary")) {
        out.push_back(name);
      }
    }
    return out;
  }
};

std::string repeated(const std::string& s, std::size_t n) {
  std::string out;
  out.reserve(s.size() * n);
  for (std::size_t i = 0; i < n; ++i) out += s;
  return out;
}

// The bundled OpenDRIVE map with `n` <userData> nested in its header.
std::string deep_xodr(std::size_t n) {
  std::string s = testing::slurp(fs::path(GEOANCHOR_SOURCE_DIR) / "fixtures" / "airport_taxiway.xodr");
  const auto at = s.find('>', s.find("<header")) + 1;
  return s.substr(0, at) + repeated("<userData>", n) + repeated("</userData>", n) + s.substr(at);
}

constexpr const char* kTransform = R"({"model": "helmert7", "convention": "position_vector", "source_frame": "ITRF2014@2024.5",
  "target_frame": "ETRF2000", "parameters": {"tx_m": 0.05, "ty_m": 0.04, "tz_m": -0.09, "rx_arcsec": 0.001,
  "ry_arcsec": 0.012, "rz_arcsec": -0.02, "ds_ppm": 0.002}})";

TEST_F(Nesting, Issue40_DeepJsonAndXmlAreRefusedWithoutACrash) {
  const auto t = write("t.json", kTransform);
  struct Case {
    std::string name, text, command;
  };
  const std::size_t n = 100000;
  const std::string point = R"("geometry": {"type": "Point", "coordinates": [8.55, 47.46, 480]})";
  const std::vector<Case> cases = {
      {"properties.geojson",
       R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"a": )" + repeated("[", n) +
           repeated("]", n) + "}, " + point + "}]}",
       "apply {} --from-frame ITRF2014@2024.5 --transform " + t.string() + " --out-dir {out}"},
      {"collections.geojson",
       R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, "geometry": )" +
           repeated(R"({"type": "GeometryCollection", "geometries": [)", 2 * n) + repeated("]}", 2 * n) + "}]}",
       "apply {} --from-frame ITRF2014@2024.5 --transform " + t.string() + " --out-dir {out}"},
      {"description.json",
       R"({"model": "translation3", "description": )" + repeated("[", n) + repeated("]", n) +
           R"(, "parameters": {"tx_m": 1, "ty_m": 2, "tz_m": 3}})",
       "convert " + write("a.csv", "id,lat_deg,lon_deg,h_m\nA,47,8,400\n").string() + " --to ecef --transform {} -o {out}"},
      {"nested.xodr", deep_xodr(n), "apply {} --from-frame ITRF2014@2024.5 --transform " + t.string() + " --out-dir {out}"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto in = write(c.name, c.text);
    std::string cmd = c.command;
    cmd.replace(cmd.find("{}"), 2, in.string());
    cmd.replace(cmd.find("{out}"), 5, path("out_" + c.name).string());
    const auto r = run(cmd);
    EXPECT_EQ(r.exit_code, 3) << r.err;
    EXPECT_NE(r.err.find("E_NESTING"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("256"), std::string::npos) << r.err;
    EXPECT_EQ(others({"t.json", "a.csv", "properties.geojson", "collections.geojson", "description.json", "nested.xodr"}),
              std::vector<std::string>{});
  }
}

}  // namespace
}  // namespace geoanchor
