// A geoid grid through PROJ's vgridshift.

#include "geoanchor/crs/proj_geoid.hpp"

#include <nlohmann/json.hpp>
#include <proj.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/hash.hpp"
#include "crs_impl.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;

// The file: a path as given, else a grid of that name (any letter case) in
// PROJ's data directories.
std::optional<fs::path> find(std::string_view text) {
  std::error_code ec;
  const fs::path given{std::string(text)};
  if (fs::is_regular_file(given, ec)) return fs::absolute(given, ec);
  return detail::find_grid_file(given.string());
}

// One PROJ operation shared by copies of the grid; PROJ objects are not
// safe to use from two threads at once, so calls take turns.
struct Evaluator {
  std::mutex m;
  detail::PjContext ctx;
  detail::Pj op;
};

}  // namespace

std::optional<std::filesystem::path> find_geoid_file(std::string_view name_or_path) { return find(name_or_path); }

geodesy::GeoidGrid proj_geoid_grid(std::string_view text, std::string_view flag) {
  const auto path = find(text);
  if (!path) {
    std::string dirs;
    for (const auto& d : detail::proj_search_paths()) dirs += (dirs.empty() ? "" : ", ") + d;
    throw Error(ErrorKind::input, "E_GEOID_MISSING",
                std::string(flag) + " " + std::string(text) +
                    ": no such file, and no grid of that name where PROJ looks (" + dirs +
                    "; network access off); expected EGM96, EGM96-NGA, a grid name PROJ knows (egm96_15.gtx) or a path "
                    "to a GTX or GeoTIFF geoid grid");
  }
  if (path->string().find_first_of("\",") != std::string::npos) {
    throw Error(ErrorKind::input, "E_GEOID",
                std::string(flag) + " " + std::string(text) + ": " + path->string() +
                    ": a path holding a double quote or a comma cannot be given to PROJ (a comma separates grids); "
                    "rename or link the file");
  }
  auto e = std::make_shared<Evaluator>();
  e->ctx = detail::quiet_context();
  // Quoted: a path may hold spaces (PROJ strings take "..." values).
  const std::string def = "+proj=vgridshift +grids=\"" + path->string() + "\" +multiplier=1";
  e->op.reset(proj_create(e->ctx.get(), def.c_str()));
  if (!e->op) {
    std::error_code ec;
    const auto size = fs::file_size(*path, ec);
    throw Error(ErrorKind::input, "E_GEOID",
                std::string(flag) + " " + std::string(text) + ": " + path->string() + " (" + std::to_string(ec ? 0 : size) +
                    " bytes) is a file PROJ cannot read as a vertical grid (PROJ: " +
                    detail::text_or(proj_context_errno_string(e->ctx.get(), proj_context_errno(e->ctx.get()))) +
                    "); geoanchor reads a GTX or GeoTIFF geoid grid through PROJ, an NTv2 geoid grid in AUSGeoid's form "
                    "(NUM_OREC header, SYSTEM_T AHD_1971) and, for adjust, DynAdjust's per-station .geo file");
  }
  auto n_at = [e](double lat_deg, double lon_deg) {
    std::lock_guard<std::mutex> lock(e->m);
    proj_errno_reset(e->op.get());
    PJ_COORD c = proj_coord(lon_deg * detail::kRadiansPerDegree, lat_deg * detail::kRadiansPerDegree, 0.0, 0.0);
    c = proj_trans(e->op.get(), PJ_FWD, c);
    if (proj_errno(e->op.get()) != 0 || c.xyz.z == HUGE_VAL || !std::isfinite(c.xyz.z)) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    return c.xyz.z;  // 0 + 1 × N
  };
  return geodesy::GeoidGrid::from_evaluator(path->filename().string() + " (PROJ vgridshift)", *path, n_at);
}

std::string geoid_record_json(const geodesy::GeoidGrid& grid) {
  const bool nga = grid.interpolation() == geodesy::GeoidInterpolation::nga_spline;
  const nlohmann::ordered_json j = {
      {"model", grid.model_name()},
      {"grid", grid.path().string()},
      {"sha256", sha256_file_hex(grid.path())},
      {"interpolation", nga ? "4 x 4 natural cubic spline (NGA INTPT)"
                        : grid.interpolation() == geodesy::GeoidInterpolation::bicubic ? geodesy::to_string(grid.interpolation())
                                                                                        : "bilinear (PROJ vgridshift)"}};
  return j.dump();
}

}  // namespace geoanchor::io
