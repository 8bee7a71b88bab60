#include "geoanchor/workflow/audit.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/tile/point_chain.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/workflow/uncertainty.hpp"
#include "map_files.hpp"
#include "tile_points.hpp"

namespace geoanchor::workflow {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

using detail::excluded_by;
using detail::is_run_summary;
using detail::kSidecarSuffix;
constexpr std::size_t kListed = 20;  // artifacts named in one line of evidence at most
// An extent read back from the file apply wrote, through the readers'
// chain (to ECEF and back: 1e-9 m of rounding), agrees to this.
constexpr double kExtentAgree_m = 1e-6;
constexpr double kMetresPerDegree = 111319.49;  // of latitude, to 1 %: for the tolerance in degrees

std::string fixed(double v, int decimals) { return format_fixed(v, decimals); }
std::string cm(double m) { return fixed(m * 100.0, 1) + " cm"; }
std::string mm(double m) { return fixed(m * 1000.0, 2) + " mm"; }

std::string join(const std::vector<std::string>& v) { return detail::name_list(v, kListed); }

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

struct Listing {
  std::vector<AuditArtifact> artifacts;
  std::vector<std::string> ignored;
};

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

AuditCheck make_check(std::string name, std::string rule, std::string limit) {
  AuditCheck c;
  c.name = std::move(name);
  c.rule = std::move(rule);
  c.limit = std::move(limit);
  return c;
}

// ----------------------------------------------------------------- metadata

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

AuditCheck check_metadata(const std::vector<AuditArtifact>& arts) {
  AuditCheck c = make_check("metadata",
                            "the map metadata contract (docs/tile-metadata.md, geoanchor.map-metadata/1): a reviewer "
                            "needs each field's value, not \"unknown\"",
                            "every field filled; the coordinate epoch for dynamic frames");
  std::size_t incomplete = 0;
  for (const auto& a : arts) {
    std::vector<std::string> missing;
    const io::MapMetadata* m = contract_of(a);
    if (!a.unreadable.empty()) {
      missing.push_back(a.unreadable);
    } else if (!m) {
      missing.push_back(a.kind == AuditArtifactKind::transform
                            ? "the transform file has no \"metadata\" (written before the contract; fit it again)"
                            : "the sidecar has no \"metadata\" (schema geoanchor.tile/1: apply it again)");
    } else {
      if (!m->frame) missing.push_back("frame");
      bool dynamic = true;
      if (m->frame) {
        try {
          dynamic = geodesy::is_dynamic(geodesy::Frame::parse(*m->frame, "metadata.frame"));
        } catch (const Error&) {
        }
      }
      if (dynamic && !m->coordinate_epoch && !m->coordinate_epoch_range) missing.push_back("coordinate_epoch");
      // An ENU origin is part of the coordinates of a local map (ENU, NED)
      // and of a transform that anchors one; a map in geodetic, ECEF or a
      // CRS's coordinates (moved between frames by a Helmert) has none to
      // state (issue 40 point 6).
      if (needs_enu_origin(a)) {
        if (!m->enu_origin) missing.push_back("enu_origin");
        if (!m->enu_origin_source) missing.push_back("enu_origin_source");
      }
      if (!m->horizontal_crs) missing.push_back("horizontal_crs");
      if (!m->vertical_datum) missing.push_back("vertical_datum");
      if (!m->geoid_model) missing.push_back("geoid_model");
      if (!m->gnss_method) missing.push_back("gnss_method");
      if (!m->gnss_base) missing.push_back("gnss_base");
      if (!m->rtk_fixed_percent) missing.push_back("rtk_fixed_percent");
      if (!m->coordinate_storage) missing.push_back("coordinate_storage");
    }
    if (!missing.empty()) {
      ++incomplete;
      c.evidence.push_back(name_of(a) + ": " + (a.unreadable.empty() && m ? "unknown: " : "") + join(missing));
    }
  }
  c.status = incomplete == 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = incomplete == 0 ? "all " + std::to_string(arts.size()) + " artifacts state every field"
                              : std::to_string(incomplete) + " of " + std::to_string(arts.size()) +
                                    " artifacts lack fields";
  return c;
}

// ---------------------------------------------------------------- one frame

std::string epoch_text(const io::MapMetadata& m) {
  if (m.coordinate_epoch) return format_shortest(*m.coordinate_epoch);
  if (m.coordinate_epoch_range) {
    return format_shortest((*m.coordinate_epoch_range)[0]) + "–" + format_shortest((*m.coordinate_epoch_range)[1]);
  }
  return "unknown";
}

std::string origin_text(const io::MapMetadata& m) {
  if (!m.enu_origin) return "unknown";
  return fixed(m.enu_origin->lat_deg, 9) + ", " + fixed(m.enu_origin->lon_deg, 9) + ", " + fixed(m.enu_origin->h_m, 3) + " m";
}

bool same_origin(const io::MetadataOrigin& a, const io::MetadataOrigin& b) {
  constexpr double kOriginDeg = 1e-8;  // 1.1 mm, as the contract compares origins
  constexpr double kOriginHeight_m = 0.001;
  return std::abs(a.lat_deg - b.lat_deg) <= kOriginDeg && std::abs(a.lon_deg - b.lon_deg) <= kOriginDeg &&
         std::abs(a.h_m - b.h_m) <= kOriginHeight_m;
}

AuditCheck check_one_frame(const std::vector<AuditArtifact>& arts) {
  AuditCheck c = make_check("one_frame",
                            "one reference: every layer of a map in the same frame, realization, coordinate epoch, "
                            "ENU origin and height reference (vertical datum, geoid model), or the layers tear apart",
                            "identical frame and epoch; origins within 1e-8° and 1 mm");
  // Each property: its values, with the artifacts that state each.
  const auto property = [&](const std::string& what, const auto& value_of, const auto& same) {
    std::vector<std::pair<std::string, std::vector<std::string>>> groups;  // value text, artifacts
    std::vector<const io::MapMetadata*> reps;
    for (const auto& a : arts) {
      const io::MapMetadata* m = contract_of(a);
      if (!m) continue;
      const std::optional<std::string> v = value_of(*m);
      if (!v) continue;
      std::size_t g = 0;
      while (g < groups.size() && !same(*reps[g], *m)) ++g;
      if (g == groups.size()) {
        groups.push_back({*v, {}});
        reps.push_back(m);
      }
      groups[g].second.push_back(name_of(a));
    }
    if (groups.size() <= 1) return groups.empty() ? std::string() : groups[0].first;
    // The largest group first; every group with its artifacts.
    std::stable_sort(groups.begin(), groups.end(), [](const auto& x, const auto& y) { return x.second.size() > y.second.size(); });
    std::string line = what + " differs:";
    for (std::size_t g = 0; g < groups.size(); ++g) line += (g ? "; " : " ") + groups[g].first + " in " + join(groups[g].second);
    c.evidence.push_back(line);
    return std::string();
  };
  const std::string frame = property(
      "frame", [](const io::MapMetadata& m) { return m.frame; },
      [](const io::MapMetadata& x, const io::MapMetadata& y) { return x.frame == y.frame; });
  const std::string epoch = property(
      "coordinate epoch",
      [](const io::MapMetadata& m) -> std::optional<std::string> {
        if (!m.coordinate_epoch && !m.coordinate_epoch_range) return std::nullopt;
        return epoch_text(m);
      },
      [](const io::MapMetadata& x, const io::MapMetadata& y) { return epoch_text(x) == epoch_text(y); });
  const std::string origin = property(
      "ENU origin",
      [](const io::MapMetadata& m) -> std::optional<std::string> {
        if (!m.enu_origin) return std::nullopt;
        return origin_text(m);
      },
      [](const io::MapMetadata& x, const io::MapMetadata& y) { return same_origin(*x.enu_origin, *y.enu_origin); });
  property(
      "vertical datum", [](const io::MapMetadata& m) { return m.vertical_datum; },
      [](const io::MapMetadata& x, const io::MapMetadata& y) { return x.vertical_datum == y.vertical_datum; });
  property(
      "geoid model", [](const io::MapMetadata& m) { return m.geoid_model; },
      [](const io::MapMetadata& x, const io::MapMetadata& y) { return x.geoid_model == y.geoid_model; });
  c.status = c.evidence.empty() ? AuditStatus::pass : AuditStatus::fail;
  c.summary = c.evidence.empty() ? "frame " + (frame.empty() ? std::string("unknown") : frame) + ", epoch " +
                                       (epoch.empty() ? std::string("unknown") : epoch) + ", ENU origin " +
                                       (origin.empty() ? std::string("unknown") : origin)
                                 : std::to_string(c.evidence.size()) + " of frame, epoch, origin and height reference differ across the map";
  return c;
}

// -------------------------------------------------------- transforms (moves)

// How a tile was moved: its transform file (by content), direction and
// epoch, as its provenance records it.
struct Move {
  std::string sha256;  // "" without a transform
  bool inverse = false;
  std::optional<double> epoch;
  std::string input_frame, output_frame;
  // A tile read through PROJ: its CRS (WKT2) and PROJ's operations, which
  // audit cannot run again; two tiles read from different CRSs are not
  // compared by their transforms alone.
  std::string input_crs;
  std::string path;  // as recorded
  bool operator==(const Move& o) const {
    return sha256 == o.sha256 && inverse == o.inverse && epoch == o.epoch && input_frame == o.input_frame &&
           output_frame == o.output_frame && input_crs == o.input_crs;
  }
};

Move move_of(const AuditArtifact& a) {
  Move m;
  const nlohmann::json p = provenance(a);
  if (p.contains("transform_sha256") && p["transform_sha256"].is_string()) m.sha256 = p["transform_sha256"].get<std::string>();
  if (p.contains("transform") && p["transform"].is_string()) m.path = p["transform"].get<std::string>();
  if (p.contains("transform_direction") && p["transform_direction"].is_string()) {
    m.inverse = p["transform_direction"].get<std::string>().starts_with("inverse");
  }
  if (p.contains("observation_epoch") && p["observation_epoch"].is_number()) m.epoch = p["observation_epoch"].get<double>();
  if (!m.epoch && p.contains("observation_epoch_range") && p["observation_epoch_range"].is_array() &&
      p["observation_epoch_range"].size() == 2) {
    m.epoch = 0.5 * (p["observation_epoch_range"][0].get<double>() + p["observation_epoch_range"][1].get<double>());
  }
  if (p.contains("input_frame") && p["input_frame"].is_string()) m.input_frame = p["input_frame"].get<std::string>();
  if (p.contains("input_crs_wkt2") && p["input_crs_wkt2"].is_string()) m.input_crs = p["input_crs_wkt2"].get<std::string>();
  if (a.meta && a.meta->frame) m.output_frame = a.meta->frame->to_string();
  return m;
}

// The transform files the map's tiles were moved with, by SHA-256: found
// among the audited artifacts, else at the path each provenance records
// (as written, then beside the sidecar), and checked against the hash.
class Transforms {
 public:
  explicit Transforms(const std::vector<AuditArtifact>& arts) {
    for (const auto& a : arts) {
      if (a.transform) by_sha_.emplace(a.transform_sha256, &*a.transform);
    }
  }
  // nullptr with `why` set when it cannot be had.
  const io::TransformFile* find(const Move& m, const AuditArtifact& tile, std::string& why) {
    if (m.sha256.empty()) return nullptr;
    if (const auto it = by_sha_.find(m.sha256); it != by_sha_.end()) return it->second;
    if (const auto it = loaded_.find(m.sha256); it != loaded_.end()) return &it->second;
    std::vector<fs::path> tries{fs::path(m.path), tile.sidecar.parent_path() / fs::path(m.path).filename()};
    for (const auto& t : tries) {
      std::error_code ec;
      if (m.path.empty() || !fs::is_regular_file(t, ec)) continue;
      try {
        if (sha256_file_hex(t) != m.sha256) {
          why = "the transform file " + t.string() + " it records has changed since (SHA-256 differs)";
          continue;
        }
        return &loaded_.emplace(m.sha256, io::read_transform_file(t)).first->second;
      } catch (const Error& e) {
        why = e.what();
      }
    }
    if (why.empty()) {
      why = "its transform file " + (m.path.empty() ? std::string("(no path recorded)") : m.path) +
            " (SHA-256 " + m.sha256.substr(0, 12) + "…) is neither among the audited files nor at its recorded path";
    }
    return nullptr;
  }

