#pragma once
// Running the real geoanchor executable in tests: a fresh folder per test
// (mkdtemp, so two runs of the suite never share one; kept when the test
// fails, for a look), commands with their exit code, standard output and
// standard error, and what files a run left behind.
//
// GEOANCHOR_TEST_EXE in the environment runs the suite against another
// geoanchor executable (e.g. an older build, to show that a new test fails
// on it); by default it is the one this build made.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "temp_folder.hpp"

namespace geoanchor::testing {

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A CSV as the commands write it (no quoted commas): header and rows of
// fields, comment and blank lines dropped.
struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  // The index of column `name`; throws when there is none.
  std::size_t col(const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw std::runtime_error("no column " + name);
    return static_cast<std::size_t>(it - header.begin());
  }
};

inline CsvTable parse_csv_table(const std::string& text) {
  CsvTable t;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string x;
    while (std::getline(ss, x, ',')) f.push_back(x);
    (t.header.empty() ? t.header : t.rows.emplace_back()) = f;
  }
  return t;
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_.emplace("geoanchor_cli");  // the one helper every test's folder comes from
    dir_ = folder_->path();
  }

  std::filesystem::path path(const std::string& name) const { return dir_ / name; }

  std::filesystem::path write(const std::string& name, const std::string& text) const {
    std::filesystem::create_directories(path(name).parent_path());
    std::ofstream(path(name), std::ios::binary) << text;
    return path(name);
  }

  // A shell command line; `stdin_file` is redirected to its input.
  RunResult shell(const std::string& command, const std::string& stdin_file = "") const {
    const auto out = path("stdout.txt"), err = path("stderr.txt");
    std::string cmd = command;
    if (!stdin_file.empty()) cmd += " < '" + stdin_file + "'";
    cmd += " > '" + out.string() + "' 2> '" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    RunResult r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
    std::filesystem::remove(out);
    std::filesystem::remove(err);
    return r;
  }

  // The executable under test (GEOANCHOR_TEST_EXE, else this build's).
  static std::string exe() {
    const char* other = std::getenv("GEOANCHOR_TEST_EXE");
    return other && *other ? std::string(other) : std::string(GEOANCHOR_EXE);
  }

  // geoanchor with `args`.
  RunResult run(const std::string& args, const std::string& stdin_file = "") const {
    return shell(exe() + " " + args, stdin_file);
  }

  // What the independent LAS reader (npm `copc`, tests/las-verify) prints
  // for a LAS file, as JSON text: header, VLRs, WKT, every point's
  // dimensions. "" (and a test failure) when the reader is not installed.
  std::string las_verify_text(const std::filesystem::path& las) const {
    const std::string verify = std::string(GEOANCHOR_SOURCE_DIR) + "/tests/las-verify";
    if (!std::filesystem::exists(verify + "/node_modules/copc")) {
      ADD_FAILURE() << "the independent LAS reader is not installed: run npm ci --prefix " << verify
                    << " (scripts/test.sh does)";
      return "";
    }
    const RunResult r = shell("node " + verify + "/verify.mjs '" + las.string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.out;
  }

  // The names in `folder` (default: the test's folder), sorted.
  std::vector<std::string> files(const std::filesystem::path& folder = {}) const {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(folder.empty() ? dir_ : folder)) {
      out.push_back(e.path().filename().string());
    }
    std::sort(out.begin(), out.end());
    return out;
  }

  // Every file in the test folder except the named inputs: outputs and temporaries.
  std::vector<std::string> leftovers(const std::vector<std::string>& inputs) const {
    std::vector<std::string> out;
    for (const auto& name : files()) {
      if (std::find(inputs.begin(), inputs.end(), name) == inputs.end()) out.push_back(name);
    }
    return out;
  }

  std::optional<TempFolder> folder_;
  std::filesystem::path dir_;
};

}  // namespace geoanchor::testing
