#pragma once
// Owning handles for PROJ objects (private to io).

#include <proj.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace geoanchor::io::detail {

struct PjDeleter {
  void operator()(PJ* p) const { proj_destroy(p); }
};
using Pj = std::unique_ptr<PJ, PjDeleter>;

struct CtxDeleter {
  void operator()(PJ_CONTEXT* c) const { proj_context_destroy(c); }
};
using PjContext = std::unique_ptr<PJ_CONTEXT, CtxDeleter>;

// A context that logs nothing and never reaches the network: every grid
// comes from the machine's PROJ data directories. A grid file that is there
// under another letter case (Debian's proj-data ships CHENYX06a.gsb where
// PROJ's database names CHENyx06a.gsb) is found by `find_grid_any_case`.
PjContext quiet_context();

// The last error PROJ reported on this thread through a quiet context's
// logger ("Unsupported conversion method: Tunisia Mining Grid"), taken and
// cleared; "" when none. Errors are kept, never printed.
std::string take_last_proj_error();

// PROJ's data directories, in its search order.
std::vector<std::string> proj_search_paths();

// A file of that bare name in PROJ's data directories: as written first,
// else under another letter case; nullopt when none holds it.
std::optional<std::filesystem::path> find_grid_file(const std::string& name);

inline std::string text_or(const char* s, const char* fallback = "") { return s ? s : fallback; }

}  // namespace geoanchor::io::detail
