#pragma once
// What the LAZ tests share: records with realistic content for every
// supported point format (laz_records.hpp), the independent decoder
// laz-perf (npm, run by tests/las-verify/laz-decode.mjs), and a
// byte-for-byte comparison of records that says where they first differ.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "laz_records.hpp"

namespace geoanchor::testing {

namespace laz_fs = std::filesystem;

inline Bytes slurp_bytes(const laz_fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// "0 of N records differ" or where the first difference is.
inline ::testing::AssertionResult SameRecords(const Bytes& got, const Bytes& want, std::size_t len) {
  if (got.size() != want.size()) {
    return ::testing::AssertionFailure() << got.size() / len << " records, expected " << want.size() / len;
  }
  std::size_t differ = 0, first = 0;
  for (std::size_t i = 0; i < got.size() / len; ++i) {
    if (std::memcmp(got.data() + i * len, want.data() + i * len, len) != 0 && differ++ == 0) first = i;
  }
  if (differ == 0) return ::testing::AssertionSuccess() << "all " << got.size() / len << " records equal";
  std::size_t byte = 0;
  while (got[first * len + byte] == want[first * len + byte]) ++byte;
  return ::testing::AssertionFailure() << differ << " of " << got.size() / len << " records differ; the first is record "
                                       << first << " at byte " << byte;
}

// laz-perf's decoding of a LAZ file: its records and what it (and copc) report.
struct LazPerfRead {
  nlohmann::json report;
  Bytes records;
};
inline std::optional<LazPerfRead> laz_perf(const laz_fs::path& laz, const laz_fs::path& scratch) {
  const laz_fs::path kVerify = laz_fs::path(GEOANCHOR_SOURCE_DIR) / "tests" / "las-verify";
  if (!laz_fs::exists(kVerify / "node_modules" / "laz-perf") || !laz_fs::exists(kVerify / "node_modules" / "copc")) {
    ADD_FAILURE() << "the independent LAZ decoder is not installed: run npm ci --prefix " << kVerify.string()
                  << " (scripts/test.sh does)";
    return std::nullopt;
  }
  const laz_fs::path out = scratch / (laz.filename().string() + ".laz-perf.bin");
  const std::string cmd = "node '" + (kVerify / "laz-decode.mjs").string() + "' '" + laz.string() + "' '" + out.string() + "' 2>&1";
  std::string text;
  if (FILE* p = ::popen(cmd.c_str(), "r")) {
    char buf[4096];
    while (const std::size_t n = std::fread(buf, 1, sizeof buf, p)) text.append(buf, n);
    const int status = ::pclose(p);
    if (status != 0) {
      ADD_FAILURE() << "laz-perf could not read " << laz << ": " << text;
      return std::nullopt;
    }
  }
  LazPerfRead r;
  r.report = nlohmann::json::parse(text);
  r.records = slurp_bytes(out);
  laz_fs::remove(out);
  return r;
}


}  // namespace geoanchor::testing
