// What audit reads: the map's artifacts listed from the inputs (folders,
// files, --exclude), read with their sidecars, and what each states.
#include "audit_artifacts.hpp"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include "audit_text.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "map_files.hpp"

namespace geoanchor::workflow::audit_detail {

namespace fs = std::filesystem;

namespace {

using detail::excluded_by;
using detail::is_run_summary;
using detail::kSidecarSuffix;

// A .json file that is no sidecar: a transform file, or GeoJSON.
enum class JsonKind { transform, geojson, other };
JsonKind json_kind(const fs::path& p, std::string& why) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", p.string() + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::exception& e) {
    why = std::string("not JSON: ") + e.what();
    return JsonKind::other;
  }
  if (doc.is_object() && doc.contains("type") && doc["type"].is_string()) {
    const std::string t = doc["type"].get<std::string>();
    if (t == "FeatureCollection" || t == "Feature") return JsonKind::geojson;
  }
  if (doc.is_object() && doc.contains("model")) return JsonKind::transform;
  why = "JSON that is neither a transform file (no \"model\") nor GeoJSON";
  return JsonKind::other;
}

}  // namespace

Listing list_artifacts(const AuditRequest& request) {
  Listing r;
  std::map<std::string, std::size_t> at;  // canonical artifact path -> index
  std::vector<std::string> unknown;
  for (const auto& g : request.exclude) {
    if (g.empty()) throw Error(ErrorKind::usage, "E_OPTION", "--exclude '': expected a glob such as '*.xyz' or 'raw/*'");
  }
  const auto add = [&](const fs::path& f, const std::string& where) {
    const std::string name = f.filename().string();
    fs::path artifact = f;
    bool from_sidecar = false;
    if (name.size() > kSidecarSuffix.size() && name.ends_with(kSidecarSuffix)) {
      artifact = f.parent_path() / name.substr(0, name.size() - kSidecarSuffix.size());
      from_sidecar = true;
    }
    if (is_run_summary(name)) {
      r.ignored.push_back(f.string() + " (apply's run summary)");
      return;
    }
    if (io::is_temporary_name(name)) {
      r.ignored.push_back(f.string() + " (a temporary file of an interrupted run)");
      return;
    }
    AuditArtifact a;
    a.path = artifact;
    const auto format = io::tile_format_of(artifact);
    if (format) {
      a.kind = io::is_vector_map(*format) ? AuditArtifactKind::vector_map : AuditArtifactKind::tile;
      a.sidecar = io::sidecar_path(artifact);
    } else if (!from_sidecar && f.extension() == ".json") {
      std::string why;
      const JsonKind k = json_kind(f, why);
      if (k == JsonKind::transform) {
        a.kind = AuditArtifactKind::transform;
      } else if (k == JsonKind::geojson) {
        a.kind = AuditArtifactKind::vector_map;
        a.sidecar = io::sidecar_path(artifact);
      } else {
        unknown.push_back(f.string() + " (" + why + ")");
        return;
      }
    } else {
      unknown.push_back(f.string() + (from_sidecar ? " (a sidecar of no tile or vector map geoanchor reads)" : "") +
                        (where.empty() ? "" : " [" + where + "]"));
      return;
    }
    std::error_code ec;
    const std::string key = fs::weakly_canonical(artifact, ec).string();
    if (at.count(key)) return;
    at[key] = r.artifacts.size();
    r.artifacts.push_back(std::move(a));
  };
  for (const auto& in : request.inputs) {
    const fs::path p(in);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::recursive_directory_iterator(p, ec)) {
        std::error_code e_ec;
        if (e.is_directory(e_ec)) continue;
        if (excluded_by(request.exclude, e.path().lexically_relative(p))) {
          r.ignored.push_back(e.path().string() + " (--exclude)");
          continue;
        }
        if (!e.is_regular_file(e_ec)) {
          unknown.push_back(e.path().string() + " (not a regular file)");
          continue;
        }
        files.push_back(e.path());
      }
      if (ec) throw Error(ErrorKind::io, "E_READ", in + ": cannot list the folder: " + ec.message());
      std::sort(files.begin(), files.end());
      for (const auto& f : files) add(f, "");
    } else if (!fs::exists(p, ec)) {
      throw Error(ErrorKind::io, "E_READ", in + ": no such file or folder");
    } else if (excluded_by(request.exclude, p)) {
      r.ignored.push_back(p.string() + " (--exclude)");
    } else {
      add(p, "");
    }
  }
  if (!unknown.empty()) {
    throw Error(ErrorKind::usage, "E_INPUT_UNKNOWN",
                std::to_string(unknown.size()) + (unknown.size() == 1 ? " file is" : " files are") +
                    " not part of a map geoanchor audits (a tile .las/.laz/.csv/.ply, a vector map "
                    ".geojson/.osm/.xodr, a sidecar, a transform file): " +
                    join(unknown) + "; leave them out with --exclude GLOB");
  }
  if (r.artifacts.empty()) throw Error(ErrorKind::usage, "E_INPUT", "no tile, vector map or transform file among the inputs");
  return r;
}

