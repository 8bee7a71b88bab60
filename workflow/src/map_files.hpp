#pragma once
// How the files of a map folder are named and left out (private to workflow):
// shared by apply, which reads a folder's tiles, and audit, which reads a
// finished map's artifacts.

#include <fnmatch.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace geoanchor::workflow::detail {

// A tile's or vector map's sidecar is its file name plus this.
inline constexpr std::string_view kSidecarSuffix = ".geoanchor.json";
// The run summaries apply writes beside its outputs.
inline constexpr std::string_view kRunSummaryStem = "geoanchor-apply-summary";

inline bool is_run_summary(const std::string& name) {
  return name.starts_with(kRunSummaryStem) && name.ends_with(".json");
}

// Whether `exclude` leaves a file out: a glob without '/' against its name,
// one with '/' against `as_listed` (its path relative to the folder given,
// a manifest's entry or an argument as written).
inline bool excluded_by(const std::vector<std::string>& exclude, const std::filesystem::path& as_listed) {
  const std::string name = as_listed.filename().string(), listed = as_listed.generic_string();
  for (const auto& g : exclude) {
    const bool path_glob = g.find('/') != std::string::npos;
    if (::fnmatch(g.c_str(), (path_glob ? listed : name).c_str(), 0) == 0) return true;
  }
  return false;
}

// The first `most` names of `v`, comma-separated, and how many more: a
// message names a few files and counts the rest.
inline std::string name_list(const std::vector<std::string>& v, std::size_t most) {
  std::string s;
  for (std::size_t i = 0; i < v.size() && i < most; ++i) s += (i ? ", " : "") + v[i];
  if (v.size() > most) s += ", and " + std::to_string(v.size() - most) + " more";
  return s;
}

}  // namespace geoanchor::workflow::detail
