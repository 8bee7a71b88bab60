#pragma once
// What the apply command-line tests share (apply_cli_test.cpp,
// apply_outputs_cli_test.cpp): the ApplyCli fixture and the transforms it fits.
// Test-only: one definition for every test file that includes it (inline).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstring>
#include <csignal>
#include <functional>
#include <set>
#include <sstream>
#include <thread>

#include "cli_support.hpp"
#include "geoanchor/base/number_text.hpp"
#include "las_builder.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace apply_cli_fixture {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::CliTest;
using testing::ProjPipeline;
using testing::RunResult;
using testing::slurp;

constexpr double kVsProjTol_m = 1e-6;  // beyond half the LAS quantization step (issue acceptance)
constexpr double kVsProjTol_deg = 1e-9;  // the same for angles (issue acceptance)

inline const std::string kFixtures = GEOANCHOR_FIXTURES_DIR;
inline const std::string kTile = kFixtures + "/airport_tile.las";
inline const std::string kControl = kFixtures + "/airport_control.csv";

class ApplyCli : public CliTest {
 protected:
  // The bundled control set fitted with a 7-parameter Helmert: T.json.
  fs::path fit() {
    const RunResult r = run("fit " + kControl + " --remove-outliers --model helmert7 --convention position_vector -o " + path("T.json").string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return path("T.json");
  }
  // A copy of the bundled tile and its sidecar under `name`, the sidecar's
  // text edited by `edit`.
  fs::path tile(const std::string& name, const std::function<void(std::string&)>& edit = {}) {
    fs::create_directories(path(name).parent_path());
    fs::copy_file(kTile, path(name), fs::copy_options::overwrite_existing);
    std::string side = slurp(kTile + ".geoanchor.json");
    if (edit) edit(side);
    write(name + ".geoanchor.json", side);
    return path(name);
  }
  // What the independent reader sees in a LAS file.
  json las_verify(const fs::path& las) {
    const std::string text = las_verify_text(las);
    return text.empty() ? json() : json::parse(text);
  }
  fs::path out_dir(const std::string& name = "out") {
    fs::create_directories(path(name));
    return path(name);
  }
  static void replace(std::string& s, const std::string& from, const std::string& to) {
    const auto at = s.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    s.replace(at, from.size(), to);
  }
};

}  // namespace apply_cli_fixture
}  // namespace geoanchor
