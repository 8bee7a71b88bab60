// The seams check of a map's audit: each tile's footprint read from its
// points, and for each pair of tiles that meet, a ground point taken through
// both tiles' transforms and frames.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "audit_artifacts.hpp"
#include "audit_checks.hpp"
#include "audit_geometry.hpp"
#include "audit_text.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "tile_points.hpp"

namespace geoanchor::workflow::audit_detail {

namespace {

// A tile's footprint: its bounds' corners in the map's ENU.
struct Footprint {
  const AuditArtifact* tile = nullptr;
  Eigen::Vector3d lo, hi;  // ENU at the map's origin
  Move move;
};

// What the seams check counts as it goes.
struct SeamCounts {
  std::size_t not_checked = 0, moved_tiles = 0;
  std::size_t pairs = 0, failing = 0;
  double worst = 0.0;
};

// The plane the footprints are compared in: the map's ENU origin, else a
// tangent plane of their own.
std::optional<geodesy::LocalOrigin> seam_origin(const std::vector<AuditArtifact>& arts) {
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
  return origin;
}

// The footprint of a tile or vector map with a sidecar, or nothing with the
// reason in the check's evidence.
std::optional<Footprint> footprint_of(const AuditArtifact& a, const std::optional<geodesy::LocalOrigin>& origin, AuditCheck& c,
                                      SeamCounts& n) {
  if (a.meta->crs) {
    c.evidence.push_back(name_of(a) + ": not checked: its coordinates are in " + a.meta->crs->display_name() +
                         " (a PROJ CRS); audit checks seams between tiles in geoanchor's own coordinates");
    ++n.not_checked;
    return std::nullopt;
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
    ++n.not_checked;
    return std::nullopt;
  }
  const auto recorded = recorded_bounds(a);
  if (!recorded) {
    c.evidence.push_back(name_of(a) + ": not checked: its sidecar records no bounds (provenance.bounds)");
    ++n.not_checked;
    return std::nullopt;
  }
  if (!same_extent(a, points, *recorded)) {
    c.evidence.push_back(name_of(a) + ": FAIL its points span " + box_text(points) + " (file axes) but its sidecar records " +
                         box_text(*recorded) + ": the points changed after apply");
    ++n.moved_tiles;
  }
  const auto b = in_coordinate_order(a, points);
  if (!b) {
    c.evidence.push_back(name_of(a) + ": not checked: its axes' order is not stated");
    ++n.not_checked;
    return std::nullopt;
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
    ++n.not_checked;
    return std::nullopt;
  }
  return f;
}

// The largest separation over a pair's samples (the corners and the middle
// of where they meet, at their mean height): a point of tile A's ground
// taken back through A's transform and forward through B's.
struct Separation {
  double worst = -1.0;
  Eigen::Vector3d at, d;  // the sample (map ENU) and its separation (ENU)
};

// Nothing, with the error in the check's evidence, where a sample cannot be
// taken through the transforms.
std::optional<Separation> pair_separation(const Footprint& A, const Footprint& B, const io::TransformFile* ta,
                                          const io::TransformFile* tb, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                                          const geodesy::LocalOrigin& origin, const std::string& pair_name, AuditCheck& c) {
  const double z = 0.25 * (A.lo.z() + A.hi.z() + B.lo.z() + B.hi.z());
  std::vector<Eigen::Vector3d> samples{{lo.x(), lo.y(), z}, {hi.x(), lo.y(), z}, {lo.x(), hi.y(), z}, {hi.x(), hi.y(), z},
                                       {0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), z}};
  double pair_worst = -1.0;
  Eigen::Vector3d at = samples.back(), d_worst = Eigen::Vector3d::Zero();
  for (const auto& s : samples) {
    try {
      const Eigen::Vector3d p = geodesy::LocalTangentPlane(origin).ecef_from_enu(geodesy::EnuPosition{s, origin}).m;
      const geodesy::EcefPosition src =
          ta ? ta->apply(geodesy::EcefPosition(p), year(A.move.epoch), !A.move.inverse, "seam") : geodesy::EcefPosition(p);
      const geodesy::EcefPosition back = tb ? tb->apply(src, year(B.move.epoch), B.move.inverse, "seam") : src;
      const Eigen::Vector3d d = enu_difference(p, back.m);
      const double dist = d.norm();
      if (!std::isfinite(dist)) throw Error(ErrorKind::input, "E_SEAM", "not finite");
      if (dist > pair_worst) pair_worst = dist, at = s, d_worst = d;
    } catch (const Error& e) {
      c.evidence.push_back(pair_name + ": not checked: " + e.what());
      return std::nullopt;
    }
  }
  return Separation{pair_worst, at, d_worst};
}

// Two footprints: whether they meet (or overlap), and if so whether their
// moves put the same ground point at the same place.
void check_pair(const Footprint& A, const Footprint& B, const std::optional<geodesy::LocalOrigin>& origin, const AuditLimits& l,
                Transforms& transforms, AuditCheck& c, SeamCounts& n) {
  Eigen::Vector2d lo, hi;
  bool near = true;
  for (int k = 0; k < 2; ++k) {
    lo[k] = std::max(A.lo[k], B.lo[k]);
    hi[k] = std::min(A.hi[k], B.hi[k]);
    if (lo[k] > hi[k] + l.adjacency_gap_m) near = false;
    if (lo[k] > hi[k]) lo[k] = hi[k] = 0.5 * (lo[k] + hi[k]);  // a gap: its middle
  }
  if (!near) return;
  ++n.pairs;
  const std::string pair_name = name_of(*A.tile) + " | " + name_of(*B.tile);
  if (A.move == B.move) return;  // the same transform, frames and epoch: no seam by construction
  std::string why_a, why_b;
  const io::TransformFile* ta = transforms.find(A.move, *A.tile, why_a);
  const io::TransformFile* tb = transforms.find(B.move, *B.tile, why_b);
  if ((!A.move.sha256.empty() && !ta) || (!B.move.sha256.empty() && !tb)) {
    c.evidence.push_back(pair_name + ": not checked: " + name_of(!ta && !A.move.sha256.empty() ? *A.tile : *B.tile) + ": " +
                         (!ta && !A.move.sha256.empty() ? why_a : why_b));
    ++n.failing;
    return;
  }
  const auto source_of = [](const Move& m, const io::TransformFile* t) {
    if (!t) return m.output_frame.empty() ? std::string("?") : m.output_frame;
    const auto& f = m.inverse ? t->target_frame : t->source_frame;
    return f ? f->to_string() : std::string("?");
  };
  if (A.move.input_crs != B.move.input_crs) {
    c.evidence.push_back(pair_name + ": not checked: the two were read from different coordinate systems through PROJ, "
                                     "whose operations audit cannot run again");
    ++n.failing;
    return;
  }
  if ((!ta && A.move.input_frame != A.move.output_frame) || (!tb && B.move.input_frame != B.move.output_frame) ||
      source_of(A.move, ta) != source_of(B.move, tb)) {
    c.evidence.push_back(pair_name + ": not checked: the tiles come from different frames (" + source_of(A.move, ta) +
                         ", " + source_of(B.move, tb) + ") or were moved between frames without a transform file");
    ++n.failing;
    return;
  }
  const std::optional<Separation> s = pair_separation(A, B, ta, tb, lo, hi, *origin, pair_name, c);
  if (!s) {
    ++n.failing;
    return;
  }
  const double pair_worst = s->worst;
  const Eigen::Vector3d &at = s->at, &d_worst = s->d;
  n.worst = std::max(n.worst, pair_worst);
  if (!(pair_worst <= l.seam_m)) {
    ++n.failing;
    c.evidence.push_back(pair_name + ": " + cm(pair_worst) + " apart (east " + cm(d_worst.x()) + ", north " +
                         cm(d_worst.y()) + ", up " + cm(d_worst.z()) + ") at map ENU " + fixed(at.x(), 1) + ", " +
                         fixed(at.y(), 1) + " m");
  } else {
    c.evidence.push_back(pair_name + ": " + mm(pair_worst) + " apart (moved differently)");
  }
}

}  // namespace