 private:
  std::map<std::string, const io::TransformFile*> by_sha_;
  std::map<std::string, io::TransformFile> loaded_;
};

std::optional<geodesy::DecimalYear> year(std::optional<double> y) {
  if (!y) return std::nullopt;
  return geodesy::DecimalYear{*y};
}

io::ArrayFrame ecef_frame() { return io::ArrayFrame{}; }

// One point of a tile's own coordinates in ECEF (no transform).
std::optional<Eigen::Vector3d> to_ecef(const io::ArrayFrame& f, const Eigen::Vector3d& p) {
  const io::PointChain chain(f, std::nullopt, false, std::nullopt, ecef_frame());
  double a = p.x(), b = p.y(), c = p.z();
  chain.apply({&a, 1}, {&b, 1}, {&c, 1});
  if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c)) return std::nullopt;
  return Eigen::Vector3d(a, b, c);
}

std::optional<Eigen::Vector3d> from_ecef(const io::ArrayFrame& f, const Eigen::Vector3d& x) {
  const io::PointChain chain(ecef_frame(), std::nullopt, false, std::nullopt, f);
  double a = x.x(), b = x.y(), c = x.z();
  chain.apply({&a, 1}, {&b, 1}, {&c, 1});
  if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c)) return std::nullopt;
  return Eigen::Vector3d(a, b, c);
}

// The tile's bounds (output coordinates) from its provenance.
using Box = std::pair<Eigen::Vector3d, Eigen::Vector3d>;

// The bounds a sidecar records (provenance.bounds), in the file's axes.
std::optional<Box> recorded_bounds(const AuditArtifact& a) {
  const nlohmann::json p = provenance(a);
  if (!p.contains("bounds") || !p["bounds"].is_object()) return std::nullopt;
  const auto& b = p["bounds"];
  if (!b.contains("min") || !b.contains("max") || !b["min"].is_array() || !b["max"].is_array() || b["min"].size() != 3 ||
      b["max"].size() != 3) {
    return std::nullopt;
  }
  Eigen::Vector3d lo, hi;
  for (int k = 0; k < 3; ++k) {
    if (!b["min"][static_cast<std::size_t>(k)].is_number() || !b["max"][static_cast<std::size_t>(k)].is_number()) return std::nullopt;
    lo[k] = b["min"][static_cast<std::size_t>(k)].get<double>();
    hi[k] = b["max"][static_cast<std::size_t>(k)].get<double>();
  }
  if (!lo.allFinite() || !hi.allFinite()) return std::nullopt;
  return Box{lo, hi};
}

