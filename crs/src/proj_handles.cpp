// PROJ contexts for io: quiet, offline, and finding grids in any letter case.

#include "proj_handles.hpp"

#include <cctype>
#include <filesystem>
#include <system_error>

namespace geoanchor::io::detail {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// PROJ asks for each resource file by name. A name that is in a search path
// as written is left to PROJ's own search (nullptr); one that is there
// under another letter case only is returned with its path. Only grid
// files are matched this way: the database and init files PROJ finds itself.
const char* find_grid_any_case(PJ_CONTEXT*, const char* name, void*) {
  thread_local std::string found;
  if (!name) return nullptr;
  const std::string wanted(name);
  const std::string extension = lower(std::filesystem::path(wanted).extension().string());
  if (extension != ".gsb" && extension != ".gtx" && extension != ".tif" && extension != ".tiff") return nullptr;
  const auto path = find_grid_file(wanted);
  if (!path || path->filename().string() == wanted) return nullptr;  // none, or PROJ finds it itself
  found = path->string();
  return found.c_str();
}

// A thread's last PROJ error, as errno is kept: each context is used by one
// thread at a time.
thread_local std::string last_error;

void keep_error(void*, int level, const char* message) {
  if (level <= PJ_LOG_ERROR && message) last_error = message;
}

}  // namespace

std::string take_last_proj_error() {
  std::string out;
  out.swap(last_error);
  return out;
}

std::optional<std::filesystem::path> find_grid_file(const std::string& name) {
  if (name.empty() || name.find('/') != std::string::npos) return std::nullopt;
  const auto paths = proj_search_paths();
  std::error_code ec;
  for (const auto& dir : paths) {
    if (std::filesystem::is_regular_file(std::filesystem::path(dir) / name, ec)) return std::filesystem::path(dir) / name;
  }
  const std::string key = lower(name);
  for (const auto& dir : paths) {
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      if (lower(it->path().filename().string()) == key && it->is_regular_file(ec)) return it->path();
    }
    ec.clear();
  }
  return std::nullopt;
}

std::vector<std::string> proj_search_paths() {
  const PJ_INFO info = proj_info();
  std::vector<std::string> out;
  const std::string all = info.searchpath ? info.searchpath : "";
  std::size_t start = 0;
  while (start <= all.size()) {
    const auto end = all.find(':', start);
    const std::string dir = all.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (!dir.empty()) out.push_back(dir);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

PjContext quiet_context() {
  PjContext ctx(proj_context_create());
  proj_log_func(ctx.get(), nullptr, keep_error);
  proj_log_level(ctx.get(), PJ_LOG_ERROR);
  proj_context_set_enable_network(ctx.get(), 0);
  proj_context_set_file_finder(ctx.get(), find_grid_any_case, nullptr);
  return ctx;
}

}  // namespace geoanchor::io::detail
