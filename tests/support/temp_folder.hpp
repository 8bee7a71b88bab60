#pragma once
// A folder of the running test's own in the system temporary folder:
// mkdtemp under GoogleTest's TempDir(), named after the test, so that two
// tests, or two runs of the suite at the same time, never share a file
// (fixed names such as TempDir()/"tile.csv" did). Removed with its contents
// when the object goes, unless the test failed: then it is kept for a look,
// and the failure names it.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace geoanchor::testing {

class TempFolder {
 public:
  // `prefix` starts the folder's name; the running test's suite and name follow.
  explicit TempFolder(const std::string& prefix = "geoanchor_test") {
    std::string name = prefix;
    if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info()) {
      name += std::string("_") + info->test_suite_name() + "_" + info->name();
    }
    for (char& c : name) {
      if (c == '/') c = '_';  // parameterised test names
    }
    std::string templ = (std::filesystem::path(::testing::TempDir()) / (name + "_XXXXXX")).string();
    if (::mkdtemp(templ.data()) == nullptr) {
      throw std::runtime_error("cannot create a temporary folder from " + templ);
    }
    path_ = templ;
  }
  ~TempFolder() {
    if (::testing::Test::HasFailure()) {
      std::fprintf(stderr, "kept for a look: %s\n", path_.c_str());
      return;
    }
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace geoanchor::testing