// Bounds in the file's axes, in the order of the tile's coordinates (lat,
// lon, h for geodetic ones): geodetic files put longitude first in LAS/LAZ
// (X), GeoJSON and OSM, and CSV in the order of its columns.
std::optional<Box> in_coordinate_order(const AuditArtifact& a, Box box) {
  auto& [lo, hi] = box;
  if (a.meta && !a.meta->crs && a.meta->coordinates.kind == io::CoordinateKind::geodetic) {
    const auto format = io::tile_format_of(a.path);
    bool lon_first = false;
    if (format == io::TileFormat::csv) {
      // The column order the CSV reader itself finds in the header.
      std::ifstream in(a.path, std::ios::binary);
      try {
        const io::CsvReader csv(in, a.path.string());
        const io::CoordinateColumns columns = io::classify_coordinate_header(csv.header(), a.path.string());
        if (columns.kind != io::CoordinateKind::geodetic) return std::nullopt;
        lon_first = columns.second < columns.first;  // (lat, lon, h) in the kind's order
      } catch (const Error&) {
        return std::nullopt;
      }
    } else if (format == io::TileFormat::ply || !format) {
      return std::nullopt;  // no stated axis order
    } else {
      lon_first = true;
    }
    if (lon_first) std::swap(lo[0], lo[1]), std::swap(hi[0], hi[1]);
  }
  return box;
}

std::optional<Box> bounds_of(const AuditArtifact& a) {
  const auto recorded = recorded_bounds(a);
  return recorded ? in_coordinate_order(a, *recorded) : std::nullopt;
}

// Two extents of the same points (file axes) agree: the reader gives back
// the numbers apply wrote, so they differ by rounding at most. Geodetic
// files hold degrees on their two horizontal axes (X, Y; or the CSV's
// first two coordinate columns) and metres on the third.
// Vector maps are compared horizontally: a position without a height (2-D
// GeoJSON, a Lanelet2 node without ele) is moved at h = 0 and written
// without one, so its moved height is in the recorded bounds and not in the
// file (the data check covers every byte).
bool same_extent(const AuditArtifact& a, const Box& x, const Box& y) {
  const bool degrees = a.meta && a.meta->coordinates.kind == io::CoordinateKind::geodetic;
  const auto format = io::tile_format_of(a.path);
  const int axes = format && io::is_vector_map(*format) ? 2 : 3;
  for (int k = 0; k < axes; ++k) {
    const double tolerance = degrees && k < 2 ? kExtentAgree_m / kMetresPerDegree : kExtentAgree_m;
    if (!(std::abs(x.first[k] - y.first[k]) <= tolerance) || !(std::abs(x.second[k] - y.second[k]) <= tolerance)) return false;
  }
  return true;
}

std::string box_text(const Box& b) {
  std::string t;
  for (int k = 0; k < 3; ++k) {
    t += std::string(k ? ", " : "") + format_shortest(b.first[k]) + " to " + format_shortest(b.second[k]);
  }
  return t;
}

// The eight corners of a box.
std::vector<Eigen::Vector3d> corners(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < 8; ++i) v.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  return v;
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

// A tile's footprint: its bounds' corners in the map's ENU.
struct Footprint {
  const AuditArtifact* tile = nullptr;
  Eigen::Vector3d lo, hi;  // ENU at the map's origin
  Move move;
};

// Residual of `x` against `ref` in ENU at `ref`.
Eigen::Vector3d enu_difference(const Eigen::Vector3d& ref, const Eigen::Vector3d& x) {
  const geodesy::GeodeticPosition g = geodesy::geodetic_from_ecef(geodesy::Ellipsoid::grs80(), geodesy::EcefPosition(ref));
  return geodesy::enu_from_ecef_rotation(g.lat, g.lon) * (x - ref);
}

// ---------------------------------------------------------------- seams