// ---------------------------------------------------------------- seams

AuditCheck check_seams(const std::vector<AuditArtifact>& arts, const AuditLimits& l, Transforms& transforms) {
  AuditCheck c = make_check("seams",
                            "no seams: where two tiles meet, the same ground point must come out of both tiles' "
                            "transforms and frames at the same place",
                            "3-D separation ≤ " + cm(l.seam_m) + " (--max-seam-m); tiles closer than " +
                                fixed(l.adjacency_gap_m, 1) + " m share a boundary");
  std::vector<Footprint> tiles;
  const std::optional<geodesy::LocalOrigin> origin = seam_origin(arts);
  SeamCounts n;
  for (const auto& a : arts) {
    // Tiles and vector maps: a layer moved otherwise than the tiles under it tears from them.
    if (a.kind == AuditArtifactKind::transform) continue;
    if (!a.meta) continue;  // the metadata check names it
    if (const std::optional<Footprint> f = footprint_of(a, origin, c, n)) tiles.push_back(*f);
  }
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    for (std::size_t j = i + 1; j < tiles.size(); ++j) check_pair(tiles[i], tiles[j], origin, l, transforms, c, n);
  }
  const std::size_t not_checked = n.not_checked, moved_tiles = n.moved_tiles, pairs = n.pairs, failing = n.failing;
  const double worst = n.worst;
  c.status = failing == 0 && not_checked == 0 && moved_tiles == 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = std::to_string(pairs) + " shared boundaries or overlaps among " + std::to_string(tiles.size()) +
              " tiles and vector maps (their extents read from their points); " +
              (failing ? std::to_string(failing) + " fail" : "largest separation " + mm(worst)) +
              (moved_tiles ? "; " + std::to_string(moved_tiles) + " tiles' points differ from their sidecars' bounds" : "") +
              (not_checked ? "; " + std::to_string(not_checked) + " tiles not checked" : "");
  return c;
}

}  // namespace geoanchor::workflow::audit_detail
