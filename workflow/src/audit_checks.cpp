// The checks of a map's audit that read its artifacts' metadata and files:
// data, metadata, one frame, RTK share, float32 storage, tangent plane, Web
// Mercator (the seams and the checkpoints have files of their own).
#include "audit_checks.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

#include "audit_artifacts.hpp"
#include "audit_geometry.hpp"
#include "audit_text.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/hash.hpp"

namespace geoanchor::workflow::audit_detail {

using json = nlohmann::ordered_json;

namespace {

bool float32_storage(const AuditArtifact& a) {
  if (a.meta && a.meta->storage == "float32") return true;
  const io::MapMetadata* m = contract_of(a);
  return m && m->coordinate_storage && m->coordinate_storage->find("float32") != std::string::npos;
}

std::string kind_of(const AuditArtifact& a) {
  if (a.meta) return io::kind_name(*a.meta);
  return "";
}

}  // namespace

AuditCheck make_check(std::string name, std::string rule, std::string limit) {
  AuditCheck c;
  c.name = std::move(name);
  c.rule = std::move(rule);
  c.limit = std::move(limit);
  return c;
}

// ----------------------------------------------------------------- metadata

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

}  // namespace geoanchor::workflow::audit_detail