AuditCheck check_seams(const std::vector<AuditArtifact>& arts, const AuditLimits& l, Transforms& transforms) {
  AuditCheck c = make_check("seams",
                            "no seams: where two tiles meet, the same ground point must come out of both tiles' "
                            "transforms and frames at the same place",
                            "3-D separation ≤ " + cm(l.seam_m) + " (--max-seam-m); tiles closer than " +
                                fixed(l.adjacency_gap_m, 1) + " m share a boundary");
  std::vector<Footprint> tiles;
  std::optional<geodesy::LocalOrigin> origin = map_origin(arts);
  if (!origin) {
    // A map in geodetic, ECEF or projected coordinates states no ENU
    // origin: its footprints are compared in a tangent plane of their own,
    // at the first corner of the first tile with bounds (any plane serves a
    // comparison; issue 40 point 6).
    for (const auto& a : arts) {
      if (a.kind == AuditArtifactKind::transform || !a.meta || a.meta->crs) continue;
      const auto b = bounds_of(a);
      if (!b) continue;
      if (const auto x = to_ecef(a.meta->coordinates, corners(b->first, b->second).front())) {
        origin = geodesy::LocalOrigin{geodesy::geodetic_from_ecef(geodesy::Ellipsoid::grs80(), geodesy::EcefPosition(*x)),
                                      geodesy::Ellipsoid::grs80()};
        break;
      }
    }
  }
  std::size_t not_checked = 0, moved_tiles = 0;
  for (const auto& a : arts) {
    // Tiles and vector maps: a layer moved otherwise than the tiles under it tears from them.
    if (a.kind == AuditArtifactKind::transform) continue;
    if (!a.meta) continue;  // the metadata check names it
    if (a.meta->crs) {
      c.evidence.push_back(name_of(a) + ": not checked: its coordinates are in " + a.meta->crs->display_name() +
                           " (a PROJ CRS); audit checks seams between tiles in geoanchor's own coordinates");
      ++not_checked;
      continue;
    }
    // The footprint of the points the file holds now, which must be those
    // the sidecar records (a tile changed after apply is named here too).
    Box points;
    try {
      std::optional<std::string> local_xy;  // a Lanelet2 map's, as apply recorded it
      const nlohmann::json prov = provenance(a);
      const nlohmann::json::json_pointer projection("/osm/local_xy/projection");
      if (prov.contains(projection) && prov.at(projection).is_string()) local_xy = prov.at(projection).get<std::string>();
      points = detail::point_extent(a.path, a.meta->coordinates, local_xy);
    } catch (const Error& e) {
      c.evidence.push_back(name_of(a) + ": not checked: its points cannot be read: " + e.what());
      ++not_checked;
      continue;
    }
    const auto recorded = recorded_bounds(a);
    if (!recorded) {
      c.evidence.push_back(name_of(a) + ": not checked: its sidecar records no bounds (provenance.bounds)");
      ++not_checked;
      continue;
    }
    if (!same_extent(a, points, *recorded)) {
      c.evidence.push_back(name_of(a) + ": FAIL its points span " + box_text(points) + " (file axes) but its sidecar records " +
                           box_text(*recorded) + ": the points changed after apply");
      ++moved_tiles;
    }
    const auto b = in_coordinate_order(a, points);
    if (!b) {
      c.evidence.push_back(name_of(a) + ": not checked: its axes' order is not stated");
      ++not_checked;
      continue;
    }
    Footprint f{&a, Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()),
                Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity()), move_of(a)};
    bool ok = true;
    for (const auto& corner : corners(b->first, b->second)) {
      const auto x = to_ecef(a.meta->coordinates, corner);
      if (!x || !origin) {
        ok = false;
        break;
      }
      const Eigen::Vector3d e = geodesy::LocalTangentPlane(*origin).enu_from_ecef(geodesy::EcefPosition(*x)).enu_m;
      f.lo = f.lo.cwiseMin(e);
      f.hi = f.hi.cwiseMax(e);
    }
    if (!ok) {
      c.evidence.push_back(name_of(a) + ": not checked: " +
                           (origin ? "its bounds do not convert to ECEF" : "the map states no ENU origin to compare tiles in"));
      ++not_checked;
      continue;
    }
    tiles.push_back(f);
  }
  std::size_t pairs = 0, failing = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    for (std::size_t j = i + 1; j < tiles.size(); ++j) {
      const Footprint &A = tiles[i], &B = tiles[j];
      Eigen::Vector2d lo, hi;
      bool near = true;
      for (int k = 0; k < 2; ++k) {
        lo[k] = std::max(A.lo[k], B.lo[k]);
        hi[k] = std::min(A.hi[k], B.hi[k]);
        if (lo[k] > hi[k] + l.adjacency_gap_m) near = false;
        if (lo[k] > hi[k]) lo[k] = hi[k] = 0.5 * (lo[k] + hi[k]);  // a gap: its middle
      }
      if (!near) continue;
      ++pairs;
      const std::string pair_name = name_of(*A.tile) + " | " + name_of(*B.tile);
      if (A.move == B.move) continue;  // the same transform, frames and epoch: no seam by construction
      std::string why_a, why_b;
      const io::TransformFile* ta = transforms.find(A.move, *A.tile, why_a);
      const io::TransformFile* tb = transforms.find(B.move, *B.tile, why_b);
      if ((!A.move.sha256.empty() && !ta) || (!B.move.sha256.empty() && !tb)) {
        c.evidence.push_back(pair_name + ": not checked: " + name_of(!ta && !A.move.sha256.empty() ? *A.tile : *B.tile) + ": " +
                             (!ta && !A.move.sha256.empty() ? why_a : why_b));
        ++failing;
        continue;
      }
      const auto source_of = [](const Move& m, const io::TransformFile* t) {
        if (!t) return m.output_frame.empty() ? std::string("?") : m.output_frame;
        const auto& f = m.inverse ? t->target_frame : t->source_frame;
        return f ? f->to_string() : std::string("?");
      };
      if (A.move.input_crs != B.move.input_crs) {
        c.evidence.push_back(pair_name + ": not checked: the two were read from different coordinate systems through PROJ, "
                                         "whose operations audit cannot run again");
        ++failing;
        continue;
      }
      if ((!ta && A.move.input_frame != A.move.output_frame) || (!tb && B.move.input_frame != B.move.output_frame) ||
          source_of(A.move, ta) != source_of(B.move, tb)) {
        c.evidence.push_back(pair_name + ": not checked: the tiles come from different frames (" + source_of(A.move, ta) +
                             ", " + source_of(B.move, tb) + ") or were moved between frames without a transform file");
        ++failing;
        continue;
      }
      const double z = 0.25 * (A.lo.z() + A.hi.z() + B.lo.z() + B.hi.z());
      std::vector<Eigen::Vector3d> samples{{lo.x(), lo.y(), z}, {hi.x(), lo.y(), z}, {lo.x(), hi.y(), z}, {hi.x(), hi.y(), z},
                                           {0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), z}};
      double pair_worst = -1.0;
      Eigen::Vector3d at = samples.back(), d_worst = Eigen::Vector3d::Zero();
      bool failed_eval = false;
      for (const auto& s : samples) {
        try {
          const Eigen::Vector3d p = geodesy::LocalTangentPlane(*origin).ecef_from_enu(geodesy::EnuPosition{s, *origin}).m;
          const geodesy::EcefPosition src =
              ta ? ta->apply(geodesy::EcefPosition(p), year(A.move.epoch), !A.move.inverse, "seam") : geodesy::EcefPosition(p);
          const geodesy::EcefPosition back = tb ? tb->apply(src, year(B.move.epoch), B.move.inverse, "seam") : src;
          const Eigen::Vector3d d = enu_difference(p, back.m);
          const double dist = d.norm();
          if (!std::isfinite(dist)) throw Error(ErrorKind::input, "E_SEAM", "not finite");
          if (dist > pair_worst) pair_worst = dist, at = s, d_worst = d;
        } catch (const Error& e) {
          c.evidence.push_back(pair_name + ": not checked: " + e.what());
          failed_eval = true;
          break;
        }
      }
      if (failed_eval) {
        ++failing;
        continue;
      }
      worst = std::max(worst, pair_worst);
      if (!(pair_worst <= l.seam_m)) {
        ++failing;
        c.evidence.push_back(pair_name + ": " + cm(pair_worst) + " apart (east " + cm(d_worst.x()) + ", north " +
                             cm(d_worst.y()) + ", up " + cm(d_worst.z()) + ") at map ENU " + fixed(at.x(), 1) + ", " +
                             fixed(at.y(), 1) + " m");
      } else {
        c.evidence.push_back(pair_name + ": " + mm(pair_worst) + " apart (moved differently)");
      }
    }
  }
  c.status = failing == 0 && not_checked == 0 && moved_tiles == 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = std::to_string(pairs) + " shared boundaries or overlaps among " + std::to_string(tiles.size()) +
              " tiles and vector maps (their extents read from their points); " +
              (failing ? std::to_string(failing) + " fail" : "largest separation " + mm(worst)) +
              (moved_tiles ? "; " + std::to_string(moved_tiles) + " tiles' points differ from their sidecars' bounds" : "") +
              (not_checked ? "; " + std::to_string(not_checked) + " tiles not checked" : "");
  return c;
}

// ------------------------------------------------------------ checkpoints