void read_artifact(AuditArtifact& a) {
  std::error_code ec;
  try {
    if (a.kind == AuditArtifactKind::transform) {
      a.transform = io::read_transform_file(a.path);
      a.transform_sha256 = sha256_file_hex(a.path);
      return;
    }
    if (!fs::exists(a.path, ec)) {
      a.unreadable = "the sidecar's " + std::string(to_string(a.kind)) + " " + a.path.string() + " is missing";
    }
    if (!fs::exists(a.sidecar, ec)) {
      a.unreadable = "no sidecar " + a.sidecar.string() + ": its frame and metadata are unknown";
      return;
    }
    a.meta = io::read_tile_metadata(a.sidecar);
  } catch (const Error& e) {
    a.unreadable = e.what();
  }
}

std::string name_of(const AuditArtifact& a) { return a.path.string(); }

// The provenance object of a sidecar, or an empty object.
nlohmann::json provenance(const AuditArtifact& a) {
  if (!a.meta || a.meta->provenance_json.empty()) return nlohmann::json::object();
  try {
    return nlohmann::json::parse(a.meta->provenance_json);
  } catch (const nlohmann::json::exception&) {
    return nlohmann::json::object();
  }
}

const io::MapMetadata* contract_of(const AuditArtifact& a) {
  if (a.meta && a.meta->metadata) return &*a.meta->metadata;
  if (a.transform && a.transform->metadata) return &*a.transform->metadata;
  return nullptr;
}

// Whether an artifact's coordinates are relative to an ENU origin: a tile
// or vector map in ENU/NED, a transform fitted in a local frame.
bool needs_enu_origin(const AuditArtifact& a) {
  if (a.kind == AuditArtifactKind::transform) {
    return a.transform && (a.transform->enu_origin || a.transform->site_calibration);
  }
  if (!a.meta) return true;  // unreadable: the metadata check names it anyway
  if (a.meta->crs) return false;
  const auto k = a.meta->coordinates.kind;
  return k == io::CoordinateKind::enu || k == io::CoordinateKind::ned;
}

// The map's reference: the ENU origin its contracts state (the first), else
// the first tile's centre.
std::optional<geodesy::LocalOrigin> map_origin(const std::vector<AuditArtifact>& arts) {
  for (const auto& a : arts) {
    const io::MapMetadata* m = contract_of(a);
    if (m && m->enu_origin) {
      geodesy::LocalOrigin o;
      o.point = geodesy::GeodeticPosition{geodesy::Angle::degrees(m->enu_origin->lat_deg), geodesy::Angle::degrees(m->enu_origin->lon_deg),
                                          geodesy::EllipsoidalHeight{m->enu_origin->h_m}};
      o.ellipsoid = geodesy::Ellipsoid::grs80();
      if (a.meta && !a.meta->crs) o.ellipsoid = a.meta->coordinates.ellipsoid;
      return o;
    }
  }
  return std::nullopt;
}

}  // namespace geoanchor::workflow::audit_detail