AuditCheck check_checkpoints(const std::vector<AuditArtifact>& arts, const AuditRequest& request, Transforms& transforms) {
  const AuditLimits& l = request.limits;
  AuditCheck c = make_check("checkpoints",
                            "airside map accuracy: surveyed checkpoints against the map's transform of their source "
                            "positions",
                            "horizontal ≤ " + cm(l.checkpoint_horizontal_m) + " (--max-checkpoint-horizontal-m), vertical ≤ " +
                                cm(l.checkpoint_vertical_m) + " (--max-checkpoint-vertical-m)");
  if (!request.checkpoints) {
    c.status = AuditStatus::not_run;
    c.summary = "no --checkpoints given";
    return c;
  }
  io::ControlReadOptions read;
  read.origin = map_origin(arts);  // for ENU columns: the map's origin
  const geodesy::ControlSet set = request.checkpoints_dst
                                      ? io::read_control_pair(*request.checkpoints, *request.checkpoints_dst, read)
                                      : io::read_control_set(*request.checkpoints, read);
  // The map's moves: one for the whole map, or the tile's whose bounds hold the mark.
  std::vector<std::pair<const AuditArtifact*, Move>> moves;
  for (const auto& a : arts) {
    if (a.meta && a.kind != AuditArtifactKind::transform) moves.push_back({&a, move_of(a)});
  }
  std::vector<Move> distinct;
  for (const auto& [a, m] : moves) {
    if (std::find(distinct.begin(), distinct.end(), m) == distinct.end()) distinct.push_back(m);
  }
  if (distinct.empty()) {
    c.status = AuditStatus::fail;
    c.summary = "the map has no tile or vector map with a sidecar to take its transform from";
    return c;
  }
  std::size_t failing = 0, checked = 0;
  double worst_h = 0.0, worst_v = 0.0;
  for (const auto& p : set.points) {
    if (!p.use) continue;
    // Which move: the only one, or the tile's that holds the target.
    const AuditArtifact* tile = moves.front().first;
    Move move = distinct.front();
    if (distinct.size() > 1) {
      tile = nullptr;
      for (const auto& [a, m] : moves) {
        const auto b = bounds_of(*a);
        if (!b || a->meta->crs) continue;
        const auto x = from_ecef(a->meta->coordinates, p.target.m);
        if (x && x->x() >= b->first.x() && x->x() <= b->second.x() && x->y() >= b->first.y() && x->y() <= b->second.y()) {
          tile = a;
          move = m;
          break;
        }
      }
      if (!tile) {
        ++failing;
        c.evidence.push_back(p.id + ": no tile holds it, and the map's tiles were moved differently: which transform is "
                                    "the map's there is unknown");
        continue;
      }
    }
    std::string why;
    const io::TransformFile* t = transforms.find(move, *tile, why);
    if (!move.sha256.empty() && !t) {
      ++failing;
      c.evidence.push_back(p.id + ": not checked: " + name_of(*tile) + ": " + why);
      continue;
    }
    // The control set's frames must be stated, and be the transform's
    // (without one: the map's own frame on both sides).
    if (!set.source_frame || !set.target_frame) {
      throw Error(ErrorKind::input, "E_CHECKPOINT_FRAME",
                  *request.checkpoints + ": the checkpoints state no " + (!set.source_frame ? "source" : "target") +
                      " frame ('# source_frame = NAME@EPOCH' / '# target_frame = …', or '# frame = …' in each file of a "
                      "pair): a checkpoint compared in an unknown frame proves nothing");
    }
    for (const auto* f : {&set.source_frame, &set.target_frame}) {
      geodesy::require_epoch_if_dynamic(**f, *request.checkpoints + ": the checkpoints' frame");
    }
    if (!t && (set.source_frame->to_string() != move.output_frame || set.target_frame->to_string() != move.output_frame)) {
      throw Error(ErrorKind::input, "E_CHECKPOINT_FRAME",
                  *request.checkpoints + ": its frames (" + set.source_frame->to_string() + " -> " + set.target_frame->to_string() +
                      ") are not the map's " + (move.output_frame.empty() ? std::string("(unknown)") : move.output_frame) +
                      ", which no transform file moved");
    }
    if (t) {
      const auto& from = move.inverse ? t->target_frame : t->source_frame;
      const auto& to = move.inverse ? t->source_frame : t->target_frame;
      // The same frame, and the same coordinate epoch where both name one.
      const auto differs = [](const std::optional<geodesy::Frame>& a, const std::optional<geodesy::Frame>& b) {
        if (!a || !b) return false;  // the transform names none: the set's is taken
        if (a->name() != b->name()) return true;
        return a->epoch().has_value() != b->epoch().has_value() || (a->epoch() && a->epoch()->year != b->epoch()->year);
      };
      if (differs(set.source_frame, from) || differs(set.target_frame, to)) {
        throw Error(ErrorKind::input, "E_CHECKPOINT_FRAME",
                    *request.checkpoints + ": its frames (" + (set.source_frame ? set.source_frame->to_string() : "?") + " -> " +
                        (set.target_frame ? set.target_frame->to_string() : "?") + ") are not the map's transform's (" +
                        (from ? from->to_string() : "?") + " -> " + (to ? to->to_string() : "?") + ")");
      }
    }
    const std::optional<geodesy::DecimalYear> epoch = p.epoch ? p.epoch : year(move.epoch);
    Eigen::Vector3d moved = p.source.m;
    std::optional<Eigen::Matrix3d> cov;
    try {
      if (t) {
        moved = t->apply(p.source, epoch, move.inverse, *request.checkpoints + ": " + p.id).m;
        cov = propagated_covariance_m2(*t, p.source, epoch, move.inverse);
      }
    } catch (const Error& e) {
      ++failing;
      c.evidence.push_back(p.id + ": not checked: " + e.what());
      continue;
    }
    ++checked;
    // Surveyed − map (measured minus map), ENU at the mark: the sign of
    // fit's residuals (target − transformed source), one convention
    // everywhere (issue 40 point 11; docs/conventions.md).
    const Eigen::Vector3d d = -enu_difference(p.target.m, moved);
    const double h = std::hypot(d.x(), d.y()), v = std::abs(d.z());
    worst_h = std::max(worst_h, h);
    worst_v = std::max(worst_v, v);
    std::string sigma = "the map's transform carries no uncertainty";
    if (cov && cov->allFinite()) {
      const geodesy::GeodeticPosition g = geodesy::geodetic_from_ecef(geodesy::Ellipsoid::grs80(), p.target);
      const Eigen::Matrix3d r = geodesy::enu_from_ecef_rotation(g.lat, g.lon);
      const Eigen::Matrix3d enu = r * *cov * r.transpose();
      const auto sd = [&](int k) { return mm(std::sqrt(std::max(0.0, enu(k, k)))); };  // a variance rounded below 0 is 0
      sigma = "propagated σ east " + sd(0) + ", north " + sd(1) + ", up " + sd(2);
    }
    const bool bad = !(h <= l.checkpoint_horizontal_m) || !(v <= l.checkpoint_vertical_m);
    if (bad) ++failing;
    c.evidence.push_back(p.id + ": " + (bad ? "FAIL " : "") + "horizontal " + cm(h) + ", vertical " + cm(d.z()) + " (east " +
                         cm(d.x()) + ", north " + cm(d.y()) + "); " + sigma);
  }
  c.status = failing == 0 && checked > 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = std::to_string(checked) + " checkpoints of " + *request.checkpoints + ": largest horizontal " + cm(worst_h) +
              ", vertical " + cm(worst_v) + (failing ? "; " + std::to_string(failing) + " fail" : "");
  if (checked == 0 && failing == 0) c.summary = *request.checkpoints + " has no checkpoint in use";
  return c;
}

// ------------------------------------------------------------- the others

AuditCheck check_rtk(const std::vector<AuditArtifact>& arts, const AuditLimits& l) {
  AuditCheck c = make_check("rtk_fixed_share",
                            "survey quality: positions from ambiguity-fixed carrier phase (RTK fixed or PPK); float and "
                            "code solutions are decimetre-level",
                            "≥ " + fixed(l.min_rtk_fixed_percent, 1) + " % (--min-rtk-fixed-percent)");
  std::size_t bad = 0, n = 0;
  double lowest = 100.0;
  for (const auto& a : arts) {
    if (a.kind == AuditArtifactKind::transform) continue;
    ++n;
    const io::MapMetadata* m = contract_of(a);
    if (!m || !m->rtk_fixed_percent) {
      ++bad;
      c.evidence.push_back(name_of(a) + ": RTK-fixed share unknown");
      continue;
    }
    lowest = std::min(lowest, *m->rtk_fixed_percent);
    if (!(*m->rtk_fixed_percent >= l.min_rtk_fixed_percent)) {
      ++bad;
      c.evidence.push_back(name_of(a) + ": " + fixed(*m->rtk_fixed_percent, 1) + " %" +
                           (m->rtk_fixed_from ? " (" + *m->rtk_fixed_from + ")" : ""));
    }
  }
  c.status = bad == 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = bad == 0 ? "lowest " + fixed(lowest, 1) + " % over " + std::to_string(n) + " tiles and vector maps"
                       : std::to_string(bad) + " of " + std::to_string(n) + " below the limit or unknown";
  return c;
}

bool float32_storage(const AuditArtifact& a) {
  if (a.meta && a.meta->storage == "float32") return true;
  const io::MapMetadata* m = contract_of(a);
  return m && m->coordinate_storage && m->coordinate_storage->find("float32") != std::string::npos;
}

std::string kind_of(const AuditArtifact& a) {
  if (a.meta) return io::kind_name(*a.meta);
  return "";
}

AuditCheck check_float32_ecef(const std::vector<AuditArtifact>& arts) {
  AuditCheck c = make_check("no_float32_ecef",
                            "float32 keeps 24 significant bits: at the Earth's radius its spacing is 0.5 m, so ECEF "
                            "coordinates in float32 lose up to 25 cm",
                            "no ECEF coordinates stored as float32");
  for (const auto& a : arts) {
    const io::MapMetadata* m = contract_of(a);
    const bool ecef_text = m && m->coordinate_storage && m->coordinate_storage->find("float32 ECEF") != std::string::npos;
    if ((float32_storage(a) && kind_of(a) == "ecef") || ecef_text) {
      c.evidence.push_back(name_of(a) + ": " + (m && m->coordinate_storage ? *m->coordinate_storage : std::string("float32 ECEF")) +
                           " (spacing " + cm(float32_spacing(6.4e6)) + " at 6 400 km)");
    }
  }
  c.status = c.evidence.empty() ? AuditStatus::pass : AuditStatus::fail;
  c.summary = c.evidence.empty() ? "none" : std::to_string(c.evidence.size()) + " artifacts store float32 ECEF";
  return c;
}

// The largest |coordinate| of a float32 artifact in metres (ENU, NED,
// projected) or the spacing in metres of its angles (geodetic).
AuditCheck check_float32_resolution(const std::vector<AuditArtifact>& arts, const AuditLimits& l) {
  AuditCheck c = make_check("float32_resolution",
                            "float32 offsets: their spacing grows with the distance from the origin (1 mm from 8 192 m, "
                            "2 mm from 16 384 m)",
                            "spacing ≤ " + mm(l.float32_resolution_m) + " (--max-float32-spacing-m) over the extent");
  std::size_t n = 0, bad = 0;
  double worst = 0.0;
  for (const auto& a : arts) {
    if (!float32_storage(a) || kind_of(a) == "ecef") continue;
    ++n;
    if (a.meta && a.meta->crs) {
      ++bad;
      c.evidence.push_back(name_of(a) + ": float32 in " + a.meta->crs->display_name() +
                           " (a PROJ CRS): its units and spacing are not checked here");
      continue;
    }
    const auto b = bounds_of(a);
    if (!b) {
      ++bad;
      c.evidence.push_back(name_of(a) + ": float32 with no bounds recorded (provenance.bounds): its extent is unknown");
      continue;
    }
    double spacing = 0.0;
    const std::string kind = kind_of(a);
    for (int k = 0; k < 3; ++k) {
      const double largest = std::max(std::abs(b->first[k]), std::abs(b->second[k]));
      double s = float32_spacing(largest);
      if (kind == "geodetic" && k < 2) s *= 111'320.0;  // metres per degree on the equator, the largest
      spacing = std::max(spacing, s);
    }
    worst = std::max(worst, spacing);
    const bool fails = !(spacing <= l.float32_resolution_m);
    if (fails) ++bad;
    c.evidence.push_back(name_of(a) + ": " + (fails ? "FAIL " : "") + "spacing " + mm(spacing) + " at its largest offset");
  }
  c.status = bad == 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = n == 0 ? "no float32 offsets in the map" : "largest spacing " + mm(worst) + " over " + std::to_string(n) + " float32 artifacts";
  return c;
}

AuditCheck check_tangent_plane(const std::vector<AuditArtifact>& arts, const AuditLimits& l) {
  AuditCheck c = make_check("tangent_plane",
                            "a tangent plane departs from the ellipsoid by d²/2R at distance d from its origin: a map "
                            "read as flat (up taken as height) is that much off at its edge",
                            "d²/2R ≤ " + cm(l.tangent_plane_m) + " (--max-tangent-departure-m)");
  if (std::none_of(arts.begin(), arts.end(), [](const AuditArtifact& a) { return a.kind != AuditArtifactKind::transform && needs_enu_origin(a); })) {
    c.status = AuditStatus::not_run;
    c.summary = "no tile or vector map of the map is in ENU/NED coordinates: no tangent plane to check";
    return c;
  }
  const std::optional<geodesy::LocalOrigin> origin = map_origin(arts);
  if (!origin) {
    c.status = AuditStatus::fail;
    c.summary = "the map states no ENU origin: its extent from the origin is unknown";
    return c;
  }
  const geodesy::LocalTangentPlane plane(*origin);
  double far = 0.0;
  std::string farthest;
  std::size_t unknown = 0;
  for (const auto& a : arts) {
    if (a.kind == AuditArtifactKind::transform || !a.meta) continue;
    const auto b = bounds_of(a);
    if (!b || a.meta->crs) {
      ++unknown;
      c.evidence.push_back(name_of(a) + ": extent not known (" + (a.meta->crs ? "a PROJ CRS" : "no bounds recorded") + ")");
      continue;
    }
    for (const auto& corner : corners(b->first, b->second)) {
      const auto x = to_ecef(a.meta->coordinates, corner);
      if (!x) {
        ++unknown;
        c.evidence.push_back(name_of(a) + ": extent not known (a corner of its bounds does not convert)");
        break;
      }
      const Eigen::Vector3d e = plane.enu_from_ecef(geodesy::EcefPosition(*x)).enu_m;
      const double d = std::hypot(e.x(), e.y());
      if (d > far) far = d, farthest = name_of(a);
    }
  }
  const double departure = tangent_plane_departure_m(far, origin->point.lat.deg(), origin->ellipsoid);
  c.status = departure <= l.tangent_plane_m && unknown == 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = "extent " + fixed(far / 1000.0, 3) + " km from the origin" + (farthest.empty() ? "" : " (" + farthest + ")") +
              ": d²/2R = " + cm(departure);
  return c;
}

AuditCheck check_web_mercator(const std::vector<AuditArtifact>& arts) {
  AuditCheck c = make_check("no_web_mercator",
                            "EPSG:3857 (WGS 84 / Pseudo-Mercator) is a visualisation CRS: spherical formulas on the "
                            "WGS 84 ellipsoid, not conformal, with scale errors of up to 0.7 % (EPSG's remark on the CRS)",
                            "no artifact in, or moved from, Web Mercator");
  for (const auto& a : arts) {
    std::vector<std::string> texts;
    if (a.meta) {
      texts.push_back(a.meta->horizontal_crs);
      if (a.meta->crs) texts.push_back(a.meta->crs->display_name()), texts.push_back(a.meta->crs->wkt2());
      const nlohmann::json p = provenance(a);
      for (const char* k : {"input_crs", "input_crs_wkt2"}) {
        if (p.contains(k) && p[k].is_string()) texts.push_back(p[k].get<std::string>());
      }
    }
    if (const io::MapMetadata* m = contract_of(a); m && m->horizontal_crs) texts.push_back(*m->horizontal_crs);
    if (a.transform) texts.push_back(io::to_json_text(*a.transform));
    for (const auto& t : texts) {
      const std::string hit = web_mercator_mention(t);
      if (!hit.empty()) {
        c.evidence.push_back(name_of(a) + ": " + hit);
        break;
      }
    }
  }
  c.status = c.evidence.empty() ? AuditStatus::pass : AuditStatus::fail;
  c.summary = c.evidence.empty() ? "none in " + std::to_string(arts.size()) + " artifacts"
                                 : std::to_string(c.evidence.size()) + " artifacts in or from Web Mercator";
  return c;
}

}  // namespace

std::string_view to_string(AuditArtifactKind k) {
  switch (k) {
    case AuditArtifactKind::tile: return "tile";
    case AuditArtifactKind::vector_map: return "vector map";
    case AuditArtifactKind::transform: return "transform file";
  }
  return "?";
}

std::string_view to_string(AuditStatus s) {
  switch (s) {
    case AuditStatus::pass: return "pass";
    case AuditStatus::fail: return "fail";
    case AuditStatus::not_run: return "not run";
  }
  return "?";
}

bool AuditResult::passed() const {
  return std::none_of(checks.begin(), checks.end(), [](const AuditCheck& c) { return c.status == AuditStatus::fail; });
}

double float32_spacing(double x) {
  const float f = static_cast<float>(std::abs(x));
  return static_cast<double>(std::nextafter(f, std::numeric_limits<float>::infinity()) - f);
}

double tangent_plane_departure_m(double distance_m, double lat_deg, const geodesy::Ellipsoid& e) {
  const double s = std::sin(lat_deg * std::numbers::pi / 180.0);
  const double w2 = 1.0 - e.e2() * s * s;
  const double n = e.a_m() / std::sqrt(w2), m = e.a_m() * (1.0 - e.e2()) / (w2 * std::sqrt(w2));
  const double r = std::sqrt(m * n);  // Gaussian mean radius of curvature
  return distance_m * distance_m / (2.0 * r);
}

std::string web_mercator_mention(std::string_view text) {
  std::string low(text);
  std::transform(low.begin(), low.end(), low.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  std::string squeezed;  // without blanks and quotes: ID["EPSG",3857] -> id[epsg,3857]
  for (const char ch : low) {
    if (ch != ' ' && ch != '"' && ch != '\'' && ch != '\t' && ch != '\n') squeezed += ch;
  }
  for (const char* name : {"pseudo-mercator", "pseudo mercator", "popular visualisation", "popular visualization", "web mercator",
                           "web_mercator", "google mercator"}) {
    if (low.find(name) != std::string::npos) return "names \"" + std::string(name) + "\"";
  }
  for (const char* code : {"epsg:3857", "epsg,3857]", "epsg::3857", "epsg:900913", "epsg,900913]", "epsg:3785", "epsg,3785]",
                           "esri:102100", "esri,102100]", "esri:102113", "esri,102113]", "epsg:102100"}) {
    const std::string c(code);
    const auto at = squeezed.find(c);
    if (at != std::string::npos) {
      const std::size_t end = at + c.size();
      if (c.back() == ']' || end == squeezed.size() || !std::isdigit(static_cast<unsigned char>(squeezed[end]))) {
        return "identified as " + c;
      }
    }
  }
  if (squeezed.find("+proj=merc") != std::string::npos &&
      (squeezed.find("+a=6378137+b=6378137") != std::string::npos || squeezed.find("+r=6378137") != std::string::npos)) {
    return "a spherical +proj=merc on the WGS 84 semi-major axis";
  }
  return "";
}

// ---------------------------------------------------------------- data

// Each tile and vector map is the file apply wrote: the SHA-256 its
// sidecar's provenance records (issue 40 point 6). A tile changed by a byte
// after apply no longer matches, whatever its sidecar says.
AuditCheck check_data(const std::vector<AuditArtifact>& arts) {
  AuditCheck c = make_check("data",
                            "the files are the ones their sidecars describe: a tile or map edited after it was written "
                            "carries metadata that no longer holds",
                            "SHA-256 of each file = its sidecar's provenance.output_sha256");
  std::size_t checked = 0, bad = 0;
  for (const auto& a : arts) {
    if (a.kind == AuditArtifactKind::transform) continue;
    ++checked;
    std::string recorded;
    if (a.meta && !a.meta->provenance_json.empty()) {
      const json prov = json::parse(a.meta->provenance_json);
      if (prov.contains("output_sha256") && prov.at("output_sha256").is_string()) recorded = prov.at("output_sha256");
    }
    if (recorded.empty()) {
      ++bad;
      c.evidence.push_back(name_of(a) + ": FAIL its sidecar records no output_sha256 (not written by geoanchor apply, or by "
                                        "one before it recorded it): its data cannot be verified; apply it again");
      continue;
    }
    std::string actual;
    try {
      actual = sha256_file_hex(a.path);
    } catch (const Error& e) {
      ++bad;
      c.evidence.push_back(name_of(a) + ": FAIL " + e.what());
      continue;
    }
    if (actual != recorded) {
      ++bad;
      c.evidence.push_back(name_of(a) + ": FAIL the file's SHA-256 is " + actual + ", its sidecar records " + recorded +
                           ": the file was changed after it was written");
    } else {
      c.evidence.push_back(name_of(a) + ": SHA-256 " + actual.substr(0, 16) + "… as recorded");
    }
  }
  c.status = bad == 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = bad == 0 ? "all " + std::to_string(checked) + " tiles and maps are the files their sidecars record"
                       : std::to_string(bad) + " of " + std::to_string(checked) + " tiles and maps do not match their sidecars";
  return c;
}

AuditResult audit_map(const AuditRequest& request) {
  const AuditLimits& l = request.limits;
  for (const auto& [v, flag] : {std::pair{l.checkpoint_horizontal_m, "--max-checkpoint-horizontal-m"},
                                {l.checkpoint_vertical_m, "--max-checkpoint-vertical-m"}, {l.seam_m, "--max-seam-m"},
                                {l.float32_resolution_m, "--max-float32-spacing-m"}, {l.tangent_plane_m, "--max-tangent-departure-m"},
                                {l.adjacency_gap_m, "--adjacency-gap-m"}}) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw Error(ErrorKind::usage, "E_OPTION", std::string(flag) + " " + format_shortest(v) + ": expected a positive length in metres");
    }
  }
  if (!(l.min_rtk_fixed_percent >= 0.0 && l.min_rtk_fixed_percent <= 100.0)) {
    throw Error(ErrorKind::usage, "E_OPTION", "--min-rtk-fixed-percent " + format_shortest(l.min_rtk_fixed_percent) + ": expected 0 to 100");
  }
  Listing listing = list_artifacts(request);
  AuditResult r;
  r.artifacts = std::move(listing.artifacts);
  r.ignored = std::move(listing.ignored);
  for (auto& a : r.artifacts) read_artifact(a);
  // A map is its tiles and vector maps: a folder of transforms alone is none
  // (it passed with 0 tiles).
  if (std::none_of(r.artifacts.begin(), r.artifacts.end(), [](const AuditArtifact& a) { return a.kind != AuditArtifactKind::transform; })) {
    std::string given;
    for (const auto& m : request.inputs) given += (given.empty() ? "" : ", ") + m;
    throw Error(ErrorKind::input, "E_MAP_EMPTY",
                given + ": no tile or vector map to audit (" + std::to_string(r.artifacts.size()) +
                    " transform files): a map's audit needs its tiles and maps with their sidecars");
  }
  Transforms transforms(r.artifacts);
  r.checks.push_back(check_data(r.artifacts));
  r.checks.push_back(check_metadata(r.artifacts));
  r.checks.push_back(check_one_frame(r.artifacts));
  r.checks.push_back(check_seams(r.artifacts, l, transforms));
  r.checks.push_back(check_checkpoints(r.artifacts, request, transforms));
  r.checks.push_back(check_rtk(r.artifacts, l));
  r.checks.push_back(check_float32_ecef(r.artifacts));
  r.checks.push_back(check_float32_resolution(r.artifacts, l));
  r.checks.push_back(check_tangent_plane(r.artifacts, l));
  r.checks.push_back(check_web_mercator(r.artifacts));
  return r;
}

std::string audit_text(const AuditResult& r) {
  std::ostringstream out;
  std::size_t tiles = 0, vectors = 0, transforms = 0;
  for (const auto& a : r.artifacts) {
    (a.kind == AuditArtifactKind::tile ? tiles : a.kind == AuditArtifactKind::vector_map ? vectors : transforms) += 1;
  }
  out << "geoanchor audit: " << r.artifacts.size() << " artifacts (" << tiles << " tiles, " << vectors << " vector maps, "
      << transforms << " transform files)\n";
  std::size_t failed = 0;
  for (const auto& c : r.checks) {
    const char* verdict = c.status == AuditStatus::pass ? "PASS" : c.status == AuditStatus::fail ? "FAIL" : "----";
    if (c.status == AuditStatus::fail) ++failed;
    out << verdict << "  " << c.name << ": " << c.summary << "\n";
    out << "      limit: " << c.limit << "\n      rule: " << c.rule << "\n";
    for (const auto& e : c.evidence) out << "      - " << e << "\n";
  }
  std::vector<std::string> failing, not_run;
  for (const auto& c : r.checks) {
    if (c.status == AuditStatus::fail) failing.push_back(c.name);
    if (c.status == AuditStatus::not_run) not_run.push_back(c.name);
  }
  const std::size_t ran = r.checks.size() - not_run.size();
  out << "audit: " << (failed == 0 ? "PASSED" : "FAILED") << " (" << ran - failed << " of " << ran << " checks pass";
  if (!failing.empty()) out << "; failing: " << join(failing);
  if (!not_run.empty()) out << "; not run: " << join(not_run);
  out << ")\n";
  return out.str();
}

std::string audit_json_text(const AuditResult& r, const AuditRequest& request) {
  json j;
  j["schema"] = "geoanchor.audit/1";
  j["passed"] = r.passed();
  json arts = json::array();
  for (const auto& a : r.artifacts) {
    arts.push_back({{"path", a.path.string()},
                    {"kind", std::string(to_string(a.kind))},
                    {"sidecar", a.sidecar.empty() ? json(nullptr) : json(a.sidecar.string())},
                    {"readable", a.unreadable.empty()}});
  }
  j["artifacts"] = arts;
  j["ignored"] = r.ignored;
  const AuditLimits& l = request.limits;
  j["limits"] = {{"checkpoint_horizontal_m", l.checkpoint_horizontal_m}, {"checkpoint_vertical_m", l.checkpoint_vertical_m},
                 {"seam_m", l.seam_m},
                 {"min_rtk_fixed_percent", l.min_rtk_fixed_percent},
                 {"float32_spacing_m", l.float32_resolution_m},
                 {"tangent_departure_m", l.tangent_plane_m},
                 {"adjacency_gap_m", l.adjacency_gap_m}};
  json checks = json::array();
  for (const auto& c : r.checks) {
    checks.push_back({{"name", c.name},
                      {"status", std::string(to_string(c.status))},
                      {"summary", c.summary},
                      {"limit", c.limit},
                      {"rule", c.rule},
                      {"evidence", c.evidence}});
  }
  j["checks"] = checks;
  return j.dump(2);
}

}  // namespace geoanchor::workflow

namespace geoanchor::workflow {

MapReference map_reference(const std::vector<std::string>& inputs, const std::vector<std::string>& exclude) {
  AuditRequest request;
  request.inputs = inputs;
  request.exclude = exclude;
  Listing listing = list_artifacts(request);
  std::vector<AuditArtifact>& arts = listing.artifacts;
  for (auto& a : arts) read_artifact(a);
  // A tile whose sidecar is missing or broken is no part of the map's
  // reference that can be checked: refused by name, as audit fails it
  // (it was skipped without a word: issue 40 point 6).
  for (const auto& a : arts) {
    if (!a.unreadable.empty()) throw Error(ErrorKind::input, "E_MAP_REFERENCE", name_of(a) + ": " + a.unreadable);
    if (a.kind != AuditArtifactKind::transform && !a.meta) {
      throw Error(ErrorKind::input, "E_MAP_REFERENCE", name_of(a) + ": no sidecar (" + a.sidecar.string() + ") to read");
    }
  }
  if (std::none_of(arts.begin(), arts.end(), [](const AuditArtifact& a) { return a.kind != AuditArtifactKind::transform; })) {
    throw Error(ErrorKind::input, "E_MAP_EMPTY", join(inputs) + ": no tile or vector map to locate points in");
  }
  const AuditCheck same = check_one_frame(arts);
  if (same.status == AuditStatus::fail) {
    std::string why;
    for (const auto& e : same.evidence) why += (why.empty() ? "" : "; ") + e;
    throw Error(ErrorKind::input, "E_MAP_REFERENCE", "the map is not in one reference: " + why);
  }
  MapReference r;
  const io::MapMetadata* first = nullptr;
  for (const auto& a : arts) {
    r.artifacts.push_back(name_of(a));
    if (const io::MapMetadata* m = contract_of(a); m && m->frame && m->enu_origin && !first) first = m;
  }
  if (!first) {
    throw Error(ErrorKind::input, "E_MAP_REFERENCE",
                "no artifact of the map states its frame and ENU origin in the metadata contract (" + join(r.artifacts) +
                    "); apply it again, or give the origin in a survey-metadata file");
  }
  std::string frame_text = *first->frame;
  if (first->coordinate_epoch) frame_text += "@" + format_shortest(*first->coordinate_epoch);
  else if (first->coordinate_epoch_range) {
    throw Error(ErrorKind::input, "E_MAP_REFERENCE",
                "the map's coordinates carry per-point epochs (" + epoch_text(*first) + "): a map point has no one epoch to locate at");
  }
  r.frame = geodesy::Frame::parse(frame_text, "the map's metadata");
  geodesy::require_epoch_if_dynamic(r.frame, "the map's metadata (coordinate_epoch)");
  const std::optional<geodesy::LocalOrigin> o = map_origin(arts);
  r.origin = *o;
  if (const auto e = geodesy::implied_ellipsoid(r.frame)) r.origin.ellipsoid = *e;
  r.origin_source = first->enu_origin_source.value_or("unknown");
  // The transform: one move across the map's tiles and vector maps.
  std::vector<std::pair<const AuditArtifact*, Move>> moves;
  for (const auto& a : arts) {
    if (a.meta && a.kind != AuditArtifactKind::transform) moves.push_back({&a, move_of(a)});
  }
  const bool one_move = std::all_of(moves.begin(), moves.end(), [&](const auto& m) { return m.second == moves.front().second; });
  if (!moves.empty() && one_move && !moves.front().second.sha256.empty()) {
    Transforms transforms(arts);
    std::string why;
    const io::TransformFile* t = transforms.find(moves.front().second, *moves.front().first, why);
    if (!t) throw Error(ErrorKind::input, "E_MAP_REFERENCE", name_of(*moves.front().first) + ": " + why);
    r.transform = *t;
    r.transform_path = moves.front().second.path;
    r.transform_sha256 = moves.front().second.sha256;
    r.transform_inverse = moves.front().second.inverse;
    r.transform_epoch = moves.front().second.epoch;
  } else if (!one_move) {
    throw Error(ErrorKind::input, "E_MAP_REFERENCE",
                "the map's tiles were moved with different transforms: a map point's uncertainty depends on which tile it is "
                "in; locate one tile (its file or sidecar) at a time");
  }
  return r;
}

}  // namespace geoanchor::workflow
